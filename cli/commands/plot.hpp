#pragma once
// `arbiter plot TRACE.jsonl -o timeline.svg`: a trace as a picture, no browser needed.

#include <string>

#include "commands/view.hpp"

namespace arbiter::cli {

struct PlotOptions {
  bool actuators = false;  ///< add a row per actuator (its value over the steps)
  /// `--compare`: a second run (B), whose row of each behaviour, state machine and actuator is
  /// drawn under the first's (A), with the steps where they differ shaded. Steps are aligned by
  /// position. The subtitle names A and B.
  const TraceFile* compare = nullptr;
  std::string name_a;
  std::string name_b;
};

/// An SVG timeline of `trace`: per layer, a row per behaviour (in execution order) with its
/// activation as a filled area, its requested level as a line and a bar where it is active, and
/// ticks where it became active or inactive; a row per state machine with its state changes; with
/// `options.actuators`, a row per actuator. Each row is a `<g class="row ...">`.
std::string plot_svg(const TraceFile& trace, const PlotOptions& options);

}  // namespace arbiter::cli

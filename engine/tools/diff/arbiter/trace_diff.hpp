#pragma once
// engine/tools/diff: two runs read by tools/read in; where and how often they differ out, step by
// step (`arbiter diff`, replay's determinism check).
//
// Two runs compared step by step (`arbiter diff`, and replay's determinism check): which
// behaviours, actuators and state machines differ, where first and how often.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "arbiter/trace_reader.hpp"

namespace arbiter {

struct TraceDiff {
  /// In how many steps something differs, and the first and last of them.
  struct Count {
    std::uint64_t differ = 0;
    std::uint64_t first = 0;
    std::uint64_t last = 0;
  };
  struct Divergence {
    std::uint64_t step = 0;
    /// "layer/behaviour", "actuator:NAME", "machine:NAME"; empty when one run only has more
    /// steps. In an exact comparison where none of those differs, the path of the first field
    /// that does: "layers.control.kick_ball.inhibited_by".
    std::vector<std::string> what;
  };
  bool identical = true;
  std::uint64_t steps_a = 0;
  std::uint64_t steps_b = 0;
  std::optional<Divergence> first_divergence;
  std::map<std::string, Count> behaviours;  ///< by "layer/name": `active` or `activation`
  std::map<std::string, Count> actuators;   ///< value or written flag
  std::map<std::string, Count> machines;    ///< state or events
};

/// The comparison of two runs fed one step at a time, for a caller that has one of the runs only
/// step by step (a scenario test comparing the run it steps with a recording). diff_traces()
/// feeds it whole traces.
class TraceDiffer {
 public:
  /// As diff_traces().
  explicit TraceDiffer(double tolerance = 1e-9, bool exact = false);
  /// Compares the records (step records, as the trace writer writes them) of a step both runs
  /// have.
  void compare(std::uint64_t step, const std::string& a, const std::string& b);
  /// What differed in the step compare() compared last, named as Divergence::what names it;
  /// empty when nothing did. A view marks each step's differences with it.
  const std::vector<std::string>& differed() const { return differed_; }
  /// A step that one run has and the other lacks.
  void unmatched(std::uint64_t step);
  /// The result, given how many steps each run has and, when those differ and nothing else
  /// did, the first step only the longer run has.
  TraceDiff finish(std::uint64_t steps_a, std::uint64_t steps_b, std::uint64_t first_extra);

 private:
  double tolerance_;
  bool exact_;
  TraceDiff diff_;
  std::vector<std::string> differed_;
};

/// Aligns by step number the steps of a run `a`, read from its source as far as they are needed,
/// with those of a run `b` given one at a time, in order: a step only one run has is unmatched.
/// `arbiter diff` and replay's determinism check (which has `b` only as it steps) align so.
class StepAligner {
 public:
  /// Both must outlive the aligner.
  StepAligner(TraceSource& a, TraceDiffer& differ) : a_(a), differ_(differ) {}
  /// Reads `a` up to its first step; false when it cannot be read (a.error()).
  bool start();
  /// Compares `b`'s record of `step` with `a`'s, if it has that step.
  void compare(std::uint64_t step, const std::string& b);
  /// The result, counting the steps of `a` up to `last` that `b` did not reach.
  TraceDiff finish(std::uint64_t last = ~std::uint64_t{0});
  /// Reads the rest of `a`, for what its end holds.
  void drain();

 private:
  bool next();
  TraceSource& a_;
  TraceDiffer& differ_;
  TraceRecord record_;
  bool more_ = false;
  std::uint64_t steps_a_ = 0;
  std::uint64_t steps_b_ = 0;
};

/// Aligns the steps of `a` and `b` by number. Numbers differing by at most `tolerance` are
/// equal; "t" and "duration" (timing, not behaviour) are never compared. With `exact`, a step
/// also differs when anything else in its record does (e.g. requested levels, queues).
TraceDiff diff_traces(const Trace& a, const Trace& b, double tolerance = 1e-9, bool exact = false);
/// The same, reading both runs to their ends a step at a time, never whole; nullopt with `error`
/// when either is not readable (then neither's warnings are read).
std::optional<TraceDiff> diff_traces(TraceSource& a, TraceSource& b, Diagnostic& error,
                                     double tolerance = 1e-9, bool exact = false);

/// `{"identical": ..., "steps": [na, nb], "first_divergence": ..., "behaviours": ...}`.
std::string format_json(const TraceDiff& diff);
/// The same for people, naming the runs `a` and `b`.
std::string format_text(const TraceDiff& diff, const std::string& a, const std::string& b);

}  // namespace arbiter

#pragma once
// engine/tools/explain: a Program and a run's trace in; why a behaviour had its activation at a
// step out, in words (`arbiter explain`, the views' explain panel); also an actuator or a state.
//
// Why a behaviour had its activation level at one step of a run, told from the compiled program
// (the closed inhibitor lists, the chains behind implicit inhibitions) and the run's trace
// (docs/semantics.md, "The trace"). Also what a state machine did in that step.

#include <cstdint>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/program.hpp"
#include "arbiter/trace_reader.hpp"

namespace arbiter {

struct Explanation {
  enum class Status {
    kOk,
    kNotFound,  ///< no such behaviour, state machine, state, actuator or step: the request is wrong
    kBadTrace,  ///< the trace is malformed, or was written for another config
  };
  Status status = Status::kOk;
  std::string text;         ///< the explanation, or what went wrong (one line)
  std::vector<Note> notes;  ///< with an error: suggestions
  /// kBadTrace because a record could not be read: where it is (the trace reader's location).
  std::optional<SourceLocation> where;
};

/// What a name as explain() takes it names in a program.
struct ExplainTarget {
  enum class Kind { kBehaviour, kController, kActuator, kState };
  Kind kind = Kind::kBehaviour;
  std::uint32_t index = 0;  ///< a behaviour, controller or actuator
  std::uint32_t state = 0;  ///< kState: the state of controller `index`
};

/// The behaviour, state machine, actuator or state `name` names, as explain() resolves it; else
/// nothing, with `error` (kNotFound) saying why: no such name (with a did-you-mean note), or
/// ambiguous (with the names to write instead).
std::optional<ExplainTarget> resolve_target(const Program& program, std::string_view name,
                                            Explanation& error);
/// The name that names `target` alone (`control/kick_ball`, `actuators/kick`, `goalie/dive`).
std::string target_name(const Program& program, const ExplainTarget& target);

/// Explains `target` at step `step` (counting from 1) of `trace`, a trace written by running
/// `program`'s config.
///
/// `target` names a behaviour (`name`, or `layer/name` when several layers have one of that
/// name): the explanation gives its requested level, each inhibitor after closure with its
/// refined level and factor (1 - a), the chain of chaining inhibitions behind an implicit one,
/// the product, and the normalisation when the layer normalises. Or it names a state machine
/// (`name`, or `state_machines/name`): which state ran, what was queued before and after, the
/// events and what they mean. Levels are recomputed from the trace's requested levels and checked
/// against its recorded activations. Or it names an actuator (`name`, or `actuators/name`): its
/// value, and either its writers with their activations and weights (aggregated) or the winning
/// writer, or, when nobody wrote it, the step whose value it holds. Or it names a state
/// (`machine/state`): whether it ran, was queued or neither at the step, when its run started and
/// why (the end of the state before), where it was planned, and when and why it ended.
Explanation explain(const Program& program, TraceSource& trace, std::uint64_t step,
                    std::string_view target);
/// explain() of the JSON-lines trace in `trace`, named "trace" in errors.
Explanation explain(const Program& program, std::istream& trace, std::uint64_t step,
                    std::string_view target);

/// Whether `header_line` (a trace's first line) was written by running `program`'s config,
/// checked as explain() checks it: kOk, or kBadTrace saying what differs.
Explanation check_trace_header(const Program& program, const std::string& header_line);

}  // namespace arbiter

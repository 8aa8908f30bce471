#pragma once
// engine/tools/breakpoint: a condition's text in (`kick_ball activates`); the steps of a run, live
// or recorded, at which it holds out (docs/cli.md, "Breakpoints").
//
// A condition is parsed once and its names resolved against the program, as explain resolves
// them, when the breakpoint is set; a live run then evaluates it after every step by index (the
// Manager's StepCheck), and a recording's steps are searched for it by name.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/explain.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/trace_reader.hpp"

namespace arbiter {

/// A breakpoint's condition as written, parsed (docs/cli.md, "Breakpoints").
struct Condition {
  enum class Kind {
    kActivates,    ///< `NAME activates`: the behaviour's activation goes from 0 to > 0
    kDeactivates,  ///< `NAME deactivates`: and back
    kStarts,       ///< `machine/state starts`: the state is activated
    kEnds,         ///< `machine/state ends`: the state is deactivated
    kAbove,        ///< `NAME[i] > X`: the value crosses above X (not above it the step before)
    kBelow,        ///< `NAME[i] < X`: the value crosses below X
    kEvent,        ///< `event ~ "TEXT"`: a reported event's text contains TEXT
    kStep,         ///< `step N`
    kStepFrom,     ///< `step >= N`: every step from N on
  };
  Kind kind = Kind::kStep;
  std::string text;     ///< as written, blanks at its ends trimmed: how the break is named
  std::string name;     ///< the behaviour, state or actuator, as written
  int name_column = 0;  ///< where `name` starts in `text`, from 1
  std::optional<std::size_t> component;  ///< kAbove, kBelow: `[i]`
  int component_column = 0;
  double bound = 0.0;
  std::string pattern;     ///< kEvent
  std::uint64_t step = 0;  ///< kStep, kStepFrom
};

/// Why a condition cannot be set: where in its text (from 1, with the length to underline), what
/// is wrong and what would do.
struct ConditionError {
  int column = 1;
  int length = 0;
  std::string code;  ///< bad-condition, unknown-name
  std::string message;
  std::vector<Note> notes;
};

/// `text` parsed; nothing, with `error` set, when it is no condition.
std::optional<Condition> parse_condition(std::string_view text, ConditionError& error);

/// The error as a diagnostic located in the argument of `option` (`--break`), line 1, to print
/// with format(diagnostic, text, options).
Diagnostic condition_diagnostic(const ConditionError& error, std::string_view option);

/// A condition with its names resolved against a program.
struct Breakpoint {
  Condition condition;
  ExplainTarget target;
  /// How an actuator's value is read: a number, or the component of a vector.
  enum class Value { kNone, kBool, kInt, kDouble, kVec2, kVec3 };
  Value value = Value::kNone;
  /// By name, for the records of a recording: the behaviour's layer and name, the state's machine
  /// and name, the actuator's name.
  std::string scope;
  std::string name;
  /// Whether the condition held at the step before (a crossing needs it).
  bool was = false;
  /// False once a reload dropped what it names.
  bool enabled = true;
};

/// `condition` with its names resolved against `program`; nothing, with `error` set (the column
/// of the name), when a name names nothing of the kind the condition needs.
std::optional<Breakpoint> resolve_breakpoint(const Program& program, Condition condition,
                                             ConditionError& error);

/// parse_condition() and resolve_breakpoint() of `text`, the argument of `option` (`--break`):
/// nothing when it cannot be set, with `error` holding the diagnostic as format() prints it, the
/// argument shown as its source line.
std::optional<Breakpoint> make_breakpoint(const Program& program, std::string_view text,
                                          std::string_view option, const FormatOptions& format,
                                          std::string& error);

/// The breakpoints of a live run: the manager's StepCheck (by index, allocation-free), and an
/// observer that resolves them again when a hot reload swaps a new program in. Add it as an
/// observer too, and keep it alive while the manager runs: the break's text is its own.
class Breakpoints : public StepCheck, public Observer {
 public:
  /// Between two steps only: the manager may hold the text of the last step's break.
  void add(Breakpoint breakpoint) { items_.push_back(std::move(breakpoint)); }
  /// Removes the breakpoint of this condition text; false when none has it.
  bool remove(std::string_view text);
  const std::vector<Breakpoint>& items() const { return items_; }
  bool empty() const { return items_.empty(); }
  /// The first breakpoint that fires at the manager's last step (every one's state is kept).
  const char* check(const Manager& manager) override;
  void on_step(const Manager& /*manager*/) override {}
  /// A breakpoint whose names the new program lacks is disabled.
  void on_reload(const Manager& manager) override;

 private:
  std::vector<Breakpoint> items_;
};

/// A step found by seek().
struct SeekHit {
  std::uint64_t step = 0;
  std::size_t breakpoint = 0;  ///< which of the breakpoints fired (the first that did)
};

/// The first step after step `after` of `trace` at which one of `breakpoints` fires, read from
/// the trace's start (a crossing needs the steps before). Nothing when none does, or when the
/// trace is bad (then `error` is set).
std::optional<SeekHit> seek(TraceSource& trace, std::vector<Breakpoint>& breakpoints,
                            std::uint64_t after, std::optional<Diagnostic>& error);

}  // namespace arbiter

#pragma once
// engine/core/record: a Manager's steps in (as its observer); a JSON-lines trace or an MCAP
// recording out (recording.hpp), which tools/read reads back.
//
// Stage 5 of the data path: the JSON-lines trace of docs/semantics.md, "The trace", written by an
// observer.

#include <memory>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "arbiter/manager.hpp"

namespace arbiter {

/// append_step_record() for an observer that formats every step: what the record needs of the
/// program (names, closed inhibitions) is gathered once, and again after reset() (at a reload),
/// not at every call.
class StepRecordFormatter {
 public:
  StepRecordFormatter();
  ~StepRecordFormatter();
  StepRecordFormatter(const StepRecordFormatter&) = delete;
  StepRecordFormatter& operator=(const StepRecordFormatter&) = delete;
  /// For `program` from now on (call it from Observer::on_start and on_reload).
  void reset(const Program& program);
  /// The record of the manager's last step; gathers the program's on first use.
  void append(const Manager& manager, std::string& out);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Writes the header when attached and one line per step. The stream must outlive the writer.
class TraceWriter : public Observer {
 public:
  explicit TraceWriter(std::ostream& out) : out_(out) {}
  void on_start(const Manager& manager) override;
  void on_step(const Manager& manager) override;
  /// Writes a new header record (reload_header()): the step records after it follow it.
  void on_reload(const Manager& manager) override;
  void on_finish(const Manager& manager) override;
  /// Writes the safe-value pass as a record with `"safe": true` and the last step's number.
  void on_safe(const Manager& manager) override;

 private:
  std::ostream& out_;
  StepRecordFormatter records_;
  std::string line_;  // reused between steps
};

/// The header line `{"arbiter_trace": 1, ...}` without the newline.
std::string trace_header(const Program& program);
/// The header of a program swapped in by a hot reload: trace_header() with `"reload": N` (the
/// manager's reloads()) and `"after_step": S` (the last step of the program it replaced) after
/// the version, so that a reader can tell it from the first header and re-key what it keeps
/// by index. Without the newline.
std::string reload_header(const Manager& manager);
/// The same from the program's trace_header(), the reload's number and the step before it.
std::string reload_header(std::string trace_header, std::uint64_t reload, std::uint64_t after_step);
/// "activate walk_to_pose", as in the trace.
std::string event_text(const Controller& controller, const Controller::Event& event);

/// A deactivation's cause as the trace's `ended` entries name it: "proceeded", "queue_empty",
/// "preempted", "go_to", "terminated", "error", "restarted", "reloaded" ("" for kNone).
const char* cause_name(Controller::EndCause cause);

/// Why a state ended, as the trace tells it (docs/semantics.md, "The trace").
struct StateEnd {
  std::string state;
  std::string cause;  ///< cause_name()
  std::string to;     ///< preempted, go_to: the state planned in its place ("": none)
  std::string by;     ///< terminated: the state that called terminate() ("": the owner's hook)
  /// preempted: by the config's `preempt:` entry of this index (from 0); -1: by a hook
  std::int64_t preempt = -1;
  bool proceeded = false;  ///< preempted after it had asked to proceed
};
/// The state end of a deactivation event.
StateEnd state_end(const Controller& controller, const Controller::Event& event);
/// What `run` and `explain` say about it: "pre-empted by dive", "proceeded", "go_to c".
std::string end_text(const StateEnd& end, std::uint64_t cycle);

/// Per-instance params (the queue entry's, then those of Plan calls), each with its value as
/// JSON text, in the order they were given: `[("x", "0.0"), ("y", "-4.2")]`.
using ParamTexts = std::vector<std::pair<std::string, std::string>>;
/// Of the instance an activation or deactivation event is about. Not `exact`: numbers to 4
/// significant digits (short_number()), as `run` shows them.
ParamTexts event_params(const Controller& controller, const Controller::Event& event,
                        bool exact = true);
/// Of the controller's current instance, exact.
ParamTexts current_params(const Controller& controller);
/// A param's number for a person: 4 significant digits, as JSON (`-4.07`, `0.0`).
std::string short_number(double value);
/// A param's value as JSON text, exact (`0.25`, `[1.0, 2.0]`, `"fast"`).
std::string param_value_text(const ParamValue& value);
/// `{x: 0.0, y: -4.2}`, as `run` and `explain` show them; "" when there are none.
std::string params_text(const ParamTexts& params);
/// The record of the manager's last step, without the newline: with `"safe": true` during the
/// safe-value pass, and `"t"` and `"duration"` (seconds) when the manager has a clock.
void append_step_record(const Manager& manager, std::string& out);

}  // namespace arbiter

#pragma once
// Stage 5 of the data path: the JSON-lines trace of docs/semantics.md, "The trace", written by an
// observer.

#include <ostream>
#include <string>

#include "arbiter/manager.hpp"

namespace arbiter {

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
  std::string line_;  // reused between steps
};

/// The header line `{"arbiter_trace": 1, ...}` without the newline.
std::string trace_header(const Program& program);
/// The header of a program swapped in by a hot reload: trace_header() with `"reload": N` (the
/// manager's reloads()) and `"after_step": S` (the last step of the program it replaced) after
/// the version, so that a reader can tell it from the first header and re-key what it keeps
/// by index. Without the newline.
std::string reload_header(const Manager& manager);
/// "activate walk_to_pose", as in the trace.
std::string event_text(const Controller& controller, const Controller::Event& event);
/// The record of the manager's last step, without the newline: with `"safe": true` during the
/// safe-value pass, and `"t"` and `"duration"` (seconds) when the manager has a clock.
void append_step_record(const Manager& manager, std::string& out);

}  // namespace arbiter

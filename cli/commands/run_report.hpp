#pragma once
// What `arbiter run` tells a person: a line per change of activity, then a summary.

#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "arbiter/manager.hpp"

namespace arbiter::cli {

class RunReport : public Observer {
 public:
  RunReport(std::ostream& out, bool quiet) : out_(out), quiet_(quiet) {}
  void on_start(const Manager& manager) override;
  void on_step(const Manager& manager) override;
  /// Re-keys what it counts per behaviour and controller by name: indices change.
  void on_reload(const Manager& manager) override;
  void on_finish(const Manager& manager) override;
  /// A line naming the safe values output; not again for a pass one single step after the last
  /// with the same values (stepping a paused run from the live view passes after each step).
  void on_safe(const Manager& manager) override;

 private:
  /// The state machines' transitions, with why each state ended, and what behaviour and
  /// interface code reported, in the order they happened in the step.
  void report_story(const Manager& manager);
  /// Writes a line of the report, after the repeats of the last event line, if any.
  void print(const std::string& line);
  /// An event line: printed unless it repeats the event line just before, whose repeats are
  /// then counted and told in one line (`world: ball kicked again (x200, steps 361-559)`).
  void print_event(std::uint64_t step, const std::string& event);
  void flush_repeats();
  void key_by_index(const Program& program);
  std::ostream& out_;
  bool quiet_;
  std::vector<char> was_active_;
  std::vector<std::uint64_t> active_steps_;
  std::vector<ControllerStatus> controller_status_;
  std::vector<std::string> keys_;                       ///< "layer/name" per behaviour index
  std::map<std::string, std::uint64_t> removed_steps_;  ///< active steps of removed behaviours
  std::map<std::string, std::uint64_t> event_counts_;   ///< "source: text" → how often
  std::string last_event_;  ///< the event of the last line printed, if that was an event line
  std::uint64_t repeats_ = 0;
  std::uint64_t first_repeat_ = 0;
  std::uint64_t last_repeat_ = 0;
  std::string last_safe_;             ///< the values of the last safe pass
  std::uint64_t last_safe_step_ = 0;  ///< the step it followed
};

}  // namespace arbiter::cli

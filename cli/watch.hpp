#pragma once
// `arbiter run --watch`: reloads the config whenever it or a file it includes changes, while the
// run goes on (docs/hot_reload.md).

#include <atomic>
#include <optional>
#include <ostream>
#include <string>
#include <thread>

#include "arbiter/reload.hpp"

namespace arbiter::cli {

/// The first load of a watched config: diagnostics go to `err` as `arbiter run` prints them.
std::optional<Program> load_watched(Reloader& reloader, const std::string& path, std::ostream& err,
                                    const FormatOptions& format_options = {});

/// Polls the modification time and size of the config and of every file it includes, from a
/// thread of its own, and reloads through `reloader` when one changes. A valid edit prints its
/// diff to `out`; a broken one prints its diagnostics (`file:line:col: error[code]: ...`) to `err`
/// and the running program goes on; a file caught mid-write is reported and retried at its
/// next change; `quiet` leaves out the diffs (errors are still printed). The manager's stepping
/// thread never waits for it.
class Watcher {
 public:
  static constexpr int kPollMilliseconds = 200;

  Watcher(Reloader& reloader, Manager& manager, std::ostream& out, std::ostream& err,
          bool quiet = false, const FormatOptions& format_options = {});
  /// Stops polling (waits for a reload in progress).
  ~Watcher();
  Watcher(const Watcher&) = delete;
  Watcher& operator=(const Watcher&) = delete;

 private:
  void run();
  std::string fingerprint() const;

  Reloader& reloader_;
  Manager& manager_;
  std::ostream& out_;
  std::ostream& err_;
  bool quiet_;
  FormatOptions format_options_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace arbiter::cli

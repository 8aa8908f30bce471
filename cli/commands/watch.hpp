#pragma once
// `arbiter run --watch`: reloads the config whenever it or a file it includes changes, while the
// run goes on (docs/hot_reload.md).

#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <ostream>
#include <streambuf>
#include <string>
#include <thread>

#include "arbiter/reload.hpp"

namespace arbiter::cli {

/// The first load of a watched config: diagnostics go to `err` as `arbiter run` prints them.
std::optional<Program> load_watched(Reloader& reloader, const std::string& path, std::ostream& err,
                                    const FormatOptions& format_options = {});

/// The status line of a watched run: `watching configs/x.yaml — step 1234, last reload at step
/// 800` (`no reload yet` before the first).
std::string status_text(const std::string& path, std::uint64_t step,
                        std::optional<std::uint64_t> last_reload);

/// The one line, on a terminal, that shows an idle watched run is alive: drawn on `fd` and
/// rewritten in place (`\r`, erase line); any other line written through a StatusClearer first
/// takes it away, and the next draw() puts it back under that line.
class StatusLine {
 public:
  explicit StatusLine(int fd) : fd_(fd) {}
  ~StatusLine() { clear(); }
  StatusLine(const StatusLine&) = delete;
  StatusLine& operator=(const StatusLine&) = delete;

  /// Replaces the line with `text`, unless a stream is in the middle of a line of its own.
  void draw(const std::string& text);
  /// Takes the line away, if it is shown.
  void clear();

 private:
  friend class StatusClearer;
  void clear_locked();
  int fd_;
  std::mutex mutex_;
  bool shown_ = false;
  int open_lines_ = 0;  // streams that have written part of a line
};

/// Sits between a stream and its buffer (std::cout's, std::cerr's) while a status line is shown:
/// each write first clears the status line and is passed on at once, so that lines and the
/// status line never mix.
class StatusClearer : public std::streambuf {
 public:
  StatusClearer(std::ostream& stream, StatusLine& status);
  /// Gives the stream its own buffer back.
  ~StatusClearer() override;
  StatusClearer(const StatusClearer&) = delete;
  StatusClearer& operator=(const StatusClearer&) = delete;

 protected:
  int overflow(int c) override;
  std::streamsize xsputn(const char* text, std::streamsize count) override;
  int sync() override;

 private:
  std::ostream& stream_;
  std::streambuf* target_;
  StatusLine& status_;
  bool open_line_ = false;
};

/// Polls the modification time and size of the config and of every file it includes, from a
/// thread of its own, and reloads through `reloader` when one changes. A valid edit prints its
/// diff to `out`; a broken one prints its diagnostics (`file:line:col: error[code]: ...`) to `err`
/// and the running program goes on; a file caught mid-write is reported and retried at its
/// next change; `quiet` leaves out the diffs (errors are still printed). The manager's stepping
/// thread never waits for it.
class Watcher {
 public:
  static constexpr int kPollMilliseconds = 200;

  /// With `status`, the watcher keeps a status line up to date there (a terminal).
  Watcher(Reloader& reloader, Manager& manager, std::ostream& out, std::ostream& err,
          bool quiet = false, const FormatOptions& format_options = {},
          StatusLine* status = nullptr);
  /// Stops polling (waits for a reload in progress).
  ~Watcher();
  Watcher(const Watcher&) = delete;
  Watcher& operator=(const Watcher&) = delete;

  /// The step the run has reached, from the stepping thread (an atomic store; no wait).
  void set_step(std::uint64_t step) { step_.store(step, std::memory_order_relaxed); }

 private:
  void run();
  std::string fingerprint() const;

  Reloader& reloader_;
  Manager& manager_;
  std::ostream& out_;
  std::ostream& err_;
  bool quiet_;
  FormatOptions format_options_;
  StatusLine* status_;
  std::atomic<std::uint64_t> step_{0};
  std::optional<std::uint64_t> last_reload_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace arbiter::cli

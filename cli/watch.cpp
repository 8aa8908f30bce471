#include "watch.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <chrono>

namespace arbiter::cli {

std::optional<Program> load_watched(Reloader& reloader, const std::string& path, std::ostream& err,
                                    const FormatOptions& format_options) {
  Diagnostics diagnostics;
  auto program = reloader.load(path, diagnostics);
  if (!diagnostics.empty()) err << format(diagnostics, format_options);
  return program;
}

Watcher::Watcher(Reloader& reloader, Manager& manager, std::ostream& out, std::ostream& err,
                 bool quiet, const FormatOptions& format_options)
    : reloader_(reloader),
      manager_(manager),
      out_(out),
      err_(err),
      quiet_(quiet),
      format_options_(format_options) {
  thread_ = std::thread([this] { run(); });
}

Watcher::~Watcher() {
  stop_ = true;
  thread_.join();
}

// Modification time (to the nanosecond) and size of each watched file; a missing file counts
// as a state of its own, so that its return is a change too.
std::string Watcher::fingerprint() const {
  std::string out;
  for (const auto& file : reloader_.files()) {
    struct stat info {};
    if (::stat(file.c_str(), &info) != 0) {
      out += "missing;";
      continue;
    }
    out += fmt::format("{}.{}:{};", static_cast<long long>(info.st_mtim.tv_sec),
                       static_cast<long long>(info.st_mtim.tv_nsec),
                       static_cast<long long>(info.st_size));
  }
  return out;
}

void Watcher::run() {
  std::string seen = fingerprint();
  while (!stop_) {
    std::this_thread::sleep_for(std::chrono::milliseconds(kPollMilliseconds));
    const std::string now = fingerprint();
    if (now == seen) continue;
    seen = now;
    const ReloadResult result = reloader_.reload(manager_);
    // The files a reload reads may differ (an include added or removed).
    seen = fingerprint();
    // Each report goes out in one piece: the run's own lines come from the stepping thread.
    if (!result.staged) {
      err_ << format(result.diagnostics, format_options_)
           << fmt::format(
                  "reload of {} rejected: {} error(s); still running the previous "
                  "config\n",
                  reloader_.path(), result.diagnostics.error_count());
      continue;
    }
    if (!result.diagnostics.empty()) err_ << format(result.diagnostics, format_options_);
    if (quiet_) continue;
    std::string text =
        fmt::format("reload of {}: {} change{}, swapped in at the next step\n", reloader_.path(),
                    result.diff.changes.size(), result.diff.changes.size() == 1 ? "" : "s");
    text += format(result.diff, "  ");
    if (!result.restarted.empty()) {
      text += "  restarted (declaration or handles changed):";
      for (const auto& name : result.restarted) text += " " + name;
      text += "\n";
    }
    out_ << text << std::flush;
  }
}

}  // namespace arbiter::cli

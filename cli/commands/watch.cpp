#include "commands/watch.hpp"

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>

namespace arbiter::cli {

std::optional<Program> load_watched(Reloader& reloader, const std::string& path, std::ostream& err,
                                    const FormatOptions& format_options) {
  Diagnostics diagnostics;
  auto program = reloader.load(path, diagnostics);
  if (!diagnostics.empty()) err << format(diagnostics, format_options);
  return program;
}

std::string status_text(const std::string& path, std::uint64_t step,
                        std::optional<std::uint64_t> last_reload) {
  return fmt::format("watching {} — step {}, {}", path, step,
                     last_reload ? fmt::format("last reload at step {}", *last_reload)
                                 : std::string("no reload yet"));
}

namespace {

// Best effort: a terminal that takes less is not worth stopping the run for.
void write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const auto written = ::write(fd, text.data() + done, text.size() - done);
    if (written <= 0) return;
    done += static_cast<std::size_t>(written);
  }
}

// Carriage return, then erase the line.
constexpr const char* kEraseLine = "\r\x1b[K";

}  // namespace

void StatusLine::draw(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (open_lines_ > 0) return;
  write_all(fd_, kEraseLine + text);
  shown_ = true;
}

void StatusLine::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  clear_locked();
}

void StatusLine::clear_locked() {
  if (!shown_) return;
  write_all(fd_, kEraseLine);
  shown_ = false;
}

StatusClearer::StatusClearer(std::ostream& stream, StatusLine& status)
    : stream_(stream), target_(stream.rdbuf()), status_(status) {
  stream_.flush();
  stream_.rdbuf(this);
}

StatusClearer::~StatusClearer() {
  stream_.rdbuf(target_);
  std::lock_guard<std::mutex> lock(status_.mutex_);
  if (open_line_) --status_.open_lines_;
}

int StatusClearer::overflow(int c) {
  if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
  const char text = traits_type::to_char_type(c);
  return xsputn(&text, 1) == 1 ? c : traits_type::eof();
}

std::streamsize StatusClearer::xsputn(const char* text, std::streamsize count) {
  if (count <= 0) return 0;
  std::lock_guard<std::mutex> lock(status_.mutex_);
  status_.clear_locked();
  const std::streamsize written = target_->sputn(text, count);
  // Passed on now: the status line is drawn on another stream, and must come after this.
  target_->pubsync();
  const bool open = text[count - 1] != '\n';
  if (open != open_line_) status_.open_lines_ += open ? 1 : -1;
  open_line_ = open;
  return written;
}

int StatusClearer::sync() {
  return target_->pubsync();
}

Watcher::Watcher(Reloader& reloader, Manager& manager, std::ostream& out, std::ostream& err,
                 bool quiet, const FormatOptions& format_options, StatusLine* status)
    : reloader_(reloader),
      manager_(manager),
      out_(out),
      err_(err),
      quiet_(quiet),
      format_options_(format_options),
      status_(status) {
  thread_ = std::thread([this] { run(); });
}

Watcher::~Watcher() {
  stop_ = true;
  thread_.join();
  if (status_ != nullptr) status_->clear();
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
    if (status_ != nullptr) {
      status_->draw(
          status_text(reloader_.path(), step_.load(std::memory_order_relaxed), last_reload_));
    }
    const std::string now = fingerprint();
    if (now == seen) continue;
    seen = now;
    const ReloadResult result = reloader_.reload(manager_);
    if (result.staged) last_reload_ = step_.load(std::memory_order_relaxed);
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

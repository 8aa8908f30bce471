#include "commands/output_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>

namespace arbiter::cli {

namespace fs = std::filesystem;

OutputPlace output_place(const std::string& path) {
  std::error_code error;
  // Looked at through every link first: one to a pipe (/dev/stdout, /proc/self/fd/1 -> pipe:[N])
  // leads nowhere a name could be followed to, and is written as it is named.
  const auto status = fs::status(path, error);
  if (fs::exists(status) && !fs::is_regular_file(status)) return {path, true};
  // An open file descriptor (/dev/stdout, /dev/fd/N, /proc/self/fd/N) names the file the shell
  // opened, and what else the command prints goes there too: it is written, not replaced.
  const auto descriptor = [](const fs::path& name) {
    return name.string().rfind("/proc/", 0) == 0;
  };
  fs::path place = path;
  if (descriptor(place)) return {path, true};
  // Followed by hand rather than with canonical(): a link to a file not yet written leads to
  // where that file is to be created. As many links as the kernel follows (ELOOP past it).
  for (int links = 0; links < 40 && fs::is_symlink(fs::symlink_status(place, error)); ++links) {
    const fs::path target = fs::read_symlink(place, error);
    if (error) break;
    place = target.is_absolute() ? target : place.parent_path() / target;
    if (descriptor(place)) return {path, true};
  }
  return {place.string(), false};
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code error;
  if (fs::exists(a, error) && fs::exists(b, error)) return fs::equivalent(a, b, error);
  const fs::path first = fs::weakly_canonical(a, error);
  if (error) return false;
  const fs::path second = fs::weakly_canonical(b, error);
  return !error && first == second;
}

bool is_standard_output(const std::string& path) {
  struct stat out {};
  struct stat file {};
  return !path.empty() && ::fstat(STDOUT_FILENO, &out) == 0 && ::stat(path.c_str(), &file) == 0 &&
         out.st_dev == file.st_dev && out.st_ino == file.st_ino;
}

bool writes_standard_output(const std::vector<std::string>& outputs) {
  return std::any_of(outputs.begin(), outputs.end(), is_standard_output);
}

std::string why_not_writable(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0666);
  if (fd < 0) return std::strerror(errno);
  ::close(fd);
  return "it could be opened when tried again";
}

bool outputs_allowed(std::string_view command, const std::vector<CommandOutput>& outputs,
                     const std::vector<CommandInput>& inputs, std::ostream& err) {
  for (auto output = outputs.begin(); output != outputs.end(); ++output) {
    if (output->path.empty()) continue;
    for (const auto& input : inputs) {
      if (input.path.empty() || !same_file(output->path, input.path)) continue;
      err << fmt::format("arbiter {}: '{}' is {} ('{}'): writing it would destroy it\n", command,
                         output->path, input.what, input.path);
      return false;
    }
    // A device (/dev/null, a terminal) keeps nothing to write over: two outputs may share it.
    std::error_code error;
    if (fs::is_character_file(output->path, error)) continue;
    for (auto other = outputs.begin(); other != output; ++other) {
      if (other->path.empty() || !same_file(output->path, other->path)) continue;
      err << fmt::format(
          "arbiter {}: {} '{}' and {} '{}' are the same file: one would write over the other; "
          "give them different files\n",
          command, other->option, other->path, output->option, output->path);
      return false;
    }
  }
  return true;
}

namespace {

/// What is held before it is written: a replay's trace comes a step at a time.
constexpr std::size_t kBuffered = 64 * 1024;

bool write_all(int fd, std::string_view text) {
  while (!text.empty()) {
    const auto written = ::write(fd, text.data(), text.size());
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) return false;
    text.remove_prefix(static_cast<std::size_t>(written));
  }
  return true;
}

}  // namespace

AtomicFile::AtomicFile(const std::string& path) : given_(path), place_(output_place(path)) {}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!done_ && !place_.in_place && !temp_.empty()) ::unlink(temp_.c_str());
}

void AtomicFile::fail(int error) {
  if (error_.empty()) error_ = fmt::format("cannot write '{}': {}", given_, std::strerror(error));
}

bool AtomicFile::open() {
  if (is_standard_output(given_)) {
    // Written through standard output's own open file (its offset, its O_APPEND), not one opened
    // on it again.
    place_ = {given_, true};
    temp_ = given_;
    fd_ = ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 0);
  } else if (place_.in_place) {
    temp_ = place_.path;
    fd_ = ::open(temp_.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  } else {
    const auto slash = place_.path.rfind('/');
    const std::string dir = slash == std::string::npos ? "." : place_.path.substr(0, slash);
    const std::string name =
        slash == std::string::npos ? place_.path : place_.path.substr(slash + 1);
    // Created with open() rather than mkstemp(), whose 0600 a new file would keep: a new file
    // gets the mode any file created there gets (0666 less the umask), an existing one keeps its
    // own. Named by process and by count: two writers in one process (a trace and a recording,
    // two saves) never meet.
    static std::atomic<unsigned> serial{0};
    do {
      temp_ = fmt::format("{}/.{}.arbiter-{}-{}", dir, name, ::getpid(), serial++);
      fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    } while (fd_ < 0 && errno == EEXIST);
    struct stat info {};
    if (fd_ >= 0 && ::stat(place_.path.c_str(), &info) == 0) ::fchmod(fd_, info.st_mode & 07777);
  }
  if (fd_ < 0) {
    const int error = errno;
    temp_.clear();  // nothing was created, nothing is to be removed
    fail(error);
    return false;
  }
  return true;
}

bool AtomicFile::flush() {
  if (!error_.empty()) return false;
  if (!write_all(fd_, buffer_)) fail(errno);
  buffer_.clear();
  return error_.empty();
}

bool AtomicFile::write(std::string_view text) {
  if (!error_.empty()) return false;
  buffer_ += text;
  return buffer_.size() < kBuffered || flush();
}

int AtomicFile::duplicate() const {
  return fd_ < 0 ? -1 : ::fcntl(fd_, F_DUPFD_CLOEXEC, 0);
}

bool AtomicFile::commit() {
  done_ = true;
  bool ok = fd_ >= 0 && flush();
  // Synced before the rename: otherwise a crash soon after it can leave the name on a file whose
  // text never reached the disk (an empty one, in place of the one replaced), which is what
  // writing whole and renaming is for. One sync per file, at its end. A FIFO or a terminal cannot
  // be synced (EINVAL), nor needs to be: nothing is replaced.
  if (ok && !place_.in_place && ::fsync(fd_) != 0) {
    fail(errno);
    ok = false;
  }
  if (fd_ >= 0 && ::close(fd_) != 0 && ok) {
    fail(errno);
    ok = false;
  }
  fd_ = -1;
  if (place_.in_place) return ok;
  if (ok && ::rename(temp_.c_str(), place_.path.c_str()) != 0) {
    fail(errno);
    ok = false;
  }
  if (!ok) ::unlink(temp_.c_str());
  return ok;
}

bool write_atomically(const std::string& path, const std::string& text, std::string& error) {
  AtomicFile file(path);
  const bool ok = file.open() && file.write(text) && file.commit();
  if (!ok) error = file.error();
  return ok;
}

}  // namespace arbiter::cli

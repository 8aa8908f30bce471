#include "commands/output_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <streambuf>

namespace arbiter::cli {

namespace fs = std::filesystem;

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

/// The descriptor `name` (absolute) names by its form alone, or -1.
int descriptor_by_name(const fs::path& name) {
  const std::string text = name.lexically_normal().string();
  constexpr std::array<std::string_view, 3> kStandard = {"/dev/stdin", "/dev/stdout",
                                                         "/dev/stderr"};
  for (std::size_t fd = 0; fd < kStandard.size(); ++fd) {
    if (text == kStandard[fd]) return static_cast<int>(fd);
  }
  const std::string own = fmt::format("/proc/{}/fd/", ::getpid());
  for (const std::string_view dir :
       {std::string_view("/dev/fd/"), std::string_view("/proc/self/fd/"),
        std::string_view("/proc/thread-self/fd/"), std::string_view(own)}) {
    if (text.size() <= dir.size() || text.compare(0, dir.size(), dir) != 0) continue;
    const char* first = text.data() + dir.size();
    const char* last = text.data() + text.size();
    int fd = -1;
    const auto [end, error] = std::from_chars(first, last, fd);
    // Digits alone: from_chars would take a sign.
    if (*first >= '0' && *first <= '9' && error == std::errc() && end == last) return fd;
  }
  return -1;
}

}  // namespace

int named_descriptor(const std::string& path) {
  if (path.empty()) return -1;
  // By the file too: the shell's `>FILE` with FILE named again is standard output's.
  if (is_standard_output(path)) return STDOUT_FILENO;
  std::error_code error;
  fs::path place = fs::absolute(path, error);
  if (error) return -1;
  // Named before its link is read: /dev/fd/N reads as the file it is open on, which a path
  // would open again.
  for (int links = 0; links < 40; ++links) {
    if (const int fd = descriptor_by_name(place); fd >= 0) return fd;
    if (!fs::is_symlink(fs::symlink_status(place, error))) break;
    const fs::path target = fs::read_symlink(place, error);
    if (error) break;
    place = target.is_absolute() ? target : place.parent_path() / target;
  }
  return -1;
}

int open_output(const std::string& path) {
  const int named = named_descriptor(path);
  if (named < 0) return ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  const int flags = ::fcntl(named, F_GETFL);
  if (flags < 0) return -1;  // EBADF: not open
  if ((flags & O_ACCMODE) == O_RDONLY) {
    errno = EBADF;
    return -1;
  }
  return ::fcntl(named, F_DUPFD_CLOEXEC, 0);
}

OutputPlace output_place(const std::string& path) {
  if (named_descriptor(path) >= 0) return {path, true};
  std::error_code error;
  // Looked at through every link first: one to a pipe (/dev/stdout, /proc/self/fd/1 -> pipe:[N])
  // leads nowhere a name could be followed to, and is written as it is named.
  const auto status = fs::status(path, error);
  if (fs::exists(status) && !fs::is_regular_file(status)) return {path, true};
  // Nor can another process's descriptor (/proc/PID/fd/N) be renamed over: it is written.
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

class OutputStream::Buffer : public std::streambuf {
 public:
  explicit Buffer(int fd) : fd_(fd), data_(kBuffered, '\0') { reset(); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer() override {
    sync();
    ::close(fd_);
  }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (sync() != 0) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override {
    if (error_ == 0 && !write_all(fd_, {pbase(), static_cast<std::size_t>(pptr() - pbase())})) {
      error_ = errno != 0 ? errno : EIO;
    }
    reset();
    return error_ == 0 ? 0 : -1;
  }

 private:
  void reset() { setp(data_.data(), data_.data() + data_.size()); }

  int fd_;
  std::string data_;
  int error_ = 0;  // the first: what follows it is its consequence
};

OutputStream::OutputStream() : std::ostream(nullptr) {}

OutputStream::~OutputStream() = default;

bool OutputStream::open(const std::string& path) {
  const int fd = open_output(path);
  if (fd < 0) {
    open_error_ = errno;
    setstate(std::ios::badbit);
    return false;
  }
  buffer_ = std::make_unique<Buffer>(fd);
  rdbuf(buffer_.get());
  return true;
}

std::string OutputStream::error() const {
  const int error = open_error_ != 0 ? open_error_ : buffer_ ? buffer_->error() : 0;
  return std::strerror(error);
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

AtomicFile::AtomicFile(const std::string& path) : given_(path), place_(output_place(path)) {}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!done_ && !place_.in_place && !temp_.empty()) ::unlink(temp_.c_str());
}

void AtomicFile::fail(int error) {
  if (error_.empty()) error_ = fmt::format("cannot write '{}': {}", given_, std::strerror(error));
}

bool AtomicFile::open() {
  if (place_.in_place) {
    temp_ = place_.path;
    fd_ = open_output(temp_);
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

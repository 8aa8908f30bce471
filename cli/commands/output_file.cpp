#include "commands/output_file.hpp"

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

}  // namespace arbiter::cli

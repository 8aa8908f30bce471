#include "commands/output_file.hpp"

#include <filesystem>

namespace arbiter::cli {

namespace fs = std::filesystem;

OutputPlace output_place(const std::string& path) {
  fs::path place = path;
  std::error_code error;
  // Followed by hand rather than with canonical(): a link to a file not yet written leads to
  // where that file is to be created. As many links as the kernel follows (ELOOP past it).
  for (int links = 0; links < 40 && fs::is_symlink(fs::symlink_status(place, error)); ++links) {
    const fs::path target = fs::read_symlink(place, error);
    if (error) break;
    place = target.is_absolute() ? target : place.parent_path() / target;
  }
  const auto status = fs::status(place, error);
  return {place.string(), fs::exists(status) && !fs::is_regular_file(status)};
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

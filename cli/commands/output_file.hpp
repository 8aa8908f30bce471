#pragma once

#include <string>

namespace arbiter::cli {

/// Where the CLI puts a file it writes whole (a replay's trace and recording, a studio save).
struct OutputPlace {
  /// The file to replace: the path, or the file a symbolic link there leads to (followed through
  /// every link), so that a link stays a link and what it names gets the new text.
  std::string path;
  /// The path exists and is not a regular file (a FIFO, a terminal, a pipe), or names an open
  /// descriptor (/dev/stdout, /dev/fd/N): it is written directly, as renaming a file over it would
  /// replace it.
  bool in_place = false;
};

OutputPlace output_place(const std::string& path);

/// Whether two paths name one file: the same file when both exist (through links and hard
/// links), the same normal path otherwise.
bool same_file(const std::string& a, const std::string& b);

}  // namespace arbiter::cli

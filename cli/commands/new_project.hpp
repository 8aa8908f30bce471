#pragma once
// `arbiter new plugin NAME [DIR]`: a starter plugin project, written from the template files of
// cli/templates/plugin/, which the build compiles in (cli/templates/embed.cmake).

#include <cstddef>
#include <ostream>
#include <string>
#include <string_view>

namespace arbiter::cli {

/// A file of a template: its path relative to the project (`@NAME@` in it stands for the
/// project's name, as in the text) and its bytes.
struct TemplateFile {
  const char* path;
  const unsigned char* bytes;
  std::size_t size;
};

extern const TemplateFile kPluginTemplate[];
extern const std::size_t kPluginTemplateSize;

/// Why `name` cannot name a plugin project (it becomes a C++ namespace, a CMake target and the
/// prefix of the class names), or "" when it can.
std::string plugin_name_error(std::string_view name);

/// Writes the plugin template, `@NAME@` replaced by `name`, into `dir` (`name` when empty),
/// which must not exist or be empty: nothing is ever overwritten. Says what it wrote and what to
/// run next on `out`, and why it refused or failed on `err`. Returns the exit code: 0, 1 when a
/// file could not be written, 2 for a bad name or a directory in the way.
int new_plugin(const std::string& name, const std::string& dir, std::ostream& out,
               std::ostream& err);

}  // namespace arbiter::cli

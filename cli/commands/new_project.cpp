#include "commands/new_project.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "commands/command.hpp"

namespace arbiter::cli {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxNameLength = 64;

// The name is a C++ namespace in the sources: none of these may be one. Each word of these
// lists is between spaces.
constexpr std::string_view kCppKeywords =
    " alignas alignof and and_eq asm atomic_cancel atomic_commit atomic_noexcept auto bitand "
    "bitor bool break case catch char char8_t char16_t char32_t class compl concept const "
    "consteval constexpr constinit const_cast continue co_await co_return co_yield decltype "
    "default delete do double dynamic_cast else enum explicit export extern false float for "
    "friend goto if inline int long mutable namespace new noexcept not not_eq nullptr "
    "operator or or_eq private protected public reflexpr register reinterpret_cast requires "
    "return short signed sizeof static static_assert static_cast struct switch synchronized "
    "template this thread_local throw true try typedef typeid typename union unsigned using "
    "virtual void volatile wchar_t while xor xor_eq ";

// Target names CMake keeps for itself (policy CMP0037).
constexpr std::string_view kCMakeReserved =
    " all clean help install package test edit_cache rebuild_cache list_install_components "
    "ZERO_CHECK ALL_BUILD RUN_TESTS INSTALL PACKAGE ";

bool is_name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
}

// The closest name that would do, for the error's note: 'my-robot' -> 'my_robot'.
std::string suggested_name(std::string_view name) {
  std::string suggestion;
  for (const char c : name) suggestion += is_name_char(c) ? c : '_';
  return plugin_name_error(suggestion).empty() ? suggestion : std::string();
}

std::string replaced(std::string_view text, const std::string& name) {
  std::string out;
  out.reserve(text.size());
  constexpr std::string_view kPlaceholder = "@NAME@";
  std::size_t at = 0;
  while (true) {
    const std::size_t found = text.find(kPlaceholder, at);
    out.append(text.substr(at, found - at));
    if (found == std::string_view::npos) break;
    out += name;
    at = found + kPlaceholder.size();
  }
  return out;
}

// A path as a shell command line takes it.
std::string shell_word(const std::string& path) {
  const bool plain = std::all_of(path.begin(), path.end(), [](char c) {
    return is_name_char(c) || c == '/' || c == '.' || c == '-' || c == '+' || c == ',';
  });
  if (plain && !path.empty()) return path;
  std::string quoted = "'";
  for (const char c : path) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace

std::string plugin_name_error(std::string_view name) {
  if (name.empty()) return "it is empty";
  if (name.size() > kMaxNameLength) {
    return fmt::format("it has {} characters; at most {} are allowed", name.size(), kMaxNameLength);
  }
  if (!std::isalpha(static_cast<unsigned char>(name.front()))) {
    return "it does not start with a letter";
  }
  const auto bad = std::find_if_not(name.begin(), name.end(), is_name_char);
  if (bad != name.end()) {
    return fmt::format("it has '{}' in it: only letters, digits and '_' are allowed",
                       printable(std::string_view(&*bad, 1)));
  }
  if (name.find("__") != std::string_view::npos) {
    return "it has '__' in it, which C++ keeps for the implementation";
  }
  if (name.back() == '_') {
    return fmt::format(
        "it ends with '_', which would put '__' in its C++ namespace, {}_plugin, "
        "and C++ keeps that for the implementation",
        name);
  }
  const std::string word = " " + std::string(name) + " ";
  if (kCppKeywords.find(word) != std::string_view::npos) {
    return "it is a C++ keyword";
  }
  if (kCMakeReserved.find(word) != std::string_view::npos) {
    return "it is a target name CMake keeps for itself";
  }
  if (name == "arbiter" || name == "std") {
    return name == "arbiter"
               ? "it is taken: Arbiter's API is its namespace, the CLI its CMake target"
               : "it is taken: it is the C++ standard library's namespace";
  }
  return {};
}

int new_plugin(const std::string& name, const std::string& dir_given, std::ostream& out,
               std::ostream& err) {
  constexpr const char* kCommand = "arbiter new plugin";
  if (const std::string why = plugin_name_error(name); !why.empty()) {
    err << fmt::format("{}: '{}' cannot name a plugin: {}\n", kCommand, printable(name), why);
    err << "  note: the name becomes the plugin's file (arbiter_NAME.so), its C++ namespace "
           "(NAME_plugin), its CMake target and the prefix of its classes (NAME.Stop): letters, "
           "digits and '_', starting with a letter\n";
    if (const std::string better = suggested_name(name); !better.empty() && better != name) {
      err << fmt::format("  note: did you mean '{}'?\n", better);
    }
    return kExitUsage;
  }
  const std::string dir_text = dir_given.empty() ? name : dir_given;
  const fs::path dir(dir_text);
  std::error_code failed;
  const fs::file_status status = fs::status(dir, failed);
  if (failed && failed != std::errc::no_such_file_or_directory) {
    err << fmt::format("{}: cannot look at '{}': {}\n", kCommand, printable(dir_text),
                       failed.message());
    return kExitUsage;
  }
  if (fs::exists(status)) {
    if (!fs::is_directory(status)) {
      err << fmt::format("{}: '{}' exists and is not a directory; nothing was written\n", kCommand,
                         printable(dir_text));
      return kExitUsage;
    }
    fs::directory_iterator entries(dir, failed);
    if (failed) {
      err << fmt::format("{}: cannot read the directory '{}': {}\n", kCommand, printable(dir_text),
                         failed.message());
      return kExitUsage;
    }
    if (entries != fs::directory_iterator()) {
      err << fmt::format(
          "{}: the directory '{}' is not empty (it has '{}'); nothing was written\n"
          "  note: give a new or empty directory: arbiter new plugin {} DIR\n",
          kCommand, printable(dir_text), printable(entries->path().filename().string()), name);
      return kExitUsage;
    }
  }

  std::vector<std::string> written;
  for (std::size_t i = 0; i < kPluginTemplateSize; ++i) {
    const TemplateFile& file = kPluginTemplate[i];
    const fs::path path = dir / replaced(file.path, name);
    fs::create_directories(path.parent_path(), failed);
    if (failed) {
      err << fmt::format("{}: cannot make the directory '{}': {}\n", kCommand,
                         printable(path.parent_path().string()), failed.message());
      return kExitInvalid;
    }
    const std::string text =
        replaced(std::string_view(reinterpret_cast<const char*>(file.bytes), file.size), name);
    // "x": a file that appeared since the directory was looked at is not overwritten either.
    std::FILE* stream = std::fopen(path.c_str(), "wbx");
    const bool ok = stream != nullptr &&
                    std::fwrite(text.data(), 1, text.size(), stream) == text.size() &&
                    std::fflush(stream) == 0;
    const int error = errno;
    if (stream != nullptr && std::fclose(stream) != 0 && ok) {
      err << fmt::format("{}: cannot write '{}': {}\n", kCommand, printable(path.string()),
                         std::strerror(errno));
      return kExitInvalid;
    }
    if (!ok) {
      err << fmt::format("{}: cannot write '{}': {}\n", kCommand, printable(path.string()),
                         std::strerror(error));
      return kExitInvalid;
    }
    written.push_back(path.string());
  }

  std::sort(written.begin(), written.end());
  out << fmt::format(
      "created the plugin project '{}' in {}/, with the classes {}.Stop (a "
      "behaviour) and {}.Drive (a state):\n",
      name, dir_text, name, name);
  for (const auto& path : written) out << "  " << path << "\n";
  const std::string at = shell_word(dir_text);
  out << fmt::format(
      "Build it and run its scenario test (with arbiter on the PATH, CMake finds the SDK):\n"
      "  cmake -S {0} -B {0}/build\n"
      "  cmake --build {0}/build\n"
      "  ctest --test-dir {0}/build\n"
      "Then run its config with the plugin:\n"
      "  arbiter --plugin-path {0}/build run {0}/{1}.yaml\n"
      "{0}/README.md tells more.\n",
      at, name);
  return kExitOk;
}

}  // namespace arbiter::cli

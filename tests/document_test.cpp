// Hostile config files (docs/robustness.md) as the reader and the document stage meet them: each
// is answered with its located error in bounded time and memory, never a crash, and so are paths
// that are not config files.

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "arbiter/load.hpp"
#include "config_files.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;

namespace {

const fs::path kHostileDir = fs::path(ARBITER_SOURCE_DIR) / "tests" / "data" / "hostile";

using test::error_codes;
using test::load_file;
using test::Outcome;
using test::read_text;
using test::TempDir;
using test::write_text;

/// The test registry: a hostile file names no class of its own.
const Registry& registry() {
  static const Registry instance = test::make_test_registry();
  return instance;
}

/// Peak resident memory of this process so far, in MiB.
double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

bool has_error(const Outcome& outcome, const std::string& code) {
  const auto codes = error_codes(outcome.diagnostics);
  return std::find(codes.begin(), codes.end(), code) != codes.end();
}

/// Checks that loading `path` fails with an error `code`, in bounded memory. Time is bounded by
/// the test's CTest TIMEOUT (tests/CMakeLists.txt), which a runaway input exceeds.
void expect_rejected(const fs::path& path, const std::string& code,
                     const LoadOptions& options = {}) {
  const double before = peak_rss_mib();
  const Outcome outcome = load_file(path, options);
  INFO(path.filename().string() << ":\n" << format(outcome.diagnostics));
  CHECK_FALSE(outcome.loaded);
  CHECK(has_error(outcome, code));
  // Sanitizer builds use several times the memory of a plain one; the bound is for runaways.
  CHECK(peak_rss_mib() - before < 1500.0);
}

/// Runs `arbiter ARGUMENTS` (already shell-quoted), capturing its output.
test::CliResult run_cli(const std::string& arguments) {
  return test::run_captured("\"" + std::string(ARBITER_CLI) + "\" " + arguments);
}

std::string quoted(const fs::path& path) {
  return "\"" + path.string() + "\"";
}

/// How a file of tests/data/hostile must be rejected: the error's code, and the first error line
/// as `arbiter validate` prints it from inside tests/data/hostile (a line ending in "..." is
/// compared up to there).
struct HostileCase {
  std::string code;
  std::string first_error;
};

const std::map<std::string, HostileCase>& hostile_cases() {
  static const std::map<std::string, HostileCase> cases = {
      {"activation_overflow.yaml",
       {"out-of-range",
        "activation_overflow.yaml:8:54: error: param 'activation' of behaviour 'run' has an item "
        "1e999999; items must be a finite number in [0, 1]"}},
      {"binary_garbage.json",
       {"binary-file",
        "binary_garbage.json:3:115: error: the file contains a NUL byte; a config is UTF-8 text"}},
      {"capacity_overflow.yaml",
       {"wrong-type",
        "capacity_overflow.yaml:5:15: error: capacity of state machine 'plan' must be an integer "
        "in [1, 1000000], found the number 1e999999"}},
      {"comments_only.yaml",
       {"wrong-type",
        "comments_only.yaml:1:1: error: a config must be a mapping starting with 'arbiter: 1', "
        "found an empty document"}},
      {"deep_nesting.json",
       {"too-deep", "deep_nesting.json:1:241: error: nesting deeper than 200 levels"}},
      {"deep_nesting_block.yaml",
       {"too-deep", "deep_nesting_block.yaml:203:201: error: nesting deeper than 200 levels"}},
      {"deep_nesting_objects.json",
       {"too-deep", "deep_nesting_objects.json:1:1236: error: nesting deeper than 200 levels"}},
      {"default_overflow.yaml",
       {"wrong-type",
        "default_overflow.yaml:6:38: error: default of actuator 'speed' must be a finite number "
        "(double), found the number 1e999999"}},
      {"default_vec_infinite.yaml",
       {"wrong-type",
        "default_vec_infinite.yaml:6:35: error: default of actuator 'walk' must be a list of 2 "
        "finite numbers (vec2), found a list of 2 items"}},
      {"empty.json",
       {"wrong-type",
        "empty.json:1:1: error: a config must be a mapping starting with 'arbiter: 1', found an "
        "empty document"}},
      {"fuzz_control_characters.yaml",
       {"yaml-syntax", "fuzz_control_characters.yaml:10:7: error: duplicate key 'c'"}},
      {"fuzz_nel_escape.yaml",
       {"wrong-type",
        "fuzz_nel_escape.yaml:5:17: error: 'behaviours' must be a mapping from names to {type: "
        "...}, found the string 'kick_ball => go_behin..."}},
      {"include_binary.yaml",
       {"binary-file",
        "nul_byte.yaml:2:10: error: the file contains a NUL byte; a config is UTF-8 text"}},
      {"include_directory.yaml",
       {"not-a-file",
        "include_directory.yaml:3:11: error: cannot include '.': is a directory, not a config "
        "file"}},
      {"include_missing.yaml",
       {"file-not-found",
        "include_missing.yaml:3:11: error: cannot include 'no_such_file.yaml': cannot open: No "
        "such file or directory"}},
      {"include_self.yaml",
       {"include-cycle",
        "include_self.yaml:3:11: error: include cycle: include_self.yaml -> include_self.yaml"}},
      {"invalid_utf8.json",
       {"invalid-utf8", "invalid_utf8.json:1:25: error: invalid UTF-8; a config is UTF-8 text"}},
      {"latin1.yaml",
       {"invalid-utf8", "latin1.yaml:2:10: error: invalid UTF-8; a config is UTF-8 text"}},
      {"list.json",
       {"wrong-type",
        "list.json:1:1: error: a config must be a mapping starting with 'arbiter: 1', found a "
        "list of 1 item"}},
      {"list.yaml",
       {"wrong-type",
        "list.yaml:1:1: error: a config must be a mapping starting with 'arbiter: 1', found a "
        "list of 2 items"}},
      {"merge_key_bomb.yaml",
       {"too-large",
        "merge_key_bomb.yaml:19:23: error: the document has more than 1048576 nodes (after "
        "expanding aliases); refusing to read further"}},
      {"nul_byte.yaml",
       {"binary-file",
        "nul_byte.yaml:2:10: error: the file contains a NUL byte; a config is UTF-8 text"}},
      {"null.json",
       {"wrong-type",
        "null.json:1:1: error: a config must be a mapping starting with 'arbiter: 1', found an "
        "empty document"}},
      {"rate_infinite.yaml",
       {"out-of-range",
        "rate_infinite.yaml:3:10: error: 'rate_hz' must be a finite positive number, found the "
        "number .inf"}},
      {"rate_nan.yaml",
       {"out-of-range",
        "rate_nan.yaml:3:10: error: 'rate_hz' must be a finite positive number, found the number "
        ".nan"}},
      {"rate_negative.json",
       {"out-of-range",
        "rate_negative.json:1:47: error: 'rate_hz' must be a positive number, found the number "
        "-15"}},
      {"rate_negative.yaml",
       {"out-of-range",
        "rate_negative.yaml:3:10: error: 'rate_hz' must be a positive number, found the number "
        "-15"}},
      {"rate_overflow.json",
       {"json-syntax",
        "rate_overflow.json:1:47: error: invalid JSON: the number 1e999999 is out of range "
        "(beyond about 1.8e308)"}},
      {"rate_overflow.yaml",
       {"out-of-range",
        "rate_overflow.yaml:3:10: error: 'rate_hz' must be a finite positive number, found the "
        "number 1e999999"}},
      {"rate_underflow.yaml",
       {"out-of-range",
        "rate_underflow.yaml:3:10: error: 'rate_hz' must be a positive number, found the number "
        "1e-999999"}},
      {"scalar.json",
       {"wrong-type",
        "scalar.json:1:1: error: a config must be a mapping starting with 'arbiter: 1', found the "
        "number 42"}},
      {"scalar.yaml",
       {"wrong-type",
        "scalar.yaml:1:1: error: a config must be a mapping starting with 'arbiter: 1', found the "
        "string 'arbiter 1 name scalar'"}},
      {"utf16.yaml",
       {"invalid-utf8",
        "utf16.yaml:1:1: error: the file is UTF-16 (it starts with a UTF-16 byte order mark); a "
        "config is UTF-8 text"}},
      {"utf8_overlong.yaml",
       {"invalid-utf8", "utf8_overlong.yaml:2:8: error: invalid UTF-8; a config is UTF-8 text"}},
      {"utf8_surrogate.yaml",
       {"invalid-utf8", "utf8_surrogate.yaml:2:8: error: invalid UTF-8; a config is UTF-8 text"}},
      {"whitespace_only.json",
       {"wrong-type",
        "whitespace_only.json:1:1: error: a config must be a mapping starting with 'arbiter: 1', "
        "found an empty document"}},
      {"write_infinite.yaml",
       {"wrong-type",
        "write_infinite.yaml:8:69: error: behaviour 'run' (scripted) needs a finite number "
        "(double) here, found the number -.inf"}},
  };
  return cases;
}

/// `text` with the codes of its errors (`error[code]:`, checked by the golden files) left out.
std::string without_codes(const std::string& text) {
  static const std::regex code(": error\\[[a-z0-9-]+\\]: ");
  return std::regex_replace(text, code, ": error: ");
}

/// The first line of `text` that reports an error, with every "`dir`/" and the error's code
/// removed.
std::string first_error_line(const std::string& text, const fs::path& dir) {
  std::istringstream lines(without_codes(text));
  std::string line;
  while (std::getline(lines, line)) {
    if (line.find(": error: ") == std::string::npos) continue;
    const std::string prefix = dir.string() + "/";
    for (auto at = line.find(prefix); at != std::string::npos; at = line.find(prefix)) {
      line.erase(at, prefix.size());
    }
    return line;
  }
  return "";
}

/// Checks `line` against an expected first error line (see HostileCase).
void check_first_error(const std::string& line, const std::string& expected) {
  const std::string ellipsis = "...";
  if (expected.size() > ellipsis.size() &&
      expected.compare(expected.size() - ellipsis.size(), ellipsis.size(), ellipsis) == 0) {
    CHECK(line.substr(0, expected.size() - ellipsis.size()) ==
          expected.substr(0, expected.size() - ellipsis.size()));
  } else {
    CHECK(line == expected);
  }
}

}  // namespace

TEST_CASE("every hostile file is rejected with its error, in bounded time and memory",
          "[robustness][hostile]") {
  for (const auto& [name, expected] : hostile_cases()) {
    DYNAMIC_SECTION(name) {
      expect_rejected(kHostileDir / name, expected.code);
      const Outcome outcome = load_file(kHostileDir / name);
      check_first_error(first_error_line(format(outcome.diagnostics), kHostileDir),
                        expected.first_error);
    }
  }
}

TEST_CASE("every file in tests/data/hostile is a listed case", "[robustness][hostile]") {
  for (const auto& path : test::files_in(kHostileDir, [](const fs::path&) { return true; })) {
    INFO(path.filename().string());
    CHECK(hostile_cases().count(path.filename().string()) == 1);
  }
}

TEST_CASE("arbiter validate exits 1 on every hostile file, with its error, without a crash",
          "[robustness][cli]") {
  for (const auto& [name, expected] : hostile_cases()) {
    DYNAMIC_SECTION(name) {
      const auto result = run_cli("validate " + quoted(kHostileDir / name));
      INFO(result.err);
      CHECK_FALSE(result.signalled);
      CHECK(result.exit_code == 1);
      check_first_error(first_error_line(result.err, kHostileDir), expected.first_error);
      const auto json = run_cli("validate --format json " + quoted(kHostileDir / name));
      CHECK_FALSE(json.signalled);
      CHECK(json.exit_code == 1);
    }
  }
}

TEST_CASE("a YAML escape that yaml-cpp decodes to invalid UTF-8 is repaired",
          "[robustness][hostile][fuzz]") {
  // Found by the fuzzer: "\N" (next line, U+0085) became the lone byte 0x85, and printing the
  // diagnostics as JSON threw.
  const Diagnostics diagnostics =
      test::diagnose_text("arbiter: 1\nname: x\nlayers: \"a\\N\\_b\"\n", registry());
  REQUIRE(diagnostics.error_count() == 1);
  CHECK(diagnostics.items()[0].message.find("'a\xC2\x85\xC2\xA0"
                                            "b'") != std::string::npos);
  CHECK_NOTHROW(nlohmann::json::parse(format_json(diagnostics)));
}

TEST_CASE("generated big inputs are rejected in bounded time and memory",
          "[robustness][hostile][big]") {
  TempDir dir;
  SECTION("a file over the size limit, and the limit is configurable") {
    const std::string config = "arbiter: 1\nname: big\n";
    write_text(dir / "big.yaml", config + "# " + std::string(ReadLimits{}.max_file_bytes, 'x'));
    expect_rejected(dir / "big.yaml", "file-too-large");
    LoadOptions small;
    small.limits.max_file_bytes = 100;
    write_text(dir / "small.yaml", config + "# " + std::string(200, 'x') + "\n");
    expect_rejected(dir / "small.yaml", "file-too-large", small);
    CHECK(load_file(dir / "small.yaml").diagnostics.error_count() == 0);
  }
  SECTION("nesting 100 000 levels deep") {
    const std::size_t n = 100000;
    write_text(dir / "flow.yaml",
               "arbiter: 1\nname: deep\nlayers: " + std::string(n, '[') + std::string(n, ']'));
    expect_rejected(dir / "flow.yaml", "too-deep");
    write_text(dir / "arrays.json", "{\"arbiter\": 1, \"name\": \"deep\", \"layers\": " +
                                        std::string(n, '[') + std::string(n, ']') + "}");
    expect_rejected(dir / "arrays.json", "too-deep");
    std::string objects;
    for (std::size_t i = 0; i < n; ++i) objects += "{\"a\":";
    write_text(dir / "objects.json", "{\"arbiter\": 1, \"name\": \"deep\", \"layers\": " + objects +
                                         "1" + std::string(n, '}') + "}");
    expect_rejected(dir / "objects.json", "too-deep");
    std::string block = "arbiter: 1\nname: deep\nq:\n";
    for (std::size_t i = 1; i <= 3000; ++i) block += std::string(i, ' ') + "k:\n";
    write_text(dir / "block.yaml", block);
    expect_rejected(dir / "block.yaml", "too-deep");
  }
  SECTION("a one-line flow list with more nodes than the limit") {
    // Locating nodes once cost time quadratic in the length of a line.
    LoadOptions options;
    options.limits.max_nodes = 100000;
    std::string items;
    for (int i = 0; i < 200000; ++i) items += "1,";
    write_text(dir / "wide.yaml", "arbiter: 1\nname: wide\nlayers: [" + items + "1]\n");
    expect_rejected(dir / "wide.yaml", "too-large", options);
  }
  SECTION("an alias bomb with the default limits") {
    std::string bomb = "arbiter: 1\nname: bomb\na: &a [x, x, x, x, x, x, x, x, x, x]\n";
    for (char c = 'b'; c <= 'k'; ++c) {
      bomb += std::string(1, c) + ": &" + c + " [";
      for (int k = 0; k < 10; ++k)
        bomb += std::string(k > 0 ? ", " : "") + "*" + static_cast<char>(c - 1);
      bomb += "]\n";
    }
    write_text(dir / "bomb.yaml", bomb);
    expect_rejected(dir / "bomb.yaml", "too-large");
  }
  SECTION("long keys and names") {
    // Suggestions compared names with a full edit-distance table, quadratic in their length.
    // yaml-cpp reads keys (so names) of up to 1024 characters; a value can be longer.
    const std::string name(1000, 'a');
    write_text(dir / "key.json", "{\"arbiter\": 1, \"name\": \"x\", \"" + name + "\": 1}");
    expect_rejected(dir / "key.json", "unknown-key");
    write_text(dir / "names.yaml",
               "arbiter: 1\nname: x\nlayers:\n  - name: l\n    behaviours:\n"
               "      " +
                   name + ": scripted\n    inhibitions: [" + name + "b -> " + name + "]\n");
    expect_rejected(dir / "names.yaml", "unknown-behaviour");
    write_text(dir / "value.yaml",
               "arbiter: 1\nname: x\non_exception: " + std::string(1 << 20, 's') + "\n");
    expect_rejected(dir / "value.yaml", "out-of-range");
  }
  SECTION("many inhibitions, valid and not") {
    // Duplicate inhibitions were found by a linear search per inhibition, and every unknown
    // name was compared with every behaviour name for a suggestion.
    std::string behaviours;
    std::string valid;
    std::string invalid;
    for (int i = 0; i < 2000; ++i) {
      behaviours += "      b" + std::to_string(i) + ": scripted\n";
      for (int j = i + 1; j < std::min(2000, i + 11); ++j) {
        valid += "      - b" + std::to_string(i) + " -> b" + std::to_string(j) + "\n";
      }
      for (int k = 0; k < 3; ++k) {
        invalid += "      - c" + std::to_string(3 * i + k) + " -> b" + std::to_string(i) + "\n";
      }
    }
    const std::string head = "arbiter: 1\nname: many\nlayers:\n  - name: l\n    behaviours:\n";
    write_text(dir / "valid.yaml", head + behaviours + "    inhibitions:\n" + valid);
    const Outcome outcome = load_file(dir / "valid.yaml");
    INFO(format(outcome.diagnostics).substr(0, 2000));
    CHECK(outcome.loaded);
    write_text(dir / "invalid.yaml", head + behaviours + "    inhibitions:\n" + invalid);
    expect_rejected(dir / "invalid.yaml", "unknown-behaviour");
  }
  SECTION("random bytes, and random printable text") {
    std::mt19937 random(20240611);
    for (int round = 0; round < 40; ++round) {
      std::string bytes(4096, '\0');
      for (auto& c : bytes) c = static_cast<char>(random() & 0xFF);
      if (round % 2 == 1) {
        for (auto& c : bytes) c = static_cast<char>(' ' + (static_cast<unsigned char>(c) % 95));
        if (round % 4 == 1) bytes = "arbiter: 1\nname: x\n" + bytes;
      }
      const fs::path path =
          dir / ("random" + std::to_string(round) + (round % 3 == 0 ? ".json" : ".yaml"));
      write_text(path, bytes);
      const Outcome outcome = load_file(path);
      INFO(path.filename().string() << ": " << format(outcome.diagnostics).substr(0, 500));
      CHECK_FALSE(outcome.loaded);
      CHECK(outcome.diagnostics.error_count() > 0);
    }
  }
}

/// The message of the only error loading `path` reports, after checking its code.
std::string only_error(const fs::path& path, const std::string& code) {
  expect_rejected(path, code);
  const Outcome outcome = load_file(path);
  const auto& items = outcome.diagnostics.items();
  REQUIRE(items.size() == 1);
  CHECK(items[0].code == code);
  return items[0].message;
}

/// True when this process can open `path` for reading (root can open a chmod 000 file).
bool can_open(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK);
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

TEST_CASE("paths that are not config files are reported", "[robustness][hostile][files]") {
  TempDir dir;
  SECTION("a missing file") {
    CHECK(only_error(dir / "missing.yaml", "file-not-found") ==
          "cannot open: No such file or directory");
  }
  SECTION("a dangling symbolic link") {
    fs::create_symlink(dir / "nowhere.yaml", dir / "dangling.yaml");
    CHECK(only_error(dir / "dangling.yaml", "file-not-found") ==
          "is a symbolic link to a file that does not exist");
  }
  SECTION("a symbolic link loop, which even root cannot read") {
    fs::create_symlink(dir / "loop.yaml", dir / "loop.yaml");
    CHECK(only_error(dir / "loop.yaml", "unreadable-file") ==
          "cannot be read: Too many levels of symbolic links");
  }
  SECTION("an include that is a symbolic link loop") {
    fs::create_symlink(dir / "loop.yaml", dir / "loop.yaml");
    write_text(dir / "main.yaml", "arbiter: 1\nname: x\ninclude: [loop.yaml]\n");
    CHECK(only_error(dir / "main.yaml", "unreadable-file") ==
          "cannot include 'loop.yaml': cannot be read: Too many levels of symbolic links");
  }
  SECTION("a directory") {
    fs::create_directories(dir / "configs.yaml");
    CHECK(only_error(dir / "configs.yaml", "not-a-file") == "is a directory, not a config file");
  }
  SECTION("a FIFO, which would block the reader") {
    REQUIRE(::mkfifo((dir / "pipe.yaml").c_str(), 0600) == 0);
    CHECK(only_error(dir / "pipe.yaml", "not-a-file") ==
          "is not a regular file (a FIFO, socket or device), not a config file");
  }
  SECTION("a device that never ends") {
    if (fs::exists("/dev/zero")) expect_rejected("/dev/zero", "not-a-file");
  }
  SECTION("an include that is a FIFO") {
    REQUIRE(::mkfifo((dir / "pipe.yaml").c_str(), 0600) == 0);
    write_text(dir / "main.yaml", "arbiter: 1\nname: x\ninclude: [pipe.yaml]\n");
    expect_rejected(dir / "main.yaml", "not-a-file");
  }
  SECTION("an unreadable file") {
    write_text(dir / "secret.yaml", "arbiter: 1\nname: secret\n");
    fs::permissions(dir / "secret.yaml", fs::perms::none);
    if (can_open(dir / "secret.yaml")) {
      WARN(
          "skipped: this user (root?) can read a chmod 000 file; the next sections fail to "
          "open and to read files that root cannot read either");
      CHECK(::geteuid() == 0);  // only root may skip: for anyone else, the file is unreadable
    } else {
      CHECK(only_error(dir / "secret.yaml", "unreadable-file") ==
            "cannot be opened for reading: Permission denied");
    }
  }
  SECTION("a file in a directory that cannot be searched") {
    fs::create_directories(dir / "locked");
    write_text(dir / "locked" / "a.yaml", "arbiter: 1\nname: a\n");
    fs::permissions(dir / "locked", fs::perms::none);
    if (can_open(dir / "locked" / "a.yaml")) {
      WARN("skipped: this user (root?) can search a chmod 000 directory");
      CHECK(::geteuid() == 0);
    } else {
      CHECK(only_error(dir / "locked" / "a.yaml", "unreadable-file") ==
            "cannot be read: Permission denied");
    }
  }
  SECTION("a regular file that even root cannot open") {
    // Linux refuses to open a write-only sysctl for reading, whoever asks.
    const fs::path write_only = "/proc/sys/vm/compact_memory";
    if (!fs::is_regular_file(write_only) || can_open(write_only)) {
      WARN("skipped: " << write_only << " is not a write-only file here");
    } else {
      CHECK(only_error(write_only, "unreadable-file") ==
            "cannot be opened for reading: Permission denied");
    }
  }
  SECTION("a regular file whose reading fails, and an include of it") {
    // Reading /proc/self/mem from offset 0 fails with EIO, for root too.
    const fs::path failing = "/proc/self/mem";
    if (!fs::is_regular_file(failing)) {
      WARN("skipped: no " << failing << " here");
    } else {
      CHECK(only_error(failing, "unreadable-file") == "read error: Input/output error");
      write_text(dir / "main.yaml", "arbiter: 1\nname: x\ninclude: [/proc/self/mem]\n");
      CHECK(only_error(dir / "main.yaml", "unreadable-file") ==
            "cannot include '/proc/self/mem': read error: Input/output error");
    }
  }
  SECTION("arbiter validate exits 1 on each, with the error") {
    REQUIRE(::mkfifo((dir / "pipe.yaml").c_str(), 0600) == 0);
    fs::create_symlink(dir / "loop.yaml", dir / "loop.yaml");
    write_text(dir / "loops.yaml", "arbiter: 1\nname: x\ninclude: [loop.yaml]\n");
    write_text(dir / "secret.yaml", "arbiter: 1\nname: secret\n");
    fs::permissions(dir / "secret.yaml", fs::perms::none);
    std::vector<std::pair<fs::path, std::string>> cases = {
        {dir.path(), ": error: is a directory, not a config file"},
        {dir / "pipe.yaml", ": error: is not a regular file"},
        {dir / "loops.yaml",
         "loops.yaml:3:11: error: cannot include 'loop.yaml': cannot be read: "
         "Too many levels of symbolic links"},
    };
    if (!can_open(dir / "secret.yaml")) {
      cases.emplace_back(dir / "secret.yaml", ": error: cannot be opened for reading");
    }
    if (fs::is_regular_file("/proc/self/mem")) {
      cases.emplace_back("/proc/self/mem", "/proc/self/mem: error: read error");
    }
    if (fs::is_regular_file("/proc/sys/vm/compact_memory") &&
        !can_open("/proc/sys/vm/compact_memory")) {
      cases.emplace_back("/proc/sys/vm/compact_memory", ": error: cannot be opened for reading");
    }
    for (const auto& [path, message] : cases) {
      const auto result = run_cli("validate " + quoted(path));
      INFO(path << ": " << result.err);
      CHECK_FALSE(result.signalled);
      CHECK(result.exit_code == 1);
      CHECK(without_codes(result.err).find(message) != std::string::npos);
    }
  }
}

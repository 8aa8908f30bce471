// Robustness (docs/robustness.md): hostile config files are answered with an error in bounded
// time and memory, never a crash; behaviour code that throws, asks for a non-finite level or
// writes non-finite values is contained at the step boundary, reported once, and handled by the
// config's `on_exception` policy.

#include <fcntl.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
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
#include "arbiter/program.hpp"
#include "arbiter/state.hpp"
#include "arbiter/trace.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;

namespace {

const fs::path kHostileDir = fs::path(ARBITER_SOURCE_DIR) / "tests" / "data" / "hostile";

// --- behaviour code that misbehaves --------------------------------------------------------------

/// Throws from `callback` (init, update, activation, execute, inhibited) in steps [from, until];
/// otherwise requests `level`. Writes `value` to `out` at the start of execute(), so a throw from
/// execute() leaves a write behind. Counts its calls.
class Faulty : public Behaviour {
 public:
  void init(BehaviourInitContext& ctx) override {
    callback = ctx.param<std::string>("callback");
    from = static_cast<std::uint64_t>(ctx.param<std::int64_t>("from"));
    until = static_cast<std::uint64_t>(ctx.param<std::int64_t>("until"));
    level = ctx.param<double>("level");
    value = ctx.param<double>("value");
    out = ctx.output<double>("out");
    if (callback == "init") throw std::runtime_error("faulty init");
  }
  void update(const StepContext& ctx) override {
    ++updates;
    fail("update", ctx);
  }
  double activation(const StepContext& ctx) override {
    ++activations;
    fail("activation", ctx);
    return level;
  }
  void execute(ExecuteContext& ctx) override {
    ++executions;
    ctx.write(out, value);
    fail("execute", ctx);
  }
  void inhibited(const InhibitedContext& ctx) override {
    ++inhibitions;
    fail("inhibited", ctx);
  }

  std::string callback;
  std::uint64_t from = 1;
  std::uint64_t until = 0;
  double level = 1.0;
  double value = 0.0;
  Output<double> out;
  int updates = 0;
  int activations = 0;
  int executions = 0;
  int inhibitions = 0;

 private:
  void fail(const std::string& here, const StepContext& ctx) const {
    if (here == callback && ctx.step() >= from && ctx.step() <= until) {
      throw std::runtime_error("faulty " + here);
    }
  }
};

double number_of(const std::string& text) {
  if (text == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (text == "inf") return std::numeric_limits<double>::infinity();
  if (text == "-inf") return -std::numeric_limits<double>::infinity();
  return std::stod(text);
}

/// Requests `level` and writes `value` to `out` (double), `out2` (vec2, as x) and `out3` (vec3,
/// as z), each given as text so that "nan", "inf" and "-inf" can be written; `from` is the first
/// step in which it writes.
class Odd : public Behaviour {
 public:
  void init(BehaviourInitContext& ctx) override {
    level = number_of(ctx.param<std::string>("level"));
    value = number_of(ctx.param<std::string>("value"));
    from = static_cast<std::uint64_t>(ctx.param<std::int64_t>("from"));
    out = ctx.output<double>("out");
    out2 = ctx.output<Vec2>("out2");
    out3 = ctx.output<Vec3>("out3");
  }
  double activation(const StepContext&) override { return level; }
  void execute(ExecuteContext& ctx) override {
    if (ctx.step() < from) return;
    ctx.write(out, value);
    ctx.write(out2, Vec2{value, 0.0});
    ctx.write(out3, Vec3{0.0, 0.0, value});
  }

  double level = 1.0;
  double value = 0.0;
  std::uint64_t from = 1;
  Output<double> out;
  Output<Vec2> out2;
  Output<Vec3> out3;
};

/// An interface that writes the step number to `out` in the input pass and throws from
/// `callback` (input or output) in steps [from, until], or from init.
class FaultyFeed : public Interface {
 public:
  void init(InitContext& ctx) override {
    callback = ctx.param<std::string>("callback");
    from = static_cast<std::uint64_t>(ctx.param<std::int64_t>("from"));
    until = static_cast<std::uint64_t>(ctx.param<std::int64_t>("until"));
    out = ctx.output<double>("out");
    if (callback == "init") throw 7;
  }
  void input(WriteContext& ctx) override {
    ++inputs;
    ctx.write(out, static_cast<double>(ctx.step()));
    if (callback == "input" && ctx.step() >= from && ctx.step() <= until) {
      throw std::runtime_error("feed input");
    }
  }
  void output(const StepContext& ctx) override {
    ++outputs;
    if (callback == "output" && ctx.step() >= from && ctx.step() <= until) throw 42;
  }

  std::string callback;
  std::uint64_t from = 1;
  std::uint64_t until = 0;
  Output<double> out;
  int inputs = 0;
  int outputs = 0;
};

/// A state that throws from `callback` (init, activate, execute or deactivate); it proceeds
/// after its first execution.
class FaultyState : public State {
 public:
  void init(StateInitContext& ctx) override {
    callback = ctx.param<std::string>("callback");
    if (callback == "init") throw std::runtime_error("faulty state init");
  }
  void activate(StateContext&) override { fail("activate"); }
  StateResult execute(StateContext&) override {
    fail("execute");
    return StateResult::kProceed;
  }
  void deactivate(StateContext&) override { fail("deactivate"); }

  std::string callback;

 private:
  void fail(const std::string& here) const {
    if (here == callback) throw std::runtime_error("faulty " + here);
  }
};

/// Controller hooks that throw from the one named `callback`.
class FaultyHooks : public ControllerHooks {
 public:
  explicit FaultyHooks(std::string callback) : callback_(std::move(callback)) {}
  bool pre_step(Controller&, Plan&) override { return fail("pre_step"); }
  void pre_activate(Controller&, std::string_view) override { fail("pre_activate"); }
  void pre_execute(Controller&, std::string_view) override { fail("pre_execute"); }
  bool post_execute(Controller&, std::string_view, StateResult) override {
    return fail("post_execute");
  }
  void post_step(Controller&) override { fail("post_step"); }
  void on_terminate(Controller&) override { fail("on_terminate"); }

 private:
  bool fail(const std::string& here) const {
    if (here == callback_) throw std::runtime_error("hook " + here);
    return false;
  }
  std::string callback_;
};

/// The test registry plus the classes above.
Registry make_registry() {
  Registry r = test::make_test_registry();
  r.set_origin("robustness_test");
  constexpr std::int64_t kForever = std::numeric_limits<std::int64_t>::max();
  auto& faulty = r.add_behaviour<Faulty>("robust.Faulty");
  faulty.param<std::string>("callback")
      .defaults_to(std::string("activation"))
      .one_of({"init", "update", "activation", "execute", "inhibited"});
  faulty.param<std::int64_t>("from").defaults_to(1);
  faulty.param<std::int64_t>("until").defaults_to(kForever);
  faulty.param<double>("level").defaults_to(1.0);
  faulty.param<double>("value").defaults_to(0.0);
  faulty.output<double>("out").make_optional();
  auto& odd = r.add_behaviour<Odd>("robust.Odd");
  odd.param<std::string>("level").defaults_to(std::string("1"));
  odd.param<std::string>("value").defaults_to(std::string("0"));
  odd.param<std::int64_t>("from").defaults_to(1);
  odd.output<double>("out").make_optional();
  odd.output<Vec2>("out2").make_optional();
  odd.output<Vec3>("out3").make_optional();
  auto& feed = r.add_interface<FaultyFeed>("robust.FaultyFeed");
  feed.param<std::string>("callback").defaults_to(std::string("input"));
  feed.param<std::int64_t>("from").defaults_to(1);
  feed.param<std::int64_t>("until").defaults_to(kForever);
  feed.output<double>("out").make_optional();
  auto& state = add_state_class<FaultyState>(r, "robust.FaultyState");
  state.param<std::string>("callback")
      .defaults_to(std::string("execute"))
      .one_of({"init", "activate", "execute", "deactivate"});
  return r;
}

const Registry& registry() {
  static const Registry instance = make_registry();
  return instance;
}

/// A logger whose lines ("error: ..." / "warning: ...") the test can read.
class Log {
 public:
  Log()
      : logger(std::make_shared<spdlog::logger>(
            "robustness", std::make_shared<spdlog::sinks::ostream_sink_st>(text_))) {
    logger->set_pattern("%l: %v");
    logger->set_level(spdlog::level::trace);
  }
  Log(const Log&) = delete;
  Log& operator=(const Log&) = delete;

  std::string text() const { return text_.str(); }
  std::size_t count(const std::string& needle) const {
    const std::string all = text_.str();
    std::size_t n = 0;
    for (auto at = all.find(needle); at != std::string::npos; at = all.find(needle, at + 1)) ++n;
    return n;
  }
  std::size_t lines() const { return count("\n"); }

  std::shared_ptr<spdlog::logger> logger;

 private:
  std::ostringstream text_;
};

Manager make(const std::string& yaml, Log& log) {
  return Manager(test::compile_text(yaml, registry()), log.logger);
}

template <typename T>
T& behaviour(const Manager& manager, const std::string& layer, const std::string& name) {
  return test::instance<T>(manager.program(), layer, name);
}

double actuator(const Manager& manager, const std::string& name) {
  return manager.actuator<double>(*manager.program().find_actuator(name));
}

bool written(const Manager& manager, const std::string& name) {
  return manager.actuator_written(*manager.program().find_actuator(name));
}

/// Collects the trace of every step as parsed JSON: a non-finite number would not parse.
class JsonTrace {
 public:
  explicit JsonTrace(Manager& manager) : writer_(out_) { manager.add_observer(writer_); }
  std::vector<nlohmann::json> records() const {
    std::vector<nlohmann::json> parsed;
    std::istringstream in(out_.str());
    std::string line;
    while (std::getline(in, line)) parsed.push_back(nlohmann::json::parse(line));
    return parsed;
  }

 private:
  std::ostringstream out_;
  TraceWriter writer_;
};

// --- config files --------------------------------------------------------------------------------

using test::read_text;
using test::write_text;

/// A fresh directory under the system's temporary one, removed at the end of the scope.
class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    path_ = fs::temp_directory_path() /
            ("arbiter_robustness_" + std::to_string(::getpid()) + "_" + std::to_string(++counter));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::permissions(path_, fs::perms::owner_all, fs::perm_options::add, ignored);
    for (const auto& entry : fs::recursive_directory_iterator(path_, ignored)) {
      fs::permissions(entry.path(), fs::perms::owner_all, fs::perm_options::add, ignored);
    }
    fs::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

/// Peak resident memory of this process so far, in MiB.
double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

struct Outcome {
  Diagnostics diagnostics;
  bool loaded = false;
};

/// The whole pipeline (read, plugins, validate, compile) on a file.
Outcome load_file(const fs::path& path, const LoadOptions& options = {}) {
  Registry fresh = make_registry();  // loading may add plugins to it
  Outcome outcome;
  outcome.loaded = load(path.string(), fresh, outcome.diagnostics, options).has_value();
  // Every message must be printable as text and as JSON (which needs valid UTF-8).
  if (outcome.diagnostics.error_count() > 0) CHECK_FALSE(format(outcome.diagnostics).empty());
  CHECK_NOTHROW(nlohmann::json::parse(format_json(outcome.diagnostics)));
  return outcome;
}

/// The codes of the errors reported, in order.
std::vector<std::string> error_codes(const Diagnostics& diagnostics) {
  std::vector<std::string> codes;
  for (const auto& item : diagnostics.items()) {
    if (item.severity == Severity::kError) codes.push_back(item.code);
  }
  return codes;
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

// --- hostile files -------------------------------------------------------------------------------

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

// --- on_exception ------------------------------------------------------------------------------

TEST_CASE("a throwing behaviour counts as inactive in that step and is reported once",
          "[robustness][faults]") {
  Log log;
  auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double}
    behaviours:
      broken: {type: robust.Faulty, params: {callback: activation, from: 2, until: 3, value: 9},
               ports: {out: speed}}
      fine: {type: test.Probe, params: {levels: 0.5, value: 1}, ports: {out: speed}}
    inhibitions: [broken -> fine]
)",
                      log);
  std::vector<double> broken_levels;
  std::vector<double> fine_levels;
  std::vector<double> speeds;
  for (int step = 0; step < 5; ++step) {
    manager.step();
    broken_levels.push_back(test::activation_of(manager, "l", "broken"));
    fine_levels.push_back(test::activation_of(manager, "l", "fine"));
    speeds.push_back(actuator(manager, "speed"));
  }
  CHECK(broken_levels == std::vector<double>{1, 0, 0, 1, 1});
  CHECK(fine_levels == std::vector<double>{0, 0.5, 0.5, 0, 0});
  CHECK(speeds == std::vector<double>{9, 1, 1, 9, 9});
  CHECK_FALSE(manager.stopped());
  INFO(log.text());
  CHECK(log.lines() == 1);
  CHECK(log.count("inline.yaml:8:7: behaviour 'broken' (robust.Faulty) threw from activation() "
                  "in step 2: faulty activation") == 1);
  CHECK(log.count("on_exception: inactive") == 1);
}

TEST_CASE("a throw from update() or execute() leaves no level and no write for that step",
          "[robustness][faults]") {
  Log log;
  auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      in_update: {type: robust.Faulty, params: {callback: update, from: 2, until: 2, value: 5},
                  ports: {out: speed}}
      in_execute: {type: robust.Faulty, params: {callback: execute, from: 3, until: 3, value: 7},
                   ports: {out: speed}}
      in_inhibited: {type: robust.Faulty, params: {callback: inhibited, level: 0}}
)",
                      log);
  auto& in_update = behaviour<Faulty>(manager, "l", "in_update");
  auto& in_inhibited = behaviour<Faulty>(manager, "l", "in_inhibited");
  manager.step();
  CHECK(actuator(manager, "speed") == 6.0);  // (5 + 7) / 2
  manager.step();
  // in_update threw from update(): not asked for a level, not executed, and back next step.
  CHECK(test::activation_of(manager, "l", "in_update") == 0.0);
  CHECK(in_update.activations == 1);
  CHECK(in_update.executions == 1);
  CHECK(actuator(manager, "speed") == 7.0);
  manager.step();
  // in_execute wrote 7, then threw: the write is dropped; its level stays as refined.
  CHECK(test::activation_of(manager, "l", "in_execute") == 1.0);
  CHECK(actuator(manager, "speed") == 5.0);
  CHECK(in_update.activations == 2);
  manager.step();
  CHECK(actuator(manager, "speed") == 6.0);
  CHECK(in_inhibited.inhibitions == 4);  // it throws every step: reported once, called on
  INFO(log.text());
  CHECK(log.count("threw from update() in step 2") == 1);
  CHECK(log.count("threw from execute() in step 3") == 1);
  CHECK(log.count("threw from inhibited() in step 1") == 1);
  CHECK(log.lines() == 3);
}

TEST_CASE("on_exception: disable takes a behaviour out for the rest of the run",
          "[robustness][faults]") {
  Log log;
  auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double}
    behaviours:
      broken: {type: robust.Faulty, params: {callback: execute, from: 2, until: 2, value: 9},
               ports: {out: speed}, on_exception: disable}
      fine: {type: test.Probe, params: {levels: 0.5, value: 1}, ports: {out: speed}}
    inhibitions: [broken -> fine]
)",
                      log);
  auto& broken = behaviour<Faulty>(manager, "l", "broken");
  manager.step();
  CHECK(actuator(manager, "speed") == 9.0);
  manager.step();  // broken writes 9 and throws: dropped; fine is still inhibited this step
  CHECK(actuator(manager, "speed") == 9.0);
  CHECK_FALSE(written(manager, "speed"));
  for (int step = 0; step < 3; ++step) manager.step();
  CHECK(test::activation_of(manager, "l", "broken") == 0.0);
  CHECK(manager.requested(*manager.program().find_behaviour("l", "broken")) == 0.0);
  CHECK(test::activation_of(manager, "l", "fine") == 0.5);
  CHECK(actuator(manager, "speed") == 1.0);
  CHECK(broken.updates == 2);
  CHECK(broken.activations == 2);
  CHECK(broken.executions == 2);
  CHECK(broken.inhibitions == 0);
  CHECK_FALSE(manager.stopped());
  INFO(log.text());
  CHECK(log.lines() == 1);
  CHECK(log.count("'broken' (robust.Faulty) threw from execute() in step 2: faulty execute; it "
                  "is disabled for the rest of the run (on_exception: disable)") == 1);
}

TEST_CASE("on_exception: stop completes the step, then the manager stops", "[robustness][faults]") {
  Log log;
  auto manager = make(R"(arbiter: 1
name: t
on_exception: stop
layers:
  - name: l
    actuators:
      speed: {type: double}
    behaviours:
      broken: {type: robust.Faulty, params: {callback: activation, from: 3, value: 9},
               ports: {out: speed}}
      fine: {type: test.Probe, params: {levels: 0.5, value: 1}, ports: {out: speed}}
    inhibitions: [broken -> fine]
)",
                      log);
  JsonTrace trace(manager);
  for (int step = 0; step < 10 && !manager.stopped(); ++step) manager.step();
  CHECK(manager.stopped());
  CHECK(manager.steps() == 3);
  // The step in which it threw ran to the end for everyone else, and was observed.
  CHECK(test::activation_of(manager, "l", "fine") == 0.5);
  CHECK(actuator(manager, "speed") == 1.0);
  const auto records = trace.records();
  REQUIRE(records.size() == 4);  // header and three steps
  CHECK(records[3]["layers"]["l"]["fine"]["active"] == true);
  CHECK_THAT(manager.stop_reason(),
             Catch::Matchers::Contains("inline.yaml:9:7: behaviour 'broken' (robust.Faulty) "
                                       "threw from activation() in step 3"));
  manager.step();
  CHECK(manager.steps() == 3);
  CHECK(behaviour<test::Probe>(manager, "l", "fine").events.size() == 6);  // 3 × update+execute
  INFO(log.text());
  CHECK(log.count("the manager stops after this step (on_exception: stop)") == 1);
}

TEST_CASE("a behaviour's on_exception overrides the config's", "[robustness][faults]") {
  Log log;
  auto manager = make(R"(arbiter: 1
name: t
on_exception: stop
layers:
  - name: l
    behaviours:
      tolerated: {type: robust.Faulty, on_exception: inactive}
      fine: {type: test.Probe}
)",
                      log);
  for (int step = 0; step < 3; ++step) manager.step();
  CHECK_FALSE(manager.stopped());
  CHECK(manager.steps() == 3);
  CHECK(test::activation_of(manager, "l", "fine") == 1.0);
  CHECK(manager.program().behaviours[0].on_exception == FaultPolicy::kInactive);
}

TEST_CASE("an interface that throws loses that pass's writes and follows the policy",
          "[robustness][faults]") {
  const std::string config = R"(arbiter: 1
name: t
on_exception: POLICY
layers:
  - name: world
    interface: robust.FaultyFeed
    params: {callback: input, from: 2, until: 2}
    ports: {out: ticks}
    actuators:
      ticks: {type: double}
  - name: l
    sensors: [ticks]
    behaviours:
      fine: test.Probe
)";
  const auto with = [&](const std::string& policy) {
    std::string text = config;
    text.replace(text.find("POLICY"), 6, policy);
    return text;
  };
  SECTION("inactive") {
    Log log;
    auto manager = make(with("inactive"), log);
    std::vector<double> ticks;
    std::vector<bool> fresh;
    for (int step = 0; step < 3; ++step) {
      manager.step();
      ticks.push_back(actuator(manager, "ticks"));
      fresh.push_back(written(manager, "ticks"));
    }
    CHECK(ticks == std::vector<double>{1, 1, 3});
    CHECK(fresh == std::vector<bool>{true, false, true});
    INFO(log.text());
    CHECK(log.count("inline.yaml:5:11: interface of layer 'world' (robust.FaultyFeed) threw "
                    "from input() in step 2: feed input") == 1);
  }
  SECTION("disable") {
    Log log;
    auto manager = make(with("disable"), log);
    for (int step = 0; step < 4; ++step) manager.step();
    const auto& program = manager.program();
    const auto& feed = dynamic_cast<const FaultyFeed&>(*program.layers[0].interface);
    CHECK(feed.inputs == 2);
    CHECK(feed.outputs == 1);
    CHECK(actuator(manager, "ticks") == 1.0);
    CHECK_FALSE(written(manager, "ticks"));
  }
  SECTION("stop") {
    Log log;
    auto manager = make(with("stop"), log);
    for (int step = 0; step < 4 && !manager.stopped(); ++step) manager.step();
    CHECK(manager.stopped());
    CHECK(manager.steps() == 2);
  }
  SECTION("a throw of something that is not an exception") {
    Log log;
    std::string text = with("inactive");
    text.replace(text.find("callback: input"), 15, "callback: output");
    auto manager = make(text, log);
    for (int step = 0; step < 3; ++step) manager.step();
    INFO(log.text());
    CHECK(log.count("threw from output() in step 2: unknown exception") == 1);
  }
}

TEST_CASE("a throwing state stops its controller and, under a config-wide stop, the manager",
          "[robustness][faults][scl]") {
  const std::string config = R"(arbiter: 1
name: t
POLICY
layers:
  - name: l
    behaviours:
      fine: test.Probe
state_machines:
  plan:
    states:
      boom: {type: test.Planner, params: {op: throw, hold: 2}}
    queue: [boom]
)";
  for (const std::string policy : {"on_exception: inactive", "on_exception: stop"}) {
    DYNAMIC_SECTION(policy) {
      std::string text = config;
      text.replace(text.find("POLICY"), 6, policy);
      Log log;
      auto manager = make(text, log);
      for (int step = 0; step < 5 && !manager.stopped(); ++step) manager.step();
      const Controller* plan = manager.program().find_controller("plan");
      CHECK(plan->status() == ControllerStatus::kError);
      CHECK_THAT(plan->error(), Catch::Matchers::Contains("state failure"));
      if (policy == "on_exception: inactive") {
        CHECK_FALSE(manager.stopped());
        CHECK(manager.steps() == 5);
      } else {
        CHECK(manager.stopped());
        CHECK(manager.steps() == 2);
        CHECK_THAT(manager.stop_reason(),
                   Catch::Matchers::Contains("state machine 'plan' stopped with an error"));
      }
      CHECK(test::activation_of(manager, "l", "fine") == 1.0);
    }
  }
}

TEST_CASE("a state that throws from any callback stops its controller, reported once",
          "[robustness][faults][scl]") {
  const std::string config = R"(arbiter: 1
name: t
on_exception: POLICY
layers:
  - name: l
    behaviours:
      fine: test.Probe
state_machines:
  plan:
    states:
      boom: {type: robust.FaultyState, params: {callback: CALLBACK}}
      after: test.Planner
    queue: [boom, after]
)";
  // The step in which each callback first runs: boom is activated and executed in step 1 and,
  // having asked to proceed, deactivated in step 2.
  const std::map<std::string, std::uint64_t> first_call = {
      {"activate", 1}, {"execute", 1}, {"deactivate", 2}};
  for (const auto& [callback, step] : first_call) {
    for (const std::string policy : {"inactive", "stop"}) {
      DYNAMIC_SECTION(callback << ", on_exception: " << policy) {
        std::string text = config;
        text.replace(text.find("POLICY"), 6, policy);
        text.replace(text.find("CALLBACK"), 8, callback);
        Log log;
        auto manager = make(text, log);
        JsonTrace trace(manager);
        for (int i = 0; i < 5 && !manager.stopped(); ++i) manager.step();
        const Controller* plan = manager.program().find_controller("plan");
        CHECK(plan->status() == ControllerStatus::kError);
        const std::string error =
            "controller 'plan' (inline.yaml:9:3), state 'boom' "
            "(inline.yaml:11:7): a state threw: faulty " +
            callback;
        CHECK(plan->error() == error);
        INFO(log.text());
        CHECK(log.count(error + "; the controller stops with status error") == 1);
        CHECK(test::activation_of(manager, "l", "fine") == 1.0);
        const auto records = trace.records();
        REQUIRE(records.size() >= 2);
        CHECK(records.back()["controllers"]["plan"]["status"] == "error");
        CHECK(records.back()["layers"]["l"]["fine"]["active"] == true);
        if (policy == "inactive") {
          CHECK_FALSE(manager.stopped());
          CHECK(manager.steps() == 5);
          CHECK(log.lines() == 1);
        } else {
          CHECK(manager.stopped());
          CHECK(manager.steps() == step);
          CHECK_THAT(
              manager.stop_reason(),
              Catch::Matchers::StartsWith("state machine 'plan' stopped with an error: " + error));
        }
      }
    }
  }
}

TEST_CASE("a controller hook that throws stops that controller only", "[robustness][faults][scl]") {
  for (const std::string hook :
       {"pre_step", "pre_activate", "pre_execute", "post_execute", "post_step", "on_terminate"}) {
    DYNAMIC_SECTION(hook) {
      FaultyHooks hooks(hook);  // outlives the manager, as set_hooks asks
      Log log;
      auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    behaviours:
      fine: test.Probe
state_machines:
  plan:
    states:
      once: test.Planner
    queue: [once]
  other:
    states:
      again: {type: test.Planner, params: {hold: 100}}
    queue: [again]
)",
                          log);
      manager.program().controllers[0]->set_hooks(&hooks);
      for (int step = 0; step < 4; ++step) manager.step();
      const Controller* plan = manager.program().find_controller("plan");
      const Controller* other = manager.program().find_controller("other");
      CHECK(plan->status() == ControllerStatus::kError);
      CHECK_THAT(plan->error(),
                 Catch::Matchers::StartsWith("controller 'plan' (inline.yaml:8:3)") &&
                     Catch::Matchers::EndsWith("hook " + hook));
      CHECK(other->status() == ControllerStatus::kRunning);
      CHECK(other->cycle() == 4);
      CHECK_FALSE(manager.stopped());
      CHECK(test::activation_of(manager, "l", "fine") == 1.0);
      INFO(log.text());
      CHECK(log.lines() == 1);
    }
  }
}

TEST_CASE("a class that throws from init() is a load error at its declaration",
          "[robustness][faults][config]") {
  const auto errors = [](const std::string& config) {
    std::vector<std::string> lines;
    const Diagnostics diagnostics = test::diagnose_text(config, registry());
    for (const auto& item : diagnostics.items()) {
      CHECK(item.code == "init-failed");
      const std::string text = format(item);
      lines.push_back(text.substr(0, text.find('\n')));
    }
    return lines;
  };
  CHECK(errors(R"(arbiter: 1
name: t
layers:
  - name: world
    interface: robust.FaultyFeed
    params: {callback: init}
  - name: l
    behaviours:
      broken: {type: robust.Faulty, params: {callback: init}}
      fine: test.Probe
)") == std::vector<std::string>{"inline.yaml:4:11: error: class robust.FaultyFeed failed to "
                                "initialise (unknown exception)",
                                "inline.yaml:9:7: error: class robust.Faulty failed to "
                                "initialise: faulty init"});
  // Every object of the state's pool (capacity 4) is initialised alike: one error, not four.
  const auto state_errors = errors(R"(arbiter: 1
name: t
state_machines:
  plan:
    capacity: 4
    states:
      boom: {type: robust.FaultyState, params: {callback: init}}
    queue: [boom]
)");
  CHECK(state_errors == std::vector<std::string>{"inline.yaml:7:7: error: class "
                                                 "robust.FaultyState failed to initialise: "
                                                 "faulty state init"});
}

TEST_CASE("on_exception is checked like any other key", "[robustness][faults][config]") {
  const auto codes = [](const std::string& text) {
    return error_codes(test::diagnose_text(text, registry()));
  };
  CHECK(codes("arbiter: 1\nname: t\non_exception: abort\n") ==
        std::vector<std::string>{"out-of-range"});
  const auto diagnostics =
      test::diagnose_text("arbiter: 1\nname: t\non_exception: disabled\n", registry());
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].message ==
        "'on_exception' must be inactive, disable or stop, found the string 'disabled'");
  CHECK(diagnostics.items()[0].notes ==
        std::vector<std::string>{"did you mean 'disable'? allowed: disable, inactive, stop"});
  CHECK(codes("arbiter: 1\nname: t\non_exception: [stop]\n") ==
        std::vector<std::string>{"wrong-type"});
  CHECK(codes("arbiter: 1\nname: t\nlayers:\n  - name: l\n    behaviours:\n      b: {type: "
              "scripted, on_exception: 1}\n") == std::vector<std::string>{"out-of-range"});
  CHECK(codes("arbiter: 1\nname: t\nlayers:\n  - name: l\n    behaviours:\n      b: {type: "
              "scripted, on_exception: stop}\n")
            .empty());
  TempDir dir;
  write_text(dir / "part.yaml", "arbiter: 1\non_exception: stop\n");
  write_text(dir / "main.yaml", "arbiter: 1\nname: t\ninclude: [part.yaml]\n");
  const Outcome outcome = load_file(dir / "main.yaml");
  CHECK(error_codes(outcome.diagnostics) == std::vector<std::string>{"unknown-key"});
}

// --- non-finite numbers
// ---------------------------------------------------------------------------

TEST_CASE("non-finite activation levels count as 0 or 1 and are reported once",
          "[robustness][levels]") {
  Log log;
  auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    behaviours:
      nan: {type: robust.Odd, params: {level: nan}}
      high: {type: robust.Odd, params: {level: inf}}
      low: {type: robust.Odd, params: {level: -inf}}
      fine: {type: test.Probe, params: {levels: 0.5}}
)",
                      log);
  for (int step = 0; step < 4; ++step) manager.step();
  CHECK(test::activation_of(manager, "l", "nan") == 0.0);
  CHECK(test::activation_of(manager, "l", "high") == 1.0);
  CHECK(test::activation_of(manager, "l", "low") == 0.0);
  CHECK(test::activation_of(manager, "l", "fine") == 0.5);
  INFO(log.text());
  CHECK(log.lines() == 3);
  CHECK(log.count("inline.yaml:6:7: behaviour 'nan' requested a NaN activation level; it counts "
                  "as 0") == 1);
  CHECK(log.count("behaviour 'high' requested an infinite activation level; it counts as 1") == 1);
  CHECK(log.count("behaviour 'low' requested a negative infinite activation level; it counts as "
                  "0") == 1);
}

TEST_CASE("non-finite values written to actuators are ignored and reported once",
          "[robustness][actuators]") {
  for (const std::string value : {"nan", "inf", "-inf"}) {
    DYNAMIC_SECTION(value) {
      Log log;
      auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double, default: 2}
      mean: {type: double, aggregate: true}
      walk: {type: vec2}
      turn: {type: vec3, aggregate: true}
    behaviours:
      odd: {type: robust.Odd, params: {value: )" +
                              value + R"(, from: 2},
            ports: {out: speed, out2: walk, out3: turn}}
      odd_too: {type: robust.Odd, params: {value: )" +
                              value + R"(}, ports: {out: mean}}
      fine: {type: test.Probe, params: {value: 4}, ports: {out: mean}}
)",
                          log);
      JsonTrace trace(manager);
      for (int step = 0; step < 3; ++step) manager.step();
      CHECK(actuator(manager, "speed") == 2.0);  // its default: never written
      CHECK_FALSE(written(manager, "speed"));
      CHECK(actuator(manager, "mean") == 4.0);  // fine's alone, not a NaN mean
      CHECK(written(manager, "mean"));
      CHECK(manager.actuator<Vec2>(*manager.program().find_actuator("walk")) == Vec2{});
      CHECK(manager.actuator<Vec3>(*manager.program().find_actuator("turn")) == Vec3{});
      CHECK(trace.records().size() == 4);  // every record parses: no NaN in the trace
      INFO(log.text());
      CHECK(log.lines() == 4);  // one per writer and actuator
      CHECK(log.count("inline.yaml:11:7: behaviour 'odd' (robust.Odd) wrote a non-finite value "
                      "(NaN or infinity) to actuator 'speed' in step 2; such writes are ignored") ==
            1);
      CHECK(log.count("to actuator 'walk' in step 2") == 1);
      CHECK(log.count("to actuator 'turn' in step 2") == 1);
      CHECK(log.count("behaviour 'odd_too' (robust.Odd) wrote a non-finite value (NaN or "
                      "infinity) to actuator 'mean' in step 1") == 1);
    }
  }
}

TEST_CASE("a behaviour that fails every way at once leaves the others and the trace intact",
          "[robustness][faults]") {
  // The same config with and without the faulty behaviours gives the same records for the rest.
  const std::string base = R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      a: {type: test.Probe, params: {levels: [1, 0, 0.5], value: 1}, ports: {out: speed}}
      b: {type: test.Probe, params: {levels: 0.5, value: 3}, ports: {out: speed}}
)";
  const std::string faulty =
      base + R"(      t1: {type: robust.Faulty, params: {callback: update, level: 0}}
      t2: {type: robust.Faulty, params: {callback: execute, level: 0.000001}, ports: {out: speed}}
      t3: {type: robust.Odd, params: {level: nan, value: nan}, ports: {out: speed}}
      t4: {type: test.Thrower, on_exception: disable}
)";
  const auto records_of = [](const std::string& text) {
    Log log;
    auto manager = make(text, log);
    JsonTrace trace(manager);
    std::vector<double> speeds;
    for (int step = 0; step < 6; ++step) {
      manager.step();
      speeds.push_back(actuator(manager, "speed"));
    }
    auto records = trace.records();
    for (auto& record : records) {
      if (!record.contains("step")) continue;
      for (const auto* name : {"t1", "t2", "t3", "t4"}) record["layers"]["l"].erase(name);
    }
    return std::make_pair(records, speeds);
  };
  const auto [plain_records, plain_speeds] = records_of(base);
  const auto [faulty_records, faulty_speeds] = records_of(faulty);
  REQUIRE(plain_records.size() == faulty_records.size());
  for (std::size_t i = 1; i < plain_records.size(); ++i) {
    CHECK(plain_records[i]["layers"] == faulty_records[i]["layers"]);
  }
  CHECK(plain_speeds == faulty_speeds);
}

// --- safe values ---------------------------------------------------------------------------------

namespace {

const std::string kSafeConfig = R"(arbiter: 1
name: t
on_exception: POLICY
layers:
  - name: control
    actuators:
      speed: {type: double, safe: -1}
      heading: {type: double}
    behaviours:
      drive: {type: test.Probe, params: {levels: 1, value: 5}, ports: {out: speed}}
      broken: {type: robust.Faulty, params: {callback: execute, from: 3, value: 2},
               ports: {out: heading}}
  - name: world
    interface: test.Feed
    ports: {out: measured, in: speed}
    actuators:
      measured: {type: double}
    sensors: [speed]
)";

std::string safe_config(const std::string& policy) {
  std::string text = kSafeConfig;
  text.replace(text.find("POLICY"), 6, policy);
  return text;
}

/// A clock that advances by a fixed amount at each reading.
class ManualClock : public StepClock {
 public:
  double now() override {
    const double t = time;
    time += tick;
    return t;
  }
  double time = 0.0;
  double tick = 0.25;
};

}  // namespace

TEST_CASE("the safe pass outputs every safe value, written, and the run resumes after it",
          "[robustness][safe]") {
  Log log;
  auto manager = make(safe_config("inactive"), log);
  JsonTrace trace(manager);
  manager.safe_pass();  // before the first step: nothing has been output, nothing to make safe
  CHECK(manager.safe_passes() == 0);
  manager.step();
  manager.step();
  auto& world = *static_cast<test::Feed*>(manager.program().layers[1].interface.get());
  CHECK(world.seen == std::vector<double>{5.0, 5.0});
  manager.safe_pass();  // as when the live page pauses the run
  CHECK(world.seen == std::vector<double>{5.0, 5.0, -1.0});
  CHECK(manager.steps() == 2);
  CHECK(actuator(manager, "speed") == -1.0);
  CHECK(written(manager, "speed"));
  CHECK_FALSE(written(manager, "heading"));  // no safe value: kept, unwritten
  manager.step();                            // resumes: the behaviours write again
  CHECK(world.seen == std::vector<double>{5.0, 5.0, -1.0, 5.0});
  CHECK(manager.steps() == 3);
  const auto records = trace.records();
  REQUIRE(records.size() == 5);  // header, two steps, the safe pass, a step
  CHECK(records[3]["step"] == 2);
  CHECK(records[3]["safe"] == true);
  CHECK(records[3]["actuators"]["speed"]["value"] == -1.0);
  CHECK(records[3]["actuators"]["speed"]["written"] == true);
  CHECK(records[3]["actuators"]["heading"]["written"] == false);
  CHECK_FALSE(records[2].contains("safe"));
  CHECK(records[4]["step"] == 3);
  CHECK_FALSE(records[4].contains("safe"));
}

TEST_CASE("a manager stopped by on_exception: stop outputs its safe values when finished",
          "[robustness][safe]") {
  Log log;
  auto manager = make(safe_config("stop"), log);
  JsonTrace trace(manager);
  for (int step = 0; step < 10 && !manager.stopped(); ++step) manager.step();
  REQUIRE(manager.stopped());
  manager.finish();
  auto& world = *static_cast<test::Feed*>(manager.program().layers[1].interface.get());
  CHECK(world.seen == std::vector<double>{5.0, 5.0, 5.0, -1.0});
  CHECK(manager.safe_passes() == 1);
  const auto records = trace.records();
  REQUIRE(records.size() == 5);
  CHECK(records.back()["safe"] == true);
  CHECK(records.back()["step"] == 3);
}

TEST_CASE("a config without safe values has no safe pass", "[robustness][safe]") {
  Log log;
  std::string text = safe_config("inactive");
  text.replace(text.find(", safe: -1"), 10, "");
  auto manager = make(text, log);
  JsonTrace trace(manager);
  manager.step();
  manager.finish();
  CHECK(manager.safe_passes() == 0);
  CHECK(trace.records().size() == 2);
}

TEST_CASE("a safe value must fit its actuator's type", "[robustness][safe][config]") {
  const auto diagnostics = test::diagnose_text(R"(arbiter: 1
name: t
layers:
  - name: control
    actuators:
      gait: {type: vec3, safe: [0, 0]}
)",
                                               registry());
  CHECK_THAT(format(diagnostics),
             Catch::Matchers::Contains(
                 "inline.yaml:6:32: error: safe value of actuator 'gait' must be a list of 3 "
                 "finite numbers (vec3), found a list of 2 items"));
}

TEST_CASE("a manager with a clock times every step and the safe pass in its records",
          "[robustness][safe][timing]") {
  Log log;
  auto manager = make(safe_config("inactive"), log);
  ManualClock clock;
  manager.set_clock(&clock);
  JsonTrace trace(manager);
  manager.step();
  manager.step();
  manager.finish();
  const auto records = trace.records();
  REQUIRE(records.size() == 4);
  // Each step reads the clock at its start and its end: 0.25 s per reading.
  CHECK(records[1]["t"] == 0.0);
  CHECK(records[1]["duration"] == 0.25);
  CHECK(records[2]["t"] == 0.5);
  CHECK(records[2]["duration"] == 0.25);
  CHECK(records[3]["t"] == 1.0);
  CHECK(records[3]["safe"] == true);
}

#pragma once
// Shared by the test binaries: classes that expose the engine's semantics, and helpers that
// compile a config written inline.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "arbiter/controller.hpp"
#include "arbiter/init_context.hpp"
#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/program.hpp"
#include "arbiter/registry.hpp"
#include "arbiter/trace_reader.hpp"

namespace arbiter::test {

/// Requests `levels[step-1]` (last held; any finite number, so clamping can be tested) and writes
/// `value` to its `out` port while active (with `overwrite`, after first writing 1000). Records
/// every value its `in` port read in execute() or inhibited(), and the callbacks it saw.
class Probe : public Behaviour {
 public:
  double activation(const StepContext& ctx) override;
  void update(const StepContext& ctx) override;
  void execute(ExecuteContext& ctx) override;
  void inhibited(const InhibitedContext& ctx) override;

  std::vector<double> levels;
  double value = 0.0;
  bool overwrite = false;
  bool record = true;  ///< false keeps the probe allocation-free
  Input<double> in;
  Output<double> out;
  std::vector<double> seen;         ///< value of `in` each step
  std::vector<bool> seen_written;   ///< its written flag each step
  std::vector<std::string> events;  ///< "update 1", "execute 1 just_activated", ...
};

/// Always requests NaN.
class NanLevel : public Behaviour {
 public:
  double activation(const StepContext&) override;
};

/// Always throws from activation().
class Thrower : public Behaviour {
 public:
  double activation(const StepContext&) override;
};

/// An interface class: the input pass writes `step * 10` to `out`; the output pass records `in`.
class Feed : public Interface {
 public:
  void input(WriteContext& ctx) override;
  void output(const StepContext& ctx) override;

  Output<double> out;
  Input<double> in;
  std::vector<double> seen;
};

/// A state that edits the plan in the execution where it proceeds (after `hold` executions):
/// `op` is one of none, append, prepend, go_to, insert_before, insert_after, remove, clear,
/// terminate_in_activate, terminate_in_execute, throw; `target` names the state (for remove:
/// the index as text), `x` is passed as the target's param `x`.
class Planner : public State {
 public:
  void init(StateInitContext& ctx) override;
  void activate(StateContext& ctx) override;
  StateResult execute(StateContext& ctx) override;

  StateParam<std::string> op_param;
  StateParam<std::string> target_param;
  StateParam<std::int64_t> hold_param;
  StateParam<double> x;
  std::string op;  ///< the state's own values of the params above
  std::string target;
  std::int64_t hold = 1;
  PlannedStateRef<double> with_x;  ///< target, when x is set on the state
  PlannedStateRef<> plain;         ///< target, otherwise
};

/// A state with a param `x` (default 0) that records the x of each activation in `seen_x`.
class Pose : public State {
 public:
  void activate(StateContext& ctx) override;
  StateResult execute(StateContext& ctx) override;
  static std::vector<double>& seen_x();
  StateParam<double> x;
};

/// State `name` of `controller`, planned without params (as a hook plans); throws when there is
/// no such state, so that a misspelt test fails at the name.
PlannedState planned(const Controller& controller, std::string_view name);

/// Collects each step's controller events as "cycle N: activate a, execute a".
class ControllerLog : public Observer {
 public:
  explicit ControllerLog(std::string controller) : controller_(std::move(controller)) {}
  void on_step(const Manager& manager) override;
  std::vector<std::string> lines;

 private:
  std::string controller_;
};

/// The built-ins plus test.Probe, test.NanLevel, test.Thrower, test.Feed (behaviours and an
/// interface) and the states test.Planner and test.Pose.
Registry make_test_registry();

/// A file's bytes ("" when it cannot be read), and writing them.
std::string read_text(const std::filesystem::path& path);
void write_text(const std::filesystem::path& path, const std::string& text);

/// How far files_in() looks: `dir` itself, or its subfolders too.
enum class Walk { kTop, kRecursive };

/// The regular files in `dir` that `keep` accepts, sorted. Throws when there is none: a test that
/// checks each file of a folder must not pass, checking nothing, when the folder is empty, gone or
/// its files renamed.
std::vector<std::filesystem::path> files_in(
    const std::filesystem::path& dir, const std::function<bool(const std::filesystem::path&)>& keep,
    Walk walk = Walk::kTop);

/// True when ARBITER_UPDATE_GOLDEN=1: golden-file tests rewrite their expected files.
bool update_golden();

struct CliResult {
  int exit_code = -1;
  bool signalled = false;  ///< killed by a signal (or the shell reported one)
  std::string out;
  std::string err;
};

/// Runs `command` (a shell command line, already quoted) with stdin from /dev/null, capturing
/// its stdout and stderr.
CliResult run_captured(const std::string& command);

/// Adds test.Tuned (a behaviour) and test.Wait (a state), whose params exercise every param check
/// (required, ranged, restricted to choices): the classes the configs of tests/data/invalid use.
void add_param_check_classes(Registry& registry);

/// Makes `dir` the working directory for the scope, so that diagnostics and outputs show relative
/// paths.
class WorkingDirectory {
 public:
  explicit WorkingDirectory(const std::filesystem::path& dir)
      : previous_(std::filesystem::current_path()) {
    std::filesystem::current_path(dir);
  }
  ~WorkingDirectory() { std::filesystem::current_path(previous_); }
  WorkingDirectory(const WorkingDirectory&) = delete;
  WorkingDirectory& operator=(const WorkingDirectory&) = delete;

 private:
  std::filesystem::path previous_;
};

/// A fresh directory under the system's temporary one, removed with everything in it at the end
/// of the scope (even what a test made unreadable).
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  /// Writes `text` to `name` in the directory; returns the file's path.
  std::string write(const std::string& name, const std::string& text) const;

 private:
  std::filesystem::path path_;
};

/// A config named `t` of one layer named `l`, whose keys (`actuators:`, `behaviours:`, ...,
/// indented by four spaces) are `layer`, with the top-level keys `top` (each a line) before
/// `layers:`. A line break that `layer` starts with is dropped, so that a raw string can start on
/// the line after its `R"(`; the layer's first key is then on line 5 (more with `top`).
std::string one_layer(const std::string& layer, const std::string& top = "");

/// Load options with the lint step, as `arbiter validate` loads: for the tests of what a user sees.
LoadOptions with_lints();

/// Parses, validates and compiles `text` (YAML, or JSON when `file` ends in .json). Throws
/// ConfigError with every diagnostic when it is invalid.
Program compile_text(const std::string& text, const Registry& registry,
                     const std::string& file = "inline.yaml");

/// The diagnostics of a config that is expected to be invalid (or to warn).
Diagnostics diagnose_text(const std::string& text, const Registry& registry,
                          const std::string& file = "inline.yaml");

/// A behaviour instance of the compiled program, by layer and name.
template <typename T>
T& instance(const Program& program, const std::string& layer, const std::string& name) {
  const auto index = program.find_behaviour(layer, name);
  if (!index) throw std::runtime_error("no behaviour " + layer + "/" + name);
  return dynamic_cast<T&>(*program.behaviours[*index].instance);
}

/// The trace or recording at `path`, read whole; one that cannot be read fails the test with the
/// reader's error.
Trace read_whole_trace(const std::string& path);

/// Steps `manager` `steps` times and finishes it; returns the trace it wrote (JSON lines).
std::string run_traced(Manager& manager, int steps);

/// The activation level of `layer/name` after the manager's last step.
double activation_of(const Manager& manager, const std::string& layer, const std::string& name);

}  // namespace arbiter::test

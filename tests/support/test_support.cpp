#include "test_support.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "arbiter/lint.hpp"
#include "arbiter/trace.hpp"
#include "builtins.hpp"
#include "core/compile/controller_builder.hpp"

namespace arbiter::test {

double Probe::activation(const StepContext& ctx) {
  const auto index = static_cast<std::size_t>(ctx.step() - 1);
  return levels[std::min(index, levels.size() - 1)];
}

void Probe::update(const StepContext& ctx) {
  if (!record) return;
  events.push_back("update " + std::to_string(ctx.step()));
}

void Probe::execute(ExecuteContext& ctx) {
  if (overwrite) ctx.write(out, 1000.0);
  ctx.write(out, value);
  if (!record) return;
  events.push_back("execute " + std::to_string(ctx.step()) +
                   (ctx.just_activated() ? " just_activated" : ""));
  seen.push_back(ctx.read(in));
  seen_written.push_back(ctx.written(in));
}

void Probe::inhibited(const InhibitedContext& ctx) {
  if (!record) return;
  events.push_back("inhibited " + std::to_string(ctx.step()) +
                   (ctx.just_deactivated() ? " just_deactivated" : ""));
  seen.push_back(ctx.read(in));
  seen_written.push_back(ctx.written(in));
}

double NanLevel::activation(const StepContext&) {
  return std::nan("");
}

double Thrower::activation(const StepContext&) {
  throw std::runtime_error("sensor unplugged");
}

void Feed::input(WriteContext& ctx) {
  ctx.write(out, static_cast<double>(ctx.step()) * 10.0);
}

void Feed::output(const StepContext& ctx) {
  if (in.bound()) seen.push_back(ctx.read(in));
}

void Planner::init(StateInitContext& ctx) {
  // The state's own values: a planned instance's are not known before its step.
  op = ctx.param(op_param);
  target = ctx.param(target_param);
  hold = ctx.param(hold_param);
  if (op != "append" && op != "prepend" && op != "go_to" && op != "insert_before" &&
      op != "insert_after") {
    return;
  }
  // x is passed only when set, so that targets without an x param can be planned too.
  if (ctx.param(x) != 0.0) {
    with_x = ctx.plan_state<double>(target, {"x"}, ctx.param_location(&Planner::target_param));
  } else {
    plain = ctx.plan_state<>(target, {}, ctx.param_location(&Planner::target_param));
  }
}

void Planner::activate(StateContext& ctx) {
  if (op == "terminate_in_activate") ctx.terminate();
}

StateResult Planner::execute(StateContext& ctx) {
  if (static_cast<std::int64_t>(ctx.executions()) + 1 < hold) return StateResult::kHold;
  auto& plan = ctx.plan();
  const auto edit = [&](const auto& state, const auto&... args) {
    if (op == "append") plan.append(state, args...);
    if (op == "prepend") plan.prepend(state, args...);
    if (op == "go_to") plan.go_to(state, args...);
    if (op == "insert_before") plan.insert_before(1, state, args...);
    if (op == "insert_after") plan.insert_after(0, state, args...);
  };
  if (with_x.bound()) {
    edit(with_x, ctx.param(x));
  } else if (plain.bound()) {
    edit(plain);
  }
  if (op == "remove") plan.remove(static_cast<std::size_t>(std::stoul(target)));
  if (op == "clear") plan.clear();
  if (op == "terminate_in_execute") ctx.terminate();
  if (op == "throw") throw std::runtime_error("state failure");
  return StateResult::kProceed;
}

void Pose::activate(StateContext& ctx) {
  seen_x().push_back(ctx.param(x));
}

StateResult Pose::execute(StateContext&) {
  return StateResult::kProceed;
}

std::vector<double>& Pose::seen_x() {
  static std::vector<double> values;
  return values;
}

PlannedState planned(const Controller& controller, std::string_view name) {
  const auto state = find_state(controller, name);
  if (!state) {
    throw std::runtime_error("state machine '" + controller.name() + "' has no state '" +
                             std::string(name) + "'");
  }
  PlannedState out;
  out.state = *state;
  return out;
}

void ControllerLog::on_step(const Manager& manager) {
  const Controller* controller = manager.program().find_controller(controller_);
  std::string line = "cycle " + std::to_string(controller->cycle()) + ":";
  for (std::size_t e = 0; e < controller->event_count(); ++e) {
    line += (e == 0 ? " " : ", ") + event_text(*controller, controller->events()[e]);
  }
  if (controller->status() != ControllerStatus::kRunning) {
    line += std::string(" [") + to_string(controller->status()) + "]";
  }
  lines.push_back(line);
}

Registry make_test_registry() {
  Registry registry;
  register_builtin_behaviours(registry);
  registry.set_origin("tests");
  auto& probe = registry.add_behaviour<Probe>("test.Probe");
  probe.param("levels", &Probe::levels).defaults_to(std::vector<double>{1.0});
  probe.param("value", &Probe::value).defaults_to(0.0);
  probe.param("overwrite", &Probe::overwrite).defaults_to(false);
  probe.param("record", &Probe::record).defaults_to(true);
  probe.port("in", &Probe::in).make_optional();
  probe.port("out", &Probe::out).make_optional();
  registry.add_behaviour<NanLevel>("test.NanLevel");
  registry.add_behaviour<Thrower>("test.Thrower");
  auto& feed = registry.add_interface<Feed>("test.Feed");
  feed.port("out", &Feed::out).make_optional();
  feed.port("in", &Feed::in).make_optional();
  // Planner reads the state's own values of its per-instance params in init().
  auto& planner = add_state_class<Planner>(registry, "test.Planner");
  planner.param("op", &Planner::op_param).defaults_to(std::string("none"));
  planner.param("target", &Planner::target_param).defaults_to(std::string());
  planner.param("hold", &Planner::hold_param).defaults_to(1).at_least(1);
  planner.param("x", &Planner::x).defaults_to(0.0);
  auto& pose = add_state_class<Pose>(registry, "test.Pose");
  pose.param("x", &Pose::x).range(-10.0, 10.0);
  return registry;
}

std::string one_layer(const std::string& layer, const std::string& top) {
  const bool line_break = !layer.empty() && layer.front() == '\n';
  return "arbiter: 1\nname: t\n" + top + "layers:\n  - name: l\n" +
         layer.substr(line_break ? 1 : 0);
}

LoadOptions with_lints() {
  LoadOptions options;
  options.lint = lint;
  return options;
}

std::vector<std::filesystem::path> files_in(
    const std::filesystem::path& dir, const std::function<bool(const std::filesystem::path&)>& keep,
    Walk walk) {
  std::vector<std::filesystem::path> files;
  const auto visit = [&](const std::filesystem::directory_entry& entry) {
    if (entry.is_regular_file() && keep(entry.path())) files.push_back(entry.path());
  };
  if (walk == Walk::kRecursive) {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) visit(entry);
  } else {
    for (const auto& entry : std::filesystem::directory_iterator(dir)) visit(entry);
  }
  if (files.empty()) throw std::runtime_error("no file to test in " + dir.string());
  std::sort(files.begin(), files.end());
  return files;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

bool update_golden() {
  const char* value = std::getenv("ARBITER_UPDATE_GOLDEN");
  return value != nullptr && std::string(value) == "1";
}

CliResult run_captured(const std::string& command) {
  const std::filesystem::path base =
      std::filesystem::temp_directory_path() / ("arbiter_test_" + std::to_string(::getpid()));
  const std::string out_path = base.string() + ".out";
  const std::string err_path = base.string() + ".err";
  const std::string line =
      "{ " + command + "; } >\"" + out_path + "\" 2>\"" + err_path + "\" </dev/null";
  const int status = std::system(line.c_str());
  CliResult result;
  result.signalled = WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) > 125);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = read_text(out_path);
  result.err = read_text(err_path);
  std::filesystem::remove(out_path);
  std::filesystem::remove(err_path);
  return result;
}

namespace {

/// Requests nothing; it exists for its params.
class Tuned : public Behaviour {
 public:
  double activation(const StepContext&) override { return 0.0; }
  double gain = 0.0;
  std::string mode;
  std::int64_t retries = 0;
  Vec2 offset;
};

/// Proceeds at once; it exists for its params.
class Wait : public State {
 public:
  StateResult execute(StateContext&) override { return StateResult::kProceed; }
  StateParam<std::int64_t> ticks;
  StateParam<std::string> label;
};

}  // namespace

void add_param_check_classes(Registry& registry) {
  auto& tuned = registry.add_behaviour<Tuned>("test.Tuned");
  tuned.param("gain", &Tuned::gain).range(0.0, 1.0);
  tuned.param("mode", &Tuned::mode).defaults_to(std::string("soft")).one_of({"soft", "hard"});
  tuned.param("retries", &Tuned::retries).defaults_to(3).at_least(0);
  tuned.param("offset", &Tuned::offset).defaults_to(Vec2{});
  auto& wait = add_state_class<Wait>(registry, "test.Wait");
  wait.param("ticks", &Wait::ticks).at_least(1);
  wait.param("label", &Wait::label).defaults_to(std::string());
}

Diagnostics diagnose_text(const std::string& text, const Registry& registry,
                          const std::string& file) {
  Diagnostics diagnostics;
  auto document = parse_document(text, file, format_of(file), diagnostics);
  if (!document) return diagnostics;
  Model model = build_model(*document, registry, diagnostics);
  if (!diagnostics.has_errors()) compile(model, registry, diagnostics);
  diagnostics.sort();
  return diagnostics;
}

Program compile_text(const std::string& text, const Registry& registry, const std::string& file) {
  Diagnostics diagnostics;
  auto document = parse_document(text, file, format_of(file), diagnostics);
  if (!document) throw ConfigError(std::move(diagnostics));
  Model model = build_model(*document, registry, diagnostics);
  if (diagnostics.has_errors()) throw ConfigError(std::move(diagnostics));
  auto program = compile(model, registry, diagnostics);
  if (!program) throw ConfigError(std::move(diagnostics));
  return std::move(*program);
}

std::string run_traced(Manager& manager, int steps) {
  std::ostringstream out;
  TraceWriter trace(out);
  manager.add_observer(trace);
  for (int i = 0; i < steps; ++i) manager.step();
  manager.finish();
  return out.str();
}

double activation_of(const Manager& manager, const std::string& layer, const std::string& name) {
  const auto index = manager.program().find_behaviour(layer, name);
  if (!index) throw std::runtime_error("no behaviour " + layer + "/" + name);
  return manager.activation(*index);
}

TempDir::TempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "arbiter-test-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  namespace fs = std::filesystem;
  std::error_code ignored;
  fs::permissions(path_, fs::perms::owner_all, fs::perm_options::add, ignored);
  for (const auto& entry : fs::recursive_directory_iterator(path_, ignored)) {
    fs::permissions(entry.path(), fs::perms::owner_all, fs::perm_options::add, ignored);
  }
  fs::remove_all(path_, ignored);
}

std::string TempDir::write(const std::string& name, const std::string& text) const {
  const std::string path = file(name);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
  return path;
}

}  // namespace arbiter::test

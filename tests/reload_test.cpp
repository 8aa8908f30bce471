// Hot reload (docs/hot_reload.md): a config edited while its manager runs. The swap happens
// inside step(), which must not allocate, so this binary counts operator new (counting_new.cpp).

#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include <unistd.h>

#include "arbiter/recording.hpp"
#include "arbiter/reload.hpp"
#include "arbiter/trace.hpp"
#include "arbiter/trace_reader.hpp"
#include "core/run/carryover.hpp"  // internal: one test stages a carry-over by hand
#include "counting_new.hpp"
#include "test_support.hpp"

using namespace arbiter;
using test::allocations;
using test::counting;

namespace {

namespace fs = std::filesystem;

/// A config file in a fresh directory, rewritten by each edit.
class ConfigFile {
 public:
  explicit ConfigFile(const std::string& text) { write(text); }
  void write(const std::string& text) const { dir_.write("robot.yaml", text); }
  std::string path() const { return dir_.file("robot.yaml"); }

 private:
  test::TempDir dir_;
};

/// Writes `text` to `config` and reloads it into `manager`; a reload that is refused fails the
/// test with its diagnostics.
ReloadResult staged_reload(const ConfigFile& config, const std::string& text, Reloader& reloader,
                           Manager& manager) {
  config.write(text);
  ReloadResult result = reloader.reload(manager);
  INFO(format(result.diagnostics));
  REQUIRE(result.staged);
  return result;
}

/// A probe that keeps its run-time state (how often it executed) across a params change.
class Counter : public Behaviour {
 public:
  double activation(const StepContext&) override { return 1.0; }
  void execute(ExecuteContext&) override { ++executions; }
  bool carry_over(Behaviour& previous) override {
    executions = static_cast<Counter&>(previous).executions;
    return true;
  }
  double gain = 0.0;
  int executions = 0;
};

Registry make_registry() {
  Registry registry = test::make_test_registry();
  registry.add_behaviour<Counter>("test.Counter").param("gain", &Counter::gain).defaults_to(1.0);
  return registry;
}

Registry& registry() {
  static Registry shared = make_registry();
  return shared;
}

Program load(Reloader& reloader, const std::string& path) {
  Diagnostics diagnostics;
  auto program = reloader.load(path, diagnostics);
  INFO(format(diagnostics));
  REQUIRE(program);
  return std::move(*program);
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

const char* const kTwoProbes = R"(arbiter: 1
name: pair
layers:
  - name: control
    actuators:
      command: {type: double}
    behaviours:
      a: {type: test.Probe, params: {levels: 0.5, value: 1}, ports: {out: command}}
      b: {type: test.Probe, params: {levels: 0.5, value: 2}, ports: {out: command}}
    inhibitions: [a -> b]
)";

std::string flipped(std::string text) {
  text.replace(text.find("[a -> b]"), 8, "[b -> a]");
  return text;
}

}  // namespace

TEST_CASE("an edit that flips an inhibition changes the trace from the next step", "[reload]") {
  ConfigFile config(kTwoProbes);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  std::ostringstream trace;
  TraceWriter writer(trace);
  manager.add_observer(writer);
  for (int i = 0; i < 3; ++i) manager.step();
  CHECK(test::activation_of(manager, "control", "b") == Approx(0.25));
  const auto* a = &test::instance<test::Probe>(manager.program(), "control", "a");
  const auto* b = &test::instance<test::Probe>(manager.program(), "control", "b");

  const ReloadResult result = staged_reload(config, flipped(kTwoProbes), reloader, manager);
  CHECK(format(result.diff) ==
        "  - inhibition control: a -> b\n"
        "  + inhibition control: b -> a\n");
  // Reordering the layer moves no writer slot, so both behaviours keep their instances.
  CHECK(result.restarted.empty());
  // Staged, not yet swapped: the running program is untouched until the next step.
  CHECK(manager.reloads() == 0);
  CHECK(test::activation_of(manager, "control", "b") == Approx(0.25));

  manager.step();
  CHECK(manager.reloads() == 1);
  CHECK(&test::instance<test::Probe>(manager.program(), "control", "a") == a);
  CHECK(&test::instance<test::Probe>(manager.program(), "control", "b") == b);
  CHECK(test::activation_of(manager, "control", "a") == Approx(0.25));
  CHECK(test::activation_of(manager, "control", "b") == Approx(0.5));
  const auto lines = lines_of(trace.str());
  REQUIRE(lines.size() == 6);  // header, 3 steps, reload header, step 4
  CHECK(lines[3].find(R"("step": 3)") != std::string::npos);
  CHECK(lines[3].find(R"("inhibited_by": ["a"])") != std::string::npos);
  CHECK(lines[4].rfind(R"({"arbiter_trace": 1, "reload": 1, "after_step": 3, "name": "pair", )"
                       R"("layers": [{"name": "control", "order": ["b", "a"]}]})",
                       0) == 0);
  CHECK(lines[5].find(R"("step": 4)") != std::string::npos);
  CHECK(lines[5].find(R"("a": {"requested": 0.5, "activation": 0.25, "active": true, )"
                      R"("inhibited_by": ["b"]})") != std::string::npos);
}

TEST_CASE("a broken edit keeps the old graph and reports the error with its location", "[reload]") {
  ConfigFile config(kTwoProbes);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  manager.step();
  std::string broken = kTwoProbes;
  broken.replace(broken.find("[a -> b]"), 8, "[a -> c]");
  config.write(broken);
  const ReloadResult result = reloader.reload(manager);
  CHECK_FALSE(result.staged);
  CHECK(result.diff.empty());
  CHECK_THAT(format(result.diagnostics),
             Catch::Contains(config.path() + ":10:24: error: ") && Catch::Contains("'c'"));
  manager.step();
  CHECK(manager.reloads() == 0);
  CHECK(test::activation_of(manager, "control", "b") == Approx(0.25));

  SECTION("a file caught mid-write is reported, and the next write is taken") {
    config.write("arbiter: 1\nname: pair\nlayers:\n  - name: [control\n");
    const ReloadResult half = reloader.reload(manager);
    CHECK_FALSE(half.staged);
    CHECK_THAT(format(half.diagnostics), Catch::Contains(config.path() + ":"));
    config.write(flipped(kTwoProbes));
    CHECK(reloader.reload(manager).staged);
    manager.step();
    CHECK(manager.reloads() == 1);
    CHECK(test::activation_of(manager, "control", "b") == Approx(0.5));
  }
}

/// One state machine, `plan`, of two scripted states, the first holding for 100 steps.
const char* const kPlanMachine = R"(state_machines:
  plan:
    states:
      wait: {type: scripted, params: {hold: 100}}
      go: scripted
    queue: [wait, go]
)";

TEST_CASE("behaviours, actuators and controllers that match keep their state", "[reload]") {
  const std::string before = R"(arbiter: 1
name: carry
layers:
  - name: control
    actuators:
      command: {type: double}
      other: {type: double}
    behaviours:
      kept: {type: test.Probe, params: {levels: 1, value: 3}, ports: {out: command}}
      tuned: {type: test.Probe, params: {levels: 1, value: 5}, ports: {out: other}}
      counted: {type: test.Counter, params: {gain: 1}}
      dropped: {type: test.Probe, params: {levels: 1}}
)" + std::string(kPlanMachine);
  ConfigFile config(before);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  for (int i = 0; i < 3; ++i) manager.step();
  const Program& running = manager.program();
  auto* kept = &test::instance<test::Probe>(running, "control", "kept");
  auto* tuned = &test::instance<test::Probe>(running, "control", "tuned");
  auto* dropped = &test::instance<test::Probe>(running, "control", "dropped");
  const Controller* plan = running.find_controller("plan");
  REQUIRE(plan->cycle() == 3);

  std::string after = before;
  after.replace(after.find("value: 5"), 8, "value: 6");
  after.replace(after.find("gain: 1"), 7, "gain: 2");
  after.replace(after.find("      dropped: {type: test.Probe, params: {levels: 1}}\n"), 55, "");
  after.replace(after.find("other: {type: double}"), 21,
                "other: {type: double}\n      added: {type: bool}");
  const ReloadResult result = staged_reload(config, after, reloader, manager);
  CHECK(format(result.diff) ==
        "  - behaviour control/dropped (test.Probe)\n"
        "  + actuator added (bool)\n"
        "  ~ behaviour control/tuned: params: value 5.0 -> 6.0\n"
        "  ~ behaviour control/counted: params: gain 1.0 -> 2.0\n");
  CHECK(result.restarted == std::vector<std::string>{"control/tuned", "control/counted"});
  // Still running the old program: the dropped behaviour is alive until the swap.
  CHECK(dropped->events.back() == "execute 3");
  manager.step();
  REQUIRE(manager.reloads() == 1);
  const Program& now = manager.program();

  SECTION("an unchanged behaviour keeps its instance, and stays active without re-activation") {
    CHECK(&test::instance<test::Probe>(now, "control", "kept") == kept);
    CHECK(kept->events.back() == "execute 4");
  }
  SECTION("a behaviour whose params changed starts afresh, unless it takes over its state") {
    auto& fresh = test::instance<test::Probe>(now, "control", "tuned");
    CHECK(&fresh != tuned);
    CHECK(fresh.value == 6.0);
    CHECK(fresh.events == std::vector<std::string>{"update 4", "execute 4 just_activated"});
    // The replaced instance was told it is inhibited, before the new one ran.
    CHECK(tuned->events.back() == "inhibited 3 just_deactivated");
    auto& counted = test::instance<Counter>(now, "control", "counted");
    CHECK(counted.gain == 2.0);
    CHECK(counted.executions == 4);
  }
  SECTION("a removed behaviour gets a final inhibited() call") {
    CHECK(dropped->events.back() == "inhibited 3 just_deactivated");
  }
  SECTION("actuator values carry over by name; new actuators start at their default") {
    CHECK(manager.actuator<double>(*now.find_actuator("command")) == 3.0);
    CHECK(manager.actuator<double>(*now.find_actuator("other")) == 6.0);
    CHECK_FALSE(manager.actuator<bool>(*now.find_actuator("added")));
  }
  SECTION("a controller declared alike keeps its current state, queue and cycle") {
    const Controller* same = now.find_controller("plan");
    CHECK(same == plan);
    CHECK(same->cycle() == 4);
    CHECK(same->current_state() == "wait");
    REQUIRE(same->queue_size() == 1);
    CHECK(same->queued(0) == "go");
  }
  SECTION("the next reload frees what the swap replaced") {
    config.write(before);
    CHECK(reloader.reload(manager).staged);
    manager.step();
    CHECK(manager.reloads() == 2);
  }
}

/// A config of just kPlanMachine.
const std::string kPlans = "arbiter: 1\nname: plans\n" + std::string(kPlanMachine);

TEST_CASE("a controller whose declaration changed restarts from its queue", "[reload]") {
  const std::string before = kPlans;
  ConfigFile config(before);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  for (int i = 0; i < 3; ++i) manager.step();
  std::string after = before;
  after.replace(after.find("hold: 100"), 9, "hold: 50");
  config.write(after);
  const ReloadResult result = reloader.reload(manager);
  REQUIRE(result.staged);
  CHECK(format(result.diff) == "  ~ controller plan: state wait: params hold 100 -> 50\n");
  CHECK(result.restarted == std::vector<std::string>{"state machine plan"});
  test::ControllerLog log("plan");
  manager.add_observer(log);
  manager.step();
  CHECK(log.lines == std::vector<std::string>{"cycle 1: activate wait, execute wait"});
}

TEST_CASE("what a swap replaced outlives the observers' on_reload()", "[reload]") {
  // An observer may read the replaced program in on_reload() (a recorder formats its last steps
  // then); a reload on another thread meanwhile must not free it.
  struct SlowObserver : Observer {
    std::atomic<bool> entered{false};
    std::atomic<bool> release{false};
    void on_step(const Manager&) override {}
    void on_reload(const Manager&) override {
      entered = true;
      while (!release) std::this_thread::yield();
    }
  };
  ConfigFile config(kPlans);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  SlowObserver observer;
  manager.add_observer(observer);
  manager.step();
  REQUIRE(reloader.reload(manager).staged);
  std::thread stepping([&] { manager.step(); });  // swaps, then waits in on_reload()
  while (!observer.entered) std::this_thread::yield();
  std::atomic<bool> withdrawn{false};
  std::thread reloading([&] {
    manager.withdraw();  // would free the replaced program
    withdrawn = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  CHECK_FALSE(withdrawn);
  observer.release = true;
  stepping.join();
  reloading.join();
  CHECK(withdrawn);
  CHECK(manager.reloads() == 1);
}

namespace {

const char* const kSwap = R"(arbiter: 1
name: swap
layers:
  - name: control
    actuators:
      command: {type: vec2, aggregate: true}
    behaviours:
      a: {type: scripted, params: {activation: [1, 0.5], writes: {command: [1, 2]}}}
      b: {type: scripted, params: {activation: 0.5, writes: {command: [3, 4]}}}
      c: {type: test.Probe, params: {levels: 1, record: false}}
    inhibitions: [a => b, b -> c]
state_machines:
  plan:
    states:
      wait: {type: scripted, params: {hold: 100}}
    queue: [wait]
)";

/// kSwap with its inhibitions flipped, a state's param changed and a behaviour added.
std::string edited_swap() {
  std::string after = kSwap;
  after.replace(after.find("[a => b, b -> c]"), 16, "[b => a, c -> b]");
  after.replace(after.find("hold: 100"), 9, "hold: 7");
  after.replace(after.find("      c: {"), 0,
                "      d: {type: test.Probe, params: {record: false}}\n");
  return after;
}

}  // namespace

TEST_CASE("a run state swapped or moved keeps its pointers into its own buffer", "[reload]") {
  // The swap of a reload exchanges two run states whole; one moved from points nowhere.
  ConfigFile config(kSwap);
  Reloader reloader(registry());
  const Program first = load(reloader, config.path());
  config.write(edited_swap());
  Diagnostics diagnostics;
  const auto second = reloader.load(config.path(), diagnostics);
  REQUIRE(second);
  RunState a(first);
  RunState b(*second);
  const auto inside = [](const RunState& state, const void* pointer) {
    const auto* at = static_cast<const std::byte*>(pointer);
    return at >= state.tracked.data() && at < state.tracked.data() + state.tracked_layout.total;
  };
  const auto* a_bytes = a.tracked.data();
  std::swap(a, b);
  CHECK(b.tracked.data() == a_bytes);
  for (const RunState* state : {&a, &b}) {
    CHECK(inside(*state, state->requested));
    CHECK(inside(*state, state->activation));
    CHECK(inside(*state, state->active));
    CHECK(inside(*state, state->actuator_written));
    CHECK(inside(*state, state->values));
  }
  RunState moved(std::move(a));
  CHECK(inside(moved, moved.requested));
  CHECK(static_cast<double*>(a.requested) == nullptr);
  CHECK(static_cast<std::byte*>(a.values) == nullptr);
}

TEST_CASE("the swap inside step() allocates nothing", "[reload][alloc]") {
  ConfigFile config(kSwap);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  for (int i = 0; i < 3; ++i) manager.step();
  config.write(edited_swap());
  REQUIRE(reloader.reload(manager).staged);
  allocations = 0;
  counting = true;
  manager.step();
  counting = false;
  CHECK(manager.reloads() == 1);
  CHECK(allocations.load() == 0);
}

TEST_CASE("a recorded swap allocates nothing on the stepping thread", "[reload][alloc][record]") {
  // The recorder lays its ring out for the staged program on the staging thread
  // (Observer::on_staged()), and the writer frees the replaced layout: the step that swaps
  // neither allocates nor waits for the writer.
  ConfigFile config(kSwap);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  const test::TempDir scratch;
  const auto path = scratch.path() / "arbiter_reload_recorded.mcap";
  {
    RecordingInfo info;
    info.version = "test";
    Recorder recorder(path.string(), info);
    REQUIRE(recorder.ok());
    manager.add_observer(recorder);
    for (int i = 0; i < 3; ++i) manager.step();
    config.write(edited_swap());
    REQUIRE(reloader.reload(manager).staged);
    allocations = 0;
    test::only_thread = std::this_thread::get_id();  // not the writer's
    counting = true;
    manager.step();
    counting = false;
    test::only_thread = std::thread::id();
    CHECK(manager.reloads() == 1);
    CHECK(allocations.load() == 0);
    manager.finish();
    CHECK(recorder.dropped() == 0);
  }
  const Trace recorded = test::read_whole_trace(path.string());
  CHECK(recorded.steps.size() == 4);
  REQUIRE(recorded.reloads.size() == 1);
  CHECK(recorded.reloads[0].before == 3);
  std::filesystem::remove(path);
}

TEST_CASE("reloads from another thread while a control loop steps", "[reload]") {
  ConfigFile config(kTwoProbes);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  std::atomic<bool> done{false};
  std::thread loop([&] {
    while (!done) manager.step();
  });
  int staged = 0;
  for (int i = 0; i < 20; ++i) {
    config.write(i % 2 == 0 ? flipped(kTwoProbes) : kTwoProbes);
    staged += reloader.reload(manager).staged ? 1 : 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const std::uint64_t steps_then = manager.steps();
  while (manager.steps() < steps_then + 2) std::this_thread::yield();
  done = true;
  loop.join();
  CHECK(staged == 20);
  // A program staged while another waited replaces it: at least the last one is swapped in.
  CHECK(manager.reloads() >= 1);
  CHECK(manager.reloads() <= 20);
  const Program& last = manager.program();  // the last config: a -> b
  CHECK(last.inhibitions.closed(*last.find_behaviour("control", "b")) ==
        std::vector<std::uint32_t>{*last.find_behaviour("control", "a")});
}

namespace {

long resident_kib() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0;
  long resident = 0;
  statm >> pages >> resident;
  return resident * (::sysconf(_SC_PAGESIZE) / 1024);
}

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

}  // namespace

TEST_CASE("1000 reloads of the soccer demo keep resident memory flat", "[reload][leak]") {
  // Each reload alternates between the demo and an edit of it (an inhibition flipped, a param
  // changed), so that instances are both kept and replaced; the manager steps in between.
  std::ifstream in(std::string(ARBITER_SOURCE_DIR) + "/configs/soccer/walk_and_kick.yaml");
  std::stringstream text;
  text << in.rdbuf();
  const std::string demo = text.str();
  std::string edit = demo;
  edit.replace(edit.find("kick_ball => go_behind_ball"), 27, "kick_ball -> go_behind_ball");
  edit.replace(edit.find("turn_rate: 0.6"), 14, "turn_rate: 0.5");
  ConfigFile config(demo);
  Registry soccer = test::make_test_registry();
  LoadOptions options;
  options.plugins.path.push_back(ARBITER_PLUGIN_DIR);
  Reloader reloader(soccer, options);
  Manager manager(load(reloader, config.path()));
  const auto reload = [&](int times) {
    for (int i = 0; i < times; ++i) {
      const ReloadResult result =
          staged_reload(config, i % 2 == 0 ? edit : demo, reloader, manager);
      for (int s = 0; s < 3; ++s) manager.step();
    }
  };
  reload(100);  // warm-up: the allocator's pools, the plugin, spdlog
  const long before = resident_kib();
  const auto started = std::chrono::steady_clock::now();
  reload(1000);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const long after = resident_kib();
  CHECK(manager.reloads() == 1100);
  std::cout << "1000 reloads of walk_and_kick: resident " << before << " KiB before, " << after
            << " KiB after (" << (after - before) << " KiB growth), " << seconds << " s\n";
  if (!kSanitized) CHECK(after - before <= 1024);
}

TEST_CASE("a carry-over plan that does not fit is refused before it reaches step()", "[reload]") {
  Manager manager(test::compile_text(kTwoProbes, registry()));
  manager.step();
  CHECK_THROWS_AS(manager.stage(test::compile_text(kTwoProbes, registry()), detail::Carryover{}),
                  std::invalid_argument);
  manager.step();
  CHECK(manager.reloads() == 0);
}

TEST_CASE("a reload's diff tells what changed in a state machine, old -> new", "[reload]") {
  const std::string before = kPlans;
  ConfigFile config(before);
  Reloader reloader(registry());
  Manager manager(load(reloader, config.path()));
  manager.step();
  std::string after = before;
  after.replace(after.find("      go: scripted\n"), 19,
                "      run: scripted\n      rest: scripted\n");
  after.replace(after.find("[wait, go]"), 10, "[wait, run, rest]");
  const ReloadResult result = staged_reload(config, after, reloader, manager);
  CHECK(format(result.diff) ==
        "  ~ controller plan: states added: run, rest; states removed: go; queue [wait, go] -> "
        "[wait, run, rest]\n");
}

TEST_CASE("config_diff tells params, inhibitions and the rate apart, as a reload does",
          "[reload]") {
  std::string text = kTwoProbes;
  text.replace(text.find("name: pair\n"), 11, "name: pair\nrate_hz: 10\n");
  ConfigFile first(text);
  ConfigFile second(flipped(text));
  Reloader reload_first(registry());
  Reloader reload_second(registry());
  const Program before = load(reload_first, first.path());
  std::string edited = flipped(text);
  edited.replace(edited.find("value: 2"), 8, "value: 3");
  edited.replace(edited.find("rate_hz: 10"), 11, "rate_hz: 20");
  second.write(edited);
  const Program after = load(reload_second, second.path());
  CHECK(lines_of(format(config_diff(before, after), "")) ==
        std::vector<std::string>{"- inhibition control: a -> b", "+ inhibition control: b -> a",
                                 "~ behaviour control/b: params: value 2.0 -> 3.0",
                                 "~ config rate_hz: 10 -> 20"});
  CHECK(config_diff(before, before).empty());
}

// The step loop is a real-time path: after the first step it must not touch the heap. This
// binary links the counting operator new (support/counting_new.cpp), so it stands apart from the
// rest.

#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <sstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#if ARBITER_HAS_FOXGLOVE
#include "foxglove_subscriber.hpp"
#include "server/foxglove.hpp"
#endif

#include "arbiter/breakpoint.hpp"
#include "arbiter/load.hpp"
#include "arbiter/recorded_inputs.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/substitute.hpp"
#include "commands/timing.hpp"
#include "core/record/step_record.hpp"
#include "counting_new.hpp"
#include "test_support.hpp"

using arbiter::test::allocations;
using arbiter::test::counting;

using namespace arbiter;

namespace {

std::string read_config(const std::string& relative) {
  std::ifstream in(std::string(ARBITER_SOURCE_DIR) + "/" + relative);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A shipped config (`relative` to the source directory) loaded with the built plugins, which
/// `registry` must outlive the program for.
Program load_shipped(const std::string& relative, Registry& registry) {
  LoadOptions options;
  options.plugins.path.push_back(ARBITER_PLUGIN_DIR);
  Diagnostics diagnostics;
  auto program =
      load(std::string(ARBITER_SOURCE_DIR) + "/" + relative, registry, diagnostics, options);
  INFO(format(diagnostics));
  REQUIRE(program);
  return std::move(*program);
}

/// Allocations made by steps 2..steps of `manager`.
std::size_t allocations_in_steps(Manager& manager, int steps) {
  manager.step();
  allocations = 0;
  counting = true;
  for (int i = 1; i < steps; ++i) manager.step();
  counting = false;
  return allocations.load();
}

/// Allocations made by steps 2..steps of a manager built from `text`.
std::size_t allocations_per_run(const std::string& text, int steps) {
  static const Registry registry = test::make_test_registry();
  Manager manager(test::compile_text(text, registry));
  return allocations_in_steps(manager, steps);
}

/// A config named `name` of one state machine, `loop`: its `states` (the lines under `states:`)
/// and its `queue` (a flow list).
std::string one_machine(const std::string& name, const std::string& states,
                        const std::string& queue) {
  return "arbiter: 1\nname: " + name + "\nstate_machines:\n  loop:\n    states:" + states +
         "    queue: " + queue + "\n";
}

/// Every config under configs/, sorted, relative to the source directory.
std::vector<std::string> shipped_configs() {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  const auto is_config = [](const fs::path& path) {
    return path.extension() == ".yaml" || path.extension() == ".json";
  };
  for (const auto& path : test::files_in(fs::path(ARBITER_SOURCE_DIR) / "configs", is_config,
                                         test::Walk::kRecursive)) {
    out.push_back(fs::relative(path, ARBITER_SOURCE_DIR).string());
  }
  return out;
}

}  // namespace

TEST_CASE("the counter sees allocations", "[alloc]") {
  counting = true;
  allocations = 0;
  auto* probe = new std::vector<int>(100);
  counting = false;
  delete probe;
  CHECK(allocations.load() >= 2);
}

TEST_CASE("with its thread filter set, the counter sees that thread's allocations only",
          "[alloc]") {
  std::atomic<int> phase{0};                       // 1: the other thread allocates; 2: it has
  std::atomic<std::vector<int>*> theirs{nullptr};  // escapes, so the allocation is made
  std::thread other([&] {
    while (phase.load() != 1) std::this_thread::yield();
    theirs = new std::vector<int>(100);
    phase = 2;
  });
  allocations = 0;
  arbiter::test::only_thread = std::this_thread::get_id();
  counting = true;
  phase = 1;
  while (phase.load() != 2) std::this_thread::yield();
  const std::size_t others = allocations.load();
  auto* mine = new std::vector<int>(100);
  counting = false;
  arbiter::test::only_thread = std::thread::id();
  delete mine;
  other.join();
  delete theirs.load();
  CHECK(others == 0);
  CHECK(allocations.load() >= 2);
}

// Reports formatted text each step: numbers, and a text longer than a report holds, made of
// two-byte characters so that the cut falls inside one.
class Reporter final : public Behaviour {
 public:
  double activation(const StepContext&) override { return 1.0; }
  void execute(ExecuteContext& ctx) override {
    ctx.report("room {} started at {:.1f} m", ctx.step(), 2.5);
    ctx.report("a{}", std::string_view(long_text_));
  }

 private:
  std::string long_text_ = [] {
    std::string text;
    for (int i = 0; i < 100; ++i) text += "\u00e9";  // é
    return text;
  }();
};

TEST_CASE("formatted reports allocate nothing, and a text too long is cut and marked", "[alloc]") {
  Registry registry = test::make_test_registry();
  registry.add_behaviour<Reporter>("test.Reporter");
  Manager manager(test::compile_text(R"(
arbiter: 1
name: reports
layers:
  - name: control
    behaviours:
      rooms: {type: test.Reporter}
)",
                                     registry));
  CHECK(allocations_in_steps(manager, 50) == 0);
  REQUIRE(manager.event_count() == 2);
  CHECK(manager.event_source(manager.event(0)) == "rooms");
  CHECK(std::string(manager.event(0).text) == "room 50 started at 2.5 m");
  // 127 bytes fit; the cut backs up to the start of the character it would split.
  std::string expected = "a";
  for (int i = 0; i < 61; ++i) expected += "\u00e9";
  expected += "\u2026";  // …
  CHECK(std::string(manager.event(1).text) == expected);
  CHECK(expected.size() < detail::kReportBytes);
}

TEST_CASE("behaviour layers step without allocating", "[alloc]") {
  CHECK(allocations_per_run(read_config("configs/paper/walk_and_kick.yaml"), 200) == 0);
  CHECK(allocations_per_run(R"(
arbiter: 1
name: layered
layers:
  - name: world
    interface: test.Feed
    ports: {out: measured}
    actuators: {measured: double}
  - name: upper
    sensors: [measured]
    actuators:
      target: {type: vec2, aggregate: true}
      label: {type: string}
    behaviours:
      a: {type: scripted, params: {activation: [0.2, 0.9, 0], writes: {target: [1, 2], label: left}}}
      b: {type: scripted, params: {activation: 0.5, writes: {target: [3, 4], label: right}}}
      c: {type: test.Probe, params: {levels: [1, 0, 1], record: false}, ports: {in: measured}}
    inhibitions: [a => b, b -> c]
  - name: lower
    sensors: [target, label]
    actuators:
      command: {type: double, aggregate: true}
    behaviours:
      d: {type: test.Probe, params: {levels: 0.7, value: 2, record: false}, ports: {out: command}}
      e: {type: test.Probe, params: {levels: 0.3, value: 4, record: false}, ports: {out: command}}
)",
                            200) == 0);
}

TEST_CASE("state controllers step, transition and re-plan without allocating", "[alloc]") {
  // goalie_plan re-plans (append) every few cycles, prepends, and is pre-empted.
  CHECK(allocations_per_run(read_config("configs/paper/goalie_plan.yaml"), 60) == 0);
  CHECK(allocations_per_run(read_config("configs/paper/hierarchical.yaml"), 30) == 0);
  CHECK(allocations_per_run(one_machine("replanning", R"(
      a: {type: test.Planner, params: {op: append, target: p, x: 1.5}}
      p: {type: test.Planner, params: {op: insert_after, target: p}}
      again: {type: scripted, params: {append: [a], hold: 2}}
)",
                                        "[a, again]"),
                            300) == 0);
  // Plan edits through handles with run-time params, and reads of them through param handles.
  CHECK(allocations_per_run(one_machine("handles", R"(
      a: {type: test.Planner, params: {op: go_to, target: b, x: 1.5}}
      b: {type: test.Planner, params: {op: prepend, target: a, x: 2.5}}
      c: {type: test.Planner, params: {op: insert_before, target: p, x: 0.5}}
      p: test.Pose
)",
                                        "[c, a]"),
                            300) == 0);
}

TEST_CASE("every config in configs/ steps without allocating", "[alloc]") {
  // Loaded as `arbiter run` loads them: the plugins they name come from the build's plugin
  // directory. 300 steps reach the soccer demo's kick and the goalie plan's re-planning. A config
  // whose plugin this build does not have (an optional one, e.g. dds without Cyclone DDS) is
  // skipped, and says so.
  const auto configs = shipped_configs();
  REQUIRE(configs.size() >= 4);
  for (const auto& config : configs) {
    DYNAMIC_SECTION(config) {
      Registry registry = test::make_test_registry();
      LoadOptions options;
      options.plugins.path.push_back(ARBITER_PLUGIN_DIR);
      Diagnostics diagnostics;
      auto program =
          load(std::string(ARBITER_SOURCE_DIR) + "/" + config, registry, diagnostics, options);
      const auto missing_plugin = std::find_if(
          diagnostics.items().begin(), diagnostics.items().end(),
          [](const Diagnostic& diagnostic) { return diagnostic.code == "plugin-not-found"; });
      if (!program && missing_plugin != diagnostics.items().end()) {
        WARN(config << " skipped: " << missing_plugin->message);
        // Only an optional plugin may be missing; the soccer plugin is built with this test.
        CHECK(missing_plugin->message.find("plugin 'dds' not found") != std::string::npos);
        continue;
      }
      INFO(format(diagnostics));
      REQUIRE(program);
      Manager manager(std::move(*program));
      CHECK(allocations_in_steps(manager, 300) == 0);
    }
  }
}

TEST_CASE("a program with substituted classes steps without allocating", "[alloc]") {
  Registry registry = test::make_test_registry();
  Diagnostics diagnostics;
  auto root = parse_document(read_config("configs/paper/walk_and_kick.yaml"), "walk_and_kick.yaml",
                             DocumentFormat::kYaml, diagnostics);
  REQUIRE(root);
  Model model = build_model(*root, registry, diagnostics);
  auto replacement =
      parse_document("{type: scripted, params: {activation: [0, 1], writes: {kick: true}}}",
                     "test.yaml", DocumentFormat::kYaml, diagnostics);
  REQUIRE(replacement);
  // Named rather than braced into the vector: GCC 12 at -O2 warns, falsely, that the braced
  // temporary's SourceLocation may be used uninitialised.
  Substitution kick_ball;
  kick_ball.target = "control/kick_ball";
  kick_ball.declaration = *replacement;
  REQUIRE(substitute(model, {kick_ball}, registry, diagnostics));
  auto program = compile(model, registry, diagnostics);
  INFO(format(diagnostics));
  REQUIRE(program);
  Manager manager(std::move(*program));
  CHECK(allocations_in_steps(manager, 50) == 0);
}

namespace {

/// A clock that only counts: what a host's steady clock costs, without the time.
class CountingClock : public StepClock {
 public:
  double now() override { return ticks_ += 1.0; }

 private:
  double ticks_ = 0.0;
};

}  // namespace

/// Safe values of every kind of type: a vector, a string; and a number without one.
const char* const kSafeValues = R"(arbiter: 1
name: safe
layers:
  - name: control
    actuators:
      gait: {type: vec3, aggregate: true, safe: [0, 0, 0]}
      label: {type: string, safe: stop}
      speed: {type: double}
    behaviours:
      walk: {type: scripted, params: {activation: 1, writes: {gait: [1, 2, 3], label: go, speed: 2}}}
  - name: world
    interface: test.Feed
    ports: {out: measured}
    actuators: {measured: double}
    sensors: [gait, label, speed]
)";

TEST_CASE("a replay draws the recorded picture without allocating", "[alloc][replay][scene]") {
  using Json = nlohmann::json;
  const Json pose = {{"position", {{"x", 1}, {"y", 2}, {"z", 0}}},
                     {"orientation", {{"x", 0}, {"y", 0}, {"z", 0}, {"w", 1}}}};
  const Json color = {{"r", 1}, {"g", 0.5}, {"b", 0}, {"a", 1}};
  const auto entity = [&](const std::string& id, double x) {
    Json out = {{"frame_id", "field"},     {"id", id},
                {"arrows", Json::array()}, {"cylinders", Json::array()},
                {"lines", Json::array()},  {"texts", Json::array()}};
    if (id == "field/still") {
      out["lines"].push_back(
          {{"type", 1},
           {"thickness", 0.05},
           {"points", {{{"x", 0}, {"y", 0}}, {{"x", 1}, {"y", 0}}, {{"x", 0}, {"y", 1}}}},
           {"color", color}});
      out["texts"].push_back(
          {{"pose", pose}, {"font_size", 0.4}, {"color", color}, {"text", "0 : 0"}});
    } else {
      Json moved = pose;
      moved["position"]["x"] = x;
      out["arrows"].push_back({{"pose", moved},
                               {"shaft_length", 0.3},
                               {"head_length", 0.15},
                               {"shaft_diameter", 0.05},
                               {"color", color}});
      out["cylinders"].push_back({{"pose", moved}, {"size", {{"x", 0.3}}}, {"color", color}});
    }
    return out;
  };
  const auto message = [&](bool whole, double x) {
    Json out = {{"deletions", Json::array()}, {"entities", Json::array()}};
    if (whole) {
      out["deletions"].push_back({{"type", 1}, {"id", ""}});
      out["entities"].push_back(entity("field/still", x));
    }
    out["entities"].push_back(entity("field/moving", x));
    return out.dump();
  };
  Registry registry = test::make_test_registry();
  Diagnostics diagnostics;
  RecordedInputs inputs;
  // The world's layer, replayed, writes its one actuator.
  const auto recorded = [](std::uint64_t step) {
    return R"({"step": )" + std::to_string(step) +
           R"(, "inputs": {"measured": {"value": 1.5, "written": true}}})";
  };
  REQUIRE(inputs.load(1, recorded(1), diagnostics, message(true, 0.0)));
  auto root = parse_document(kSafeValues, "safe.yaml", DocumentFormat::kYaml, diagnostics);
  REQUIRE(root);
  Model model = build_model(*root, registry, diagnostics);
  inputs.replace_interfaces(model, diagnostics);
  auto program = compile(model, registry, diagnostics);
  INFO(format(diagnostics));
  REQUIRE(program);
  Manager manager(std::move(*program));
  manager.step();
  CHECK(manager.scene_primitive_count() == 4);
  std::size_t made = 0;
  for (std::uint64_t step = 2; step <= 30; ++step) {
    REQUIRE(inputs.load(step, recorded(step), diagnostics, message(step % 15 == 0, 0.1 * step)));
    allocations = 0;
    counting = true;
    manager.step();
    counting = false;
    made += allocations.load();
    // The still line and text kept from the whole picture, the moving arrow and disc replaced.
    CHECK(manager.scene_primitive_count() == 4);
  }
  CHECK(made == 0);
  // The arrow, where the last step's message moved it.
  const auto& scene = manager.scene();
  const auto arrow =
      std::find_if(scene.primitives, scene.primitives + 4,
                   [](const ScenePrimitive& p) { return p.shape == SceneShape::kArrow; });
  REQUIRE(arrow != scene.primitives + 4);
  CHECK(arrow->x0 == Approx(3.0));
}

TEST_CASE("a step checked against breakpoints of every kind allocates nothing",
          "[alloc][breakpoint]") {
  // The soccer demo: behaviours, values and reported events; 400 steps reach two kicks.
  Registry registry = test::make_test_registry();
  LoadOptions options;
  options.plugins.path.push_back(ARBITER_PLUGIN_DIR);
  Diagnostics diagnostics;
  auto program = load(std::string(ARBITER_SOURCE_DIR) + "/configs/soccer/walk_and_kick.yaml",
                      registry, diagnostics, options);
  INFO(format(diagnostics));
  REQUIRE(program);
  Breakpoints breakpoints;
  for (const char* text :
       {"kick_ball activates", "control/kick_ball deactivates", "gait_velocity[0] > 0.2",
        "head_angle < -0.1", "kick > 0.5", "event ~ \"kicked\"", "step >= 1000"}) {
    ConditionError error;
    auto condition = parse_condition(text, error);
    REQUIRE(condition);
    auto breakpoint = resolve_breakpoint(*program, std::move(*condition), error);
    INFO(text << ": " << error.message);
    REQUIRE(breakpoint);
    breakpoints.add(std::move(*breakpoint));
  }
  Manager manager(std::move(*program));
  manager.set_check(&breakpoints);
  std::uint64_t breaks = 0;
  allocations = 0;
  counting = true;
  for (int i = 0; i < 400; ++i) {
    manager.step();
    if (manager.break_text() != nullptr) ++breaks;
  }
  counting = false;
  CHECK(allocations.load() == 0);
  CHECK(breaks >= 4);
}

TEST_CASE("a timed step and the safe pass allocate nothing", "[alloc][safe]") {
  static const Registry registry = test::make_test_registry();
  Manager manager(test::compile_text(kSafeValues, registry));
  CountingClock clock;
  manager.set_clock(&clock);
  manager.step();
  manager.safe_pass();
  allocations = 0;
  counting = true;
  for (int i = 0; i < 50; ++i) {
    manager.step();
    manager.safe_pass();
  }
  counting = false;
  CHECK(allocations.load() == 0);
  CHECK(manager.safe_passes() == 51);
  CHECK(manager.actuator<std::string>(*manager.program().find_actuator("label")) == "stop");
}

TEST_CASE("recording a step's timing allocates nothing", "[alloc][timing]") {
  cli::RunTiming timing(0.01);
  cli::SteadyStepClock clock;
  timing.record_step(1e-5);
  allocations = 0;
  counting = true;
  for (int i = 0; i < 1000; ++i) {
    timing.record_lateness(clock.now() * 1e-3);
    timing.record_step(1e-6 * i);
    if (i % 100 == 0) timing.record_missed(2);
  }
  counting = false;
  CHECK(allocations.load() == 0);
  CHECK(timing.duration().count() == 1001);
  CHECK(timing.overruns() == 10);
  CHECK(timing.missed() == 20);
  // Percentiles within a bucket (2 %) of the exact ones; the maximum is exact.
  CHECK(timing.duration().percentile(0.5) == Approx(499e-6).epsilon(0.03));
  CHECK(timing.duration().max() == 1e-6 * 999);
}

namespace {

/// Allocations on the stepping thread in steps 2..steps of `program` recorded into an MCAP file,
/// safe passes included; `dropped`: the steps the recorder dropped.
std::size_t allocations_recorded(Program program, int steps, std::uint64_t& dropped) {
  const test::TempDir scratch;
  const auto path = scratch.path() / "arbiter_alloc_record.mcap";
  Manager manager(std::move(program));
  CountingClock clock;
  manager.set_clock(&clock);
  std::size_t counted = 0;
  {
    RecordingInfo info;
    info.version = "test";
    Recorder recorder(path.string(), info, static_cast<std::size_t>(2 * steps));
    REQUIRE(recorder.ok());
    manager.add_observer(recorder);
    manager.step();
    allocations = 0;
    arbiter::test::only_thread = std::this_thread::get_id();  // not the writer's
    counting = true;
    for (int i = 1; i < steps; ++i) {
      manager.step();
      if (i % 50 == 0) manager.safe_pass();
    }
    counting = false;
    arbiter::test::only_thread = std::thread::id();
    counted = allocations.load();
    manager.finish();
    dropped = recorder.dropped();
  }
  std::filesystem::remove(path);
  return counted;
}

}  // namespace

TEST_CASE("a recorded step allocates nothing on the stepping thread", "[alloc][record]") {
  // The soccer demo (its plugin, reports, state machines with params), a graph with string and
  // vector actuators and safe values, and a state machine that re-plans with run-time params.
  Registry registry = test::make_test_registry();
  LoadOptions options;
  options.plugins.path.push_back(ARBITER_PLUGIN_DIR);
  for (const auto* config : {"configs/soccer/walk_and_kick.yaml", "configs/paper/goalie_plan.yaml",
                             "configs/paper/hierarchical.yaml"}) {
    DYNAMIC_SECTION(config) {
      Diagnostics diagnostics;
      auto program =
          load(std::string(ARBITER_SOURCE_DIR) + "/" + config, registry, diagnostics, options);
      INFO(format(diagnostics));
      REQUIRE(program);
      std::uint64_t dropped = 0;
      CHECK(allocations_recorded(std::move(*program), 300, dropped) == 0);
      CHECK(dropped == 0);  // every step was copied, none skipped for want of room
    }
  }
  SECTION("strings, vectors and safe values") {
    std::uint64_t dropped = 0;
    CHECK(allocations_recorded(test::compile_text(kSafeValues, registry), 200, dropped) == 0);
    CHECK(dropped == 0);
  }
}

#if ARBITER_HAS_FOXGLOVE
TEST_CASE("a step served to a subscribed Foxglove client allocates nothing on the stepping thread",
          "[alloc][foxglove]") {
  Registry registry = test::make_test_registry();
  Manager manager(load_shipped("configs/soccer/walk_and_kick.yaml", registry));
  CountingClock clock;
  manager.set_clock(&clock);
  std::ostringstream said;
  auto server = cli::FoxgloveServer::open("127.0.0.1", 0, "test", "arbiter test", said, said);
  REQUIRE(server);
  manager.add_observer(server->observer());
  manager.step();
  test::FoxgloveSubscriber client(server->url());
  REQUIRE(client.connected());
  for (int i = 0; i < 2000 && client.received() == 0; ++i) {
    manager.step();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  REQUIRE(client.received() > 0);  // subscribed: the steps are captured from here on
  const auto sent_before = server->counts().sent;
  allocations = 0;
  arbiter::test::only_thread = std::this_thread::get_id();  // not the server's or the client's
  counting = true;
  for (int i = 0; i < 300; ++i) {
    manager.step();
    if (i % 50 == 0) manager.safe_pass();
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  counting = false;
  arbiter::test::only_thread = std::thread::id();
  const auto counted = allocations.load();
  manager.finish();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const auto counts = server->counts();
  server->stop();
  client.stop();
  CHECK(counted == 0);
  CHECK(counts.sent > sent_before + 300);  // the steps went out, step records and inputs
  CHECK(counts.dropped_steps == 0);
}

TEST_CASE("a live server sends the picture at its scene rate, or every step's when told 0",
          "[foxglove][scene]") {
  // The soccer demo (rate_hz 15) draws every step; 400 steps a millisecond apart (more under
  // load), far faster than its rate_hz, against a client subscribed to every channel.
  const auto serve = [](double scene_rate) {
    Registry registry = test::make_test_registry();
    Manager manager(load_shipped("configs/soccer/walk_and_kick.yaml", registry));
    std::ostringstream said;
    auto server = cli::FoxgloveServer::open("127.0.0.1", 0, "test", "arbiter test", said, said);
    REQUIRE(server);
    server->set_scene_rate(scene_rate);
    manager.add_observer(server->observer());
    manager.step();
    test::FoxgloveSubscriber client(server->url());
    REQUIRE(client.connected());
    for (int i = 0; i < 2000 && client.received("/arbiter/scene") == 0; ++i) {
      manager.step();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    REQUIRE(client.received("/arbiter/scene") > 0);
    const auto steps_before = client.received("/arbiter/step");
    const auto scenes_before = client.received("/arbiter/scene");
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 400; ++i) {
      manager.step();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the last ones on their way
    const auto counts = server->counts();
    server->stop();
    client.stop();
    CHECK(counts.dropped_steps == 0);
    CHECK(counts.dropped_for_slow_clients == 0);
    struct Received {
      std::uint64_t steps, scenes;
      double seconds;
    };
    return Received{client.received("/arbiter/step") - steps_before,
                    client.received("/arbiter/scene") - scenes_before, took.count()};
  };
  SECTION("10 pictures a second: every step's record, a picture every 100 ms") {
    const auto received = serve(10.0);
    INFO(received.steps << " steps, " << received.scenes << " pictures in " << received.seconds
                        << " s");
    CHECK(received.steps >= 400);
    // The server's thread asks for a picture when it looks at the steps, every 5 ms.
    CHECK(received.scenes >= 10.0 * received.seconds / 2);
    CHECK(received.scenes <= 10.0 * received.seconds + 3);
  }
  // As for a program whose rate_hz is no faster than the scene rate (the soccer demo's 15 at 20):
  // its steps all have their pictures, without the server's thread asking for each in time.
  for (const double rate : {0.0, 20.0}) {
    DYNAMIC_SECTION("every step's picture at scene rate " << rate) {
      const auto received = serve(rate);
      INFO(received.steps << " steps, " << received.scenes << " pictures in " << received.seconds
                          << " s");
      CHECK(received.steps >= 400);
      CHECK(received.scenes + 1 >= received.steps);
    }
  }
}
#endif
namespace {

// Draws more than a step has room for: as many circles as `circles`, and a polyline of
// `points` points.
class Painter final : public Interface {
 public:
  void input(WriteContext& ctx) override {
    Scene scene = ctx.scene("a frame name longer than its room");
    for (std::int64_t i = 0; i < circles_; ++i) {
      scene.circle({static_cast<double>(i), 0.0}, 0.1, SceneColor{});
    }
    std::vector<ScenePoint>& line = line_;
    scene.polyline(line.data(), line.size(), SceneColor{});
  }
  void init(InitContext&) override { line_.resize(static_cast<std::size_t>(points_)); }

  std::int64_t circles_ = 0, points_ = 0;
  std::vector<ScenePoint> line_;
};

}  // namespace

TEST_CASE("drawing beyond a step's room drops and counts, without allocating", "[alloc][scene]") {
  Registry registry = test::make_test_registry();
  auto& info = registry.add_interface<Painter>("test.Painter");
  info.param("circles", &Painter::circles_);
  info.param("points", &Painter::points_);
  const auto config = [](int circles, int points) {
    return "arbiter: 1\nname: painted\nlayers:\n  - name: world\n    interface: test.Painter\n"
           "    params: {circles: " +
           std::to_string(circles) + ", points: " + std::to_string(points) + "}\n";
  };
  SECTION("more primitives than room: the first ones are kept") {
    Manager manager(test::compile_text(config(200, 2), registry));
    CHECK(allocations_in_steps(manager, 50) == 0);
    REQUIRE(manager.scene_primitive_count() == Manager::kScenePrimitivesPerStep);
    CHECK(manager.scene().dropped == 201 - Manager::kScenePrimitivesPerStep);
    CHECK(manager.scene_dropped_total() == 49 * (201 - Manager::kScenePrimitivesPerStep));
    CHECK(manager.scene().primitives[5].x0 == 5.0);
    // The frame is copied, cut to its room.
    const auto picture = manager.scene().picture();
    CHECK(std::string(picture.frame(picture.primitives[0])) == "a frame name lo");
    std::string message;
    append_scene_update(0, picture, message);
    CHECK(message.find(R"("metadata":[{"key":"dropped","value":"73"}])") != std::string::npos);
  }
  SECTION("more points than room: the line is dropped whole") {
    Manager manager(test::compile_text(config(3, Manager::kScenePointsPerStep + 1), registry));
    CHECK(allocations_in_steps(manager, 50) == 0);
    CHECK(manager.scene_primitive_count() == 3);
    CHECK(manager.scene().point_count == 0);
    CHECK(manager.scene().dropped == 1);
  }
  SECTION("a step starts with an empty picture") {
    Manager manager(test::compile_text(config(0, 0), registry));
    manager.step();
    CHECK(manager.scene_primitive_count() == 0);
    CHECK(manager.scene().dropped == 1);  // a polyline of no points
  }
}

namespace {

// A step's picture with room for `kPrimitives` primitives and `kPoints` points, laid out as a
// Manager lays its own out, smaller: a text and a frame's name for each primitive.
template <std::size_t kPrimitives, std::size_t kPoints>
struct PictureRoom {
  PictureRoom() {
    data.primitives = primitives;
    data.primitive_capacity = kPrimitives;
    data.points = points;
    data.point_capacity = kPoints;
    data.strings = strings;
    data.string_capacity = sizeof strings;
    data.frames = frames;
    data.frame_capacity = kPrimitives;
  }
  PictureRoom(const PictureRoom&) = delete;  // data points into this one
  PictureRoom& operator=(const PictureRoom&) = delete;

  ScenePrimitive primitives[kPrimitives];
  ScenePoint points[kPoints];
  char strings[kPrimitives * (ScenePrimitive::kFrameBytes + ScenePrimitive::kTextBytes)];
  std::uint16_t frames[kPrimitives];
  detail::SceneData data;
};

}  // namespace

TEST_CASE("a text cut to its room is cut between characters", "[scene]") {
  PictureRoom<2, 1> room;
  auto& data = room.data;
  Scene scene(data, "field");
  std::string long_text;
  for (int i = 0; i < 30; ++i) long_text += "\xc3\xa9";  // é, two bytes
  scene.text({0.0, 0.0}, long_text.c_str(), SceneColor{});
  scene.text({0.0, 0.0}, "kick", SceneColor{});
  std::string message;
  append_scene_update(0, data.picture(), message);
  // 39 bytes fit: 19 whole characters, the first byte of the 20th left out.
  CHECK(message.find("\"text\":\"" + long_text.substr(0, 38) + "\"") != std::string::npos);
  CHECK(message.find(R"("text":"kick")") != std::string::npos);
}

TEST_CASE("a frame's name is written once a step, however many primitives are drawn in it",
          "[scene]") {
  PictureRoom<8, 4> room;
  auto& data = room.data;
  const ScenePrimitive* primitives = room.primitives;
  Scene field(data, "field");
  Scene robot(data, "robot");
  field.circle({0.0, 0.0}, 1.0, SceneColor{});
  robot.circle({1.0, 0.0}, 0.1, SceneColor{});
  field.line({0.0, 0.0}, {1.0, 1.0}, SceneColor{});
  Scene field_again(data, "field");  // another Scene, the same frame
  field_again.text({0.0, 0.0}, "kick", SceneColor{});
  REQUIRE(data.primitive_count == 4);
  CHECK(data.frame_count == 2);
  // Two names of kFrameBytes, and the text's 4 bytes.
  CHECK(data.string_size == 2 * ScenePrimitive::kFrameBytes + 4);
  const auto picture = data.picture();
  CHECK(std::string(picture.frame(primitives[0])) == "field");
  CHECK(std::string(picture.frame(primitives[1])) == "robot");
  CHECK(primitives[2].frame == primitives[0].frame);
  CHECK(primitives[3].frame == primitives[0].frame);
  CHECK(std::string(picture.text(primitives[3]), picture.text_size(primitives[3])) == "kick");
  std::string message;
  append_scene_update(0, picture, message);
  CHECK(message.find(R"("frame_id":"robot")") != std::string::npos);
  CHECK(message.find(R"("text":"kick")") != std::string::npos);
}

namespace {

// Draws a field that stays and `moving` discs that move with the step, `moving` changing with the
// step: from nothing moving to more changed lines than a block holds.
class Mover final : public Interface {
 public:
  void input(WriteContext& ctx) override {
    Scene scene = ctx.scene("field");
    for (int i = 0; i < 20; ++i) scene.circle({static_cast<double>(i), 0.0}, 0.5, SceneColor{});
    const ScenePoint outline[] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    scene.polygon(outline, 4, SceneColor{});
    const int moving = kMoving[steps_ % 4];
    for (int i = 0; i < moving; ++i) {
      const double at = static_cast<double>(steps_) + i;
      scene.circle({at, -at}, 0.1, SceneColor{1.0f, 0.0f, 0.0f, 1.0f}, true);
      const ScenePoint line[] = {{at, 0}, {0, at}, {at, at}};
      scene.polyline(line, 3, SceneColor{});
    }
    ++steps_;
  }
  static constexpr int kMoving[] = {0, 1, 30, 2};
  std::int64_t steps_ = 0;
};

}  // namespace

TEST_CASE("a chained capture gives the reader every step's whole picture", "[record][scene]") {
  Registry registry = test::make_test_registry();
  registry.add_interface<Mover>("test.Mover");
  Manager manager(test::compile_text(
      "arbiter: 1\nname: moving\nlayers:\n  - name: world\n    interface: test.Mover\n", registry));
  detail::SnapshotGeneration generation(manager.program(), 0, 3);
  detail::StepImage image;  // the reader's
  const auto& shape = generation.blocks.shape();
  for (std::size_t i = 0; i < 40; ++i) {
    manager.step();
    // Step 10 is a whole capture again, as after a dropped step. Every seventh leaves its
    // picture out, as a Foxglove server's while no client shows the scene: the next picture is
    // whole all the same.
    const bool chained = i > 0 && i != 10;
    const auto picture = i % 7 == 3 ? CapturePicture::kLeaveOut : CapturePicture::kCopy;
    const auto block = generation.blocks[i % generation.blocks.size()];
    REQUIRE(detail::capture_step(manager, generation.layout, shape, block, false, &generation.last,
                                 chained, picture));
    detail::fence_streamed_stores();
    detail::StepSnapshot step(shape, block);
    step.apply(image);
    if (picture == CapturePicture::kLeaveOut) {
      CHECK(step.scene.size() == 0);
      CHECK(step.scene_points.size() == 0);
      continue;
    }
    const auto& drawn = manager.scene();
    REQUIRE(step.scene.size() == manager.scene_primitive_count());
    REQUIRE(step.scene_points.size() == drawn.point_count);
    INFO("step " << manager.steps());
    CHECK(std::memcmp(step.scene.data(), drawn.primitives,
                      step.scene.size() * sizeof(ScenePrimitive)) == 0);
    CHECK(std::memcmp(step.scene_points.data(), drawn.points,
                      step.scene_points.size() * sizeof(ScenePoint)) == 0);
    CHECK(std::memcmp(step.scene_strings, drawn.strings, drawn.string_size) == 0);
  }
}

namespace {

// Draws pictures of many sizes, the largest as much as a step may draw.
class Filler final : public Interface {
 public:
  void input(WriteContext& ctx) override {
    static constexpr std::size_t kPrimitives[] = {Manager::kScenePrimitivesPerStep, 2,  90,
                                                  Manager::kScenePrimitivesPerStep, 40, 127};
    static constexpr std::size_t kPoints[] = {Manager::kScenePointsPerStep, 2,  300, 17,
                                              Manager::kScenePointsPerStep, 511};
    Scene scene = ctx.scene("field");
    const auto at = static_cast<double>(steps_);
    const std::size_t points = kPoints[steps_ % 6];
    for (std::size_t i = 0; i < points; ++i) line_[i] = {at, static_cast<double>(i)};
    scene.polyline(line_, points, SceneColor{});
    // Texts of every length, in a frame of their own, among the circles: the strings' room
    // varies too.
    Scene other = ctx.scene("labels");
    const char* const text = "a label longer than the room a text has in a picture";
    for (std::size_t i = 1; i < kPrimitives[steps_ % 6]; ++i) {
      if (i % 7 == 0) {
        other.text({at, 0.0}, text + (steps_ + i) % 50, SceneColor{});
      } else {
        scene.circle({at, static_cast<double>(i)}, 0.1, SceneColor{});
      }
    }
    ++steps_;
  }
  std::size_t steps_ = 0;
  ScenePoint line_[Manager::kScenePointsPerStep];
};

}  // namespace

TEST_CASE("the pictures of steps not yet read are never written over", "[record][scene]") {
  // Each step's picture goes after the one before in one ring of pictures, whatever it draws:
  // with 3 blocks, 2 steps wait for the reader while the third is captured, and pictures of
  // every size, up to the most a step may draw, make the ring start again at every place.
  Registry registry = test::make_test_registry();
  registry.add_interface<Filler>("test.Filler");
  Manager manager(test::compile_text(
      "arbiter: 1\nname: filling\nlayers:\n  - name: world\n    interface: test.Filler\n",
      registry));
  detail::SnapshotGeneration generation(manager.program(), 0, 3);
  detail::StepImage image;  // the reader's
  const auto& shape = generation.blocks.shape();
  const auto count = generation.blocks.size();
  struct Drawn {
    std::vector<ScenePrimitive> primitives;
    std::vector<ScenePoint> points;
    std::string strings;
  };
  std::vector<Drawn> drawn;
  for (std::size_t i = 0; i < 200; ++i) {
    manager.step();
    REQUIRE(detail::capture_step(manager, generation.layout, shape, generation.blocks[i % count],
                                 false, &generation.last, i > 0));
    detail::fence_streamed_stores();
    const auto& scene = manager.scene();
    REQUIRE(scene.dropped == 0);
    drawn.push_back({{scene.primitives, scene.primitives + manager.scene_primitive_count()},
                     {scene.points, scene.points + scene.point_count},
                     {scene.strings, scene.string_size}});
    if (i + 1 < count) continue;
    const auto read = i + 1 - count;  // the oldest step still waiting
    detail::StepSnapshot step(shape, generation.blocks[read % count]);
    step.apply(image);
    INFO("step " << read + 1 << ", read after step " << i + 1);
    REQUIRE(step.scene.size() == drawn[read].primitives.size());
    REQUIRE(step.scene_points.size() == drawn[read].points.size());
    CHECK(std::memcmp(step.scene.data(), drawn[read].primitives.data(),
                      step.scene.size() * sizeof(ScenePrimitive)) == 0);
    CHECK(std::memcmp(step.scene_points.data(), drawn[read].points.data(),
                      step.scene_points.size() * sizeof(ScenePoint)) == 0);
    CHECK(std::string(step.scene_strings, drawn[read].strings.size()) == drawn[read].strings);
  }
}

TEST_CASE(
    "a step feed captures the steps only while its reader wants them, the picture only "
    "while it wants that",
    "[record][scene]") {
  Registry registry = test::make_test_registry();
  registry.add_interface<Mover>("test.Mover");
  Manager manager(test::compile_text(
      "arbiter: 1\nname: moving\nlayers:\n  - name: world\n    interface: test.Mover\n", registry));
  StepRing::Waiter waiter;
  StepRing ring(16, waiter);
  StepFeed feed(ring);
  CHECK_FALSE(feed.started());
  manager.add_observer(feed);
  CHECK(feed.started());
  // What the reader meets, after the start's header: the steps, and whether each drew.
  const auto read = [&] {
    ring.settle();
    std::vector<std::pair<std::uint64_t, bool>> steps;
    for (auto next = ring.next(); next != StepRing::Next::kNothing; next = ring.next()) {
      if (next == StepRing::Next::kStep) steps.emplace_back(ring.step().step(), ring.step().drew());
      ring.release();
    }
    return steps;
  };
  using Steps = std::vector<std::pair<std::uint64_t, bool>>;
  for (int i = 0; i < 3; ++i) manager.step();  // nobody wants them
  CHECK(read() == Steps{});
  feed.want(true, false);  // a client that plots
  manager.step();
  manager.step();
  CHECK(read() == Steps{{4, false}, {5, false}});
  feed.want(true, true);  // and one that shows the scene
  manager.step();
  feed.want(false, false);  // both gone
  manager.step();
  CHECK(read() == Steps{{6, true}});
  // A reader that shows the picture at a rate of its own asks for the next one: twice before a
  // step is still one picture.
  feed.want(true, false);
  feed.want_next_picture();
  feed.want_next_picture();
  manager.step();
  manager.step();
  feed.want_next_picture();
  manager.step();
  CHECK(read() == Steps{{8, true}, {9, false}, {10, true}});
  CHECK(ring.dropped() == 0);
  // Asked for while the ring is full, the picture comes with the first step captured after.
  for (int i = 0; i < 16; ++i) manager.step();  // steps 11 to 26 fill the ring
  feed.want_next_picture();
  manager.step();  // dropped
  CHECK(ring.dropped() == 1);
  const auto full = read();
  CHECK(full.size() == 16);
  manager.step();
  manager.step();
  CHECK(read() == Steps{{28, true}, {29, false}});
}

// Breakpoints (engine/tools/breakpoint): conditions parsed and resolved with located errors,
// evaluated after each step of a live run, `arbiter run --break` and `arbiter seek`.

#include <catch2/catch.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "arbiter/breakpoint.hpp"
#include "arbiter/manager.hpp"
#include "tooling_support.hpp"

using namespace arbiter;
using namespace arbiter::test;
using Json = nlohmann::json;

namespace {

const char* const kGoaliePlan = "configs/paper/goalie_plan.yaml";
const char* const kSoccer = "configs/soccer/walk_and_kick.yaml";

ConditionError parse_error(const std::string& text) {
  ConditionError error;
  INFO(text);
  REQUIRE_FALSE(parse_condition(text, error));
  return error;
}

/// A config of the source tree with breakpoints set on it.
struct Set {
  explicit Set(const std::string& config) : program(load_config(config, registry, diagnostics)) {}

  std::optional<Breakpoint> resolve(const std::string& text, ConditionError& error) const {
    auto condition = parse_condition(text, error);
    REQUIRE(condition);
    return resolve_breakpoint(program, std::move(*condition), error);
  }
  ConditionError error(const std::string& text) const {
    ConditionError error;
    INFO(text);
    REQUIRE_FALSE(resolve(text, error));
    return error;
  }
  Breakpoint breakpoint(const std::string& text) const {
    ConditionError error;
    auto resolved = resolve(text, error);
    INFO(text << ": " << error.message);
    REQUIRE(resolved);
    return std::move(*resolved);
  }

  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  Program program;
};

/// The steps of `steps` at which each condition fires in a live run of `config`, and the break
/// each step's events carry.
struct Fired {
  std::vector<std::uint64_t> steps;
  std::vector<std::string> marks;  // "by: text" of every break event
};

Fired fire(const std::string& config, const std::vector<std::string>& conditions, int steps) {
  Set set(config);
  Breakpoints breakpoints;
  for (const auto& text : conditions) breakpoints.add(set.breakpoint(text));
  Manager manager(std::move(set.program));
  manager.set_check(&breakpoints);
  Fired fired;
  for (int i = 0; i < steps; ++i) {
    manager.step();
    if (manager.break_text() == nullptr) continue;
    fired.steps.push_back(manager.steps());
    for (std::size_t e = 0; e < manager.event_count(); ++e) {
      const auto& event = manager.event(e);
      if (event.source == Manager::kBreakSource) {
        fired.marks.push_back(manager.event_source(event) + ": " + event.text);
      }
    }
  }
  return fired;
}

std::vector<Json> steps_of(const std::string& trace_path) {
  std::ifstream in(trace_path);
  std::vector<Json> out;
  for (std::string line; std::getline(in, line);) {
    auto json = Json::parse(line);
    if (json.contains("step") && !json.contains("safe")) out.push_back(std::move(json));
  }
  return out;
}

}  // namespace

TEST_CASE("every form of condition parses", "[breakpoint]") {
  ConditionError error;
  auto c = parse_condition("  kick_ball activates ", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kActivates);
  CHECK(c->name == "kick_ball");
  CHECK(c->text == "kick_ball activates");
  c = parse_condition("control/kick_ball deactivates", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kDeactivates);
  CHECK(c->name == "control/kick_ball");
  c = parse_condition("field_play/kick starts", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kStarts);
  c = parse_condition("goalie/dive ends", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kEnds);
  c = parse_condition("gait_velocity[0] > 0.5", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kAbove);
  CHECK(c->component == std::size_t{0});
  CHECK(c->bound == 0.5);
  c = parse_condition("head_angle<-0.1", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kBelow);
  CHECK_FALSE(c->component);
  CHECK(c->bound == -0.1);
  c = parse_condition(R"(event ~ "say \"hi\"")", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kEvent);
  CHECK(c->pattern == R"(say "hi")");
  c = parse_condition("step 171", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kStep);
  CHECK(c->step == 171);
  c = parse_condition("step >= 20", error);
  REQUIRE(c);
  CHECK(c->kind == Condition::Kind::kStepFrom);
  CHECK(c->step == 20);
}

TEST_CASE("a malformed condition is refused at the column of what is wrong", "[breakpoint]") {
  auto error = parse_error("kick_ball activate");
  CHECK(error.column == 11);
  CHECK(error.length == 8);
  CHECK(contains(error.message, "expected activates, deactivates, starts, ends, '>' or '<'"));
  REQUIRE_FALSE(error.notes.empty());
  CHECK(contains(error.notes.front().text, "did you mean 'activates'?"));
  error = parse_error("gait_velocity[x] > 1");
  CHECK(error.column == 15);
  error = parse_error("gait_velocity[0] >");
  CHECK(contains(error.message, "expected a number"));
  error = parse_error("head_angle > 1.2.3");
  CHECK(error.column == 14);
  CHECK(contains(error.message, "'1.2.3' is no number"));
  error = parse_error(R"(event ~ "open)");
  CHECK(error.column == 9);
  CHECK(contains(error.message, "not closed"));
  error = parse_error("event = \"x\"");
  CHECK(error.column == 7);
  error = parse_error("step 0");
  CHECK(error.column == 6);
  error = parse_error("step");
  CHECK(contains(error.message, "expected a step number"));
  error = parse_error("kick_ball activates now");
  CHECK(error.column == 21);
  CHECK(contains(error.message, "unexpected 'now'"));
  error = parse_error("kick_ball[0] activates");
  CHECK(contains(error.message, "'activates' takes none"));
  error = parse_error("");
  CHECK(error.message == "empty condition");
}

TEST_CASE("a name a condition cannot use is refused with its column and a suggestion",
          "[breakpoint]") {
  const Set paper(kWalkAndKick);
  auto error = paper.error("kick_bal activates");
  CHECK(error.column == 1);
  CHECK(error.length == 8);
  CHECK(error.code == "unknown-name");
  CHECK(error.message == "'kick_bal' names no behaviour of 'walk_and_kick'");
  REQUIRE(error.notes.size() == 1);
  CHECK(contains(error.notes[0].text, "did you mean 'kick_ball'?"));
  error = paper.error("kick activates");
  CHECK(error.message == "'kick' is an actuator: 'activates' takes a behaviour");
  error = paper.error("  gait_velocity > 1");
  CHECK(error.message == "'gait_velocity' is a vec3: pick a component, as gait_velocity[0]");
  error = paper.error("gait_velocity[3] > 1");
  CHECK(error.column == 15);
  CHECK(error.message == "'gait_velocity' is a vec3: its components are 0 to 2");
  error = paper.error("head_angle[1] > 1");
  CHECK(contains(error.message, "it has no components"));
  error = paper.error("kick_ball > 1");
  CHECK(error.message == "'kick_ball' is a behaviour: '>' takes an actuator");

  const Set goalie(kGoaliePlan);
  error = goalie.error("goalie starts");
  CHECK(error.message == "'goalie' is a state machine: 'starts' takes a state");
  REQUIRE(error.notes.size() == 1);
  CHECK(error.notes[0].text == "name one of its states, as goalie/STATE");
  error = goalie.error("goalie/monitr_ball ends");
  REQUIRE(error.notes.size() == 1);
  CHECK(contains(error.notes[0].text, "did you mean 'goalie/monitor_ball'?"));
}

TEST_CASE("a behaviour's breakpoints fire where its activation crosses zero, as the trace has it",
          "[breakpoint]") {
  const std::string trace = trace_of(kWalkAndKick, 40);
  std::vector<std::uint64_t> activates, deactivates;
  bool was = false;
  std::istringstream in(trace);
  for (std::string line; std::getline(in, line);) {
    const auto json = Json::parse(line);
    if (!json.contains("step")) continue;
    const bool active = json["layers"]["control"]["kick_ball"]["active"].get<bool>();
    if (active && !was) activates.push_back(json["step"]);
    if (!active && was) deactivates.push_back(json["step"]);
    was = active;
  }
  REQUIRE_FALSE(activates.empty());
  CHECK(fire(kWalkAndKick, {"kick_ball activates"}, 40).steps == activates);
  CHECK(fire(kWalkAndKick, {"control/kick_ball deactivates"}, 40).steps == deactivates);
  const auto fired = fire(kWalkAndKick, {"kick_ball activates"}, 40);
  CHECK(fired.marks == std::vector<std::string>(activates.size(), "break: kick_ball activates"));
}

TEST_CASE("a value's breakpoint fires when it crosses its bound, not while it stays beyond it",
          "[breakpoint]") {
  const std::string trace = trace_of(kWalkAndKick, 40);
  std::vector<std::uint64_t> above, below;
  bool was_above = false, was_below = false;
  std::istringstream in(trace);
  for (std::string line; std::getline(in, line);) {
    const auto json = Json::parse(line);
    if (!json.contains("step")) continue;
    const double forward = json["actuators"]["gait_velocity"]["value"][0].get<double>();
    if (forward > 0.2 && !was_above) above.push_back(json["step"]);
    if (forward < 0.1 && !was_below) below.push_back(json["step"]);
    was_above = forward > 0.2;
    was_below = forward < 0.1;
  }
  REQUIRE_FALSE(above.empty());
  REQUIRE(above.size() < 40);
  CHECK(fire(kWalkAndKick, {"gait_velocity[0] > 0.2"}, 40).steps == above);
  CHECK(fire(kWalkAndKick, {"gait_velocity[0] < 0.1"}, 40).steps == below);
}

TEST_CASE("a state's breakpoints fire at the steps it starts and ends", "[breakpoint]") {
  // goalie_plan: monitor_ball runs at steps 18-24 and 26-32 and 34-40 (its run's report).
  CHECK(fire(kGoaliePlan, {"goalie/monitor_ball starts"}, 45).steps ==
        std::vector<std::uint64_t>{18, 26, 34});
  CHECK(fire(kGoaliePlan, {"goalie/monitor_ball ends"}, 45).steps ==
        std::vector<std::uint64_t>{24, 32, 40});
}

TEST_CASE("step breakpoints fire at their step, or at every step from it", "[breakpoint]") {
  CHECK(fire(kWalkAndKick, {"step 7"}, 20).steps == std::vector<std::uint64_t>{7});
  CHECK(fire(kWalkAndKick, {"step >= 18"}, 20).steps == std::vector<std::uint64_t>{18, 19, 20});
  // Several: the first that fires names the break; each keeps its own state.
  const auto both = fire(kWalkAndKick, {"step 13", "kick_ball activates"}, 20);
  CHECK(both.steps == std::vector<std::uint64_t>{13});
  CHECK(both.marks == std::vector<std::string>{"break: step 13"});
}

TEST_CASE("arbiter run --break stops the soccer demo at the kick: its trace ends at that step",
          "[breakpoint][cli]") {
  TempDir dir;
  const auto whole = (dir.path() / "whole.jsonl").string();
  const auto broken = (dir.path() / "break.jsonl").string();
  REQUIRE(run_cli(std::string("run ") + kSoccer + " --steps 400 -q --trace " + test::quoted(whole))
              .exit_code == 0);
  std::uint64_t kick = 0;
  for (const auto& step : steps_of(whole)) {
    if (step["layers"]["control"]["kick_ball"]["active"].get<bool>()) {
      kick = step["step"];
      break;
    }
  }
  REQUIRE(kick > 0);
  const auto result =
      run_cli(std::string("run ") + kSoccer +
              " --steps 400 --break 'kick_ball activates' --trace " + test::quoted(broken));
  INFO(result.err);
  CHECK(result.exit_code == 0);
  CHECK(contains(result.out, fmt::format("step {:>4}  break: kick_ball activates\n", kick)));
  CHECK(contains(result.out,
                 fmt::format("stopped at the break after step {}: kick_ball activates", kick)));
  const auto steps = steps_of(broken);
  REQUIRE_FALSE(steps.empty());
  CHECK(steps.back()["step"] == kick);
  CHECK(steps.back()["reported"].back() ==
        Json({{"by", "break"}, {"text", "kick_ball activates"}}));
  // Paused as the page pauses it: the safe values are output after the break step.
  std::ifstream in(broken);
  std::string line, last;
  while (std::getline(in, line)) last = line;
  const auto safe = Json::parse(last);
  CHECK(safe["safe"] == true);
  CHECK(safe["step"] == kick);
  CHECK(safe["actuators"]["gait_velocity"]["value"] == Json::array({0.0, 0.0, 0.0}));
}

TEST_CASE("a recording of a run stopped at a break ends with the break's step, marked",
          "[breakpoint][cli]") {
  TempDir dir;
  const auto recording = (dir.path() / "run.mcap").string();
  const auto result =
      run_cli(std::string("run ") + kSoccer +
              " --steps 400 -q --break 'kick_ball activates' --record " + test::quoted(recording));
  REQUIRE(result.exit_code == 0);
  const auto source = open_trace(recording);
  TraceRecord record;
  Json last_step;
  while (source->next(record)) {
    if (record.kind == TraceRecord::Kind::kStep) last_step = Json::parse(record.text);
  }
  REQUIRE_FALSE(source->error());
  REQUIRE(last_step.is_object());
  CHECK(last_step["layers"]["control"]["kick_ball"]["active"] == true);
  CHECK(last_step["reported"].back() == Json({{"by", "break"}, {"text", "kick_ball activates"}}));
}

TEST_CASE("arbiter run --break with an event and a value condition stops where they become true",
          "[breakpoint][cli]") {
  TempDir dir;
  const auto trace = (dir.path() / "t.jsonl").string();
  auto result =
      run_cli(std::string("run ") + kSoccer +
              " --steps 400 -q --break 'event ~ \"goal\"' --trace " + test::quoted(trace));
  CHECK(result.exit_code == 0);
  auto steps = steps_of(trace);
  REQUIRE_FALSE(steps.empty());
  CHECK(steps.back()["reported"][0]["text"] == "goal!");
  result =
      run_cli(std::string("run ") + kGoaliePlan +
              " --steps 60 -q --break 'goalie/monitor_ball ends' --trace " + test::quoted(trace));
  CHECK(result.exit_code == 0);
  steps = steps_of(trace);
  REQUIRE_FALSE(steps.empty());
  CHECK(steps.back()["step"] == 24);
}

TEST_CASE("arbiter run --break reports a bad condition located in its argument, and runs nothing",
          "[breakpoint][cli]") {
  const auto result = run_cli(std::string("run ") + kWalkAndKick +
                              " --color never --break 'step 3' --break 'kick_bal activates'");
  CHECK(result.exit_code == 2);
  CHECK(result.out.empty());
  CHECK(result.err ==
        "--break:1:1: error[unknown-name]: 'kick_bal' names no behaviour of 'walk_and_kick'\n"
        "1 | kick_bal activates\n"
        "  | ^~~~~~~~\n"
        "--break:1:1: note: did you mean 'kick_ball'? known: go_behind_ball, head_control, "
        "kick_ball, search_for_ball\n");
}

TEST_CASE("arbiter seek finds the next step where a condition becomes true in a recording",
          "[breakpoint][cli]") {
  TempDir dir;
  const auto recording = (dir.path() / "run.mcap").string();
  const auto broken = (dir.path() / "break.jsonl").string();
  REQUIRE(
      run_cli(std::string("run ") + kSoccer + " --steps 400 -q --record " + test::quoted(recording))
          .exit_code == 0);
  REQUIRE(run_cli(std::string("run ") + kSoccer + " --steps 400 -q --break 'kick_ball activates'" +
                  " --trace " + test::quoted(broken))
              .exit_code == 0);
  const std::uint64_t kick = steps_of(broken).back()["step"];
  auto result = run_cli("seek --trace " + test::quoted(recording) + " 'kick_ball activates'");
  INFO(result.err);
  CHECK(result.exit_code == 0);
  CHECK(result.out == fmt::format("{}\n", kick));
  // The next kick, and a crossing that needs the step before --from.
  result = run_cli("seek --trace " + test::quoted(recording) + " 'kick_ball activates' --from " +
                   std::to_string(kick));
  CHECK(result.exit_code == 0);
  CHECK(std::stoull(result.out) > kick);
  result = run_cli("seek --trace " + test::quoted(recording) + " 'kick_ball deactivates' --from " +
                   std::to_string(kick));
  CHECK(result.out == fmt::format("{}\n", kick + 1));
  result = run_cli("seek --trace " + test::quoted(recording) + " 'head_angle < -5'");
  CHECK(result.exit_code == 1);
  CHECK(result.err == "arbiter seek: no step where head_angle < -5\n");
  result =
      run_cli("seek --color never --trace " + test::quoted(recording) + " 'kick_ball actives'");
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err, "CONDITION:1:11: error[bad-condition]: expected activates"));
}

TEST_CASE("arbiter seek reads a JSON-lines trace with its config: a state's start and end",
          "[breakpoint][cli]") {
  TempDir dir;
  const auto trace = (dir.path() / "g.jsonl").string();
  REQUIRE(
      run_cli(std::string("run ") + kGoaliePlan + " --steps 60 -q --trace " + test::quoted(trace))
          .exit_code == 0);
  auto result = run_cli(std::string("seek ") + kGoaliePlan + " --trace " + test::quoted(trace) +
                        " 'goalie/monitor_ball starts' --from 18");
  CHECK(result.out == "26\n");
  result = run_cli(std::string("seek ") + kGoaliePlan + " --trace " + test::quoted(trace) +
                   " 'goalie/monitor_ball ends'");
  CHECK(result.out == "24\n");
}

TEST_CASE(
    "a reload resolves the breakpoints again by name and one whose name is gone no longer fires",
    "[breakpoint]") {
  const Set paper(kWalkAndKick);
  Breakpoints breakpoints;
  breakpoints.add(paper.breakpoint("kick_ball activates"));
  // kick_ball has another index here: a breakpoint still keyed by the old one would watch
  // `other`, active from step 1.
  Registry registry = tooling_registry();
  Manager moved(test::compile_text(R"(arbiter: 1
name: moved
layers:
  - name: control
    behaviours:
      other: {type: scripted, params: {activation: 1}}
      kick_ball: {type: scripted, params: {activation: [0, 0, 1, 0]}}
)",
                                   registry));
  REQUIRE(*paper.program.find_behaviour("control", "kick_ball") !=
          *moved.program().find_behaviour("control", "kick_ball"));
  breakpoints.on_reload(moved);
  moved.set_check(&breakpoints);
  std::vector<std::uint64_t> fired;
  for (int i = 0; i < 5; ++i) {
    moved.step();
    if (moved.break_text() != nullptr) fired.push_back(moved.steps());
  }
  CHECK(fired == std::vector<std::uint64_t>{3});

  Manager gone(test::compile_text(R"(arbiter: 1
name: gone
layers:
  - name: control
    behaviours:
      other: {type: scripted, params: {activation: [0, 1]}}
)",
                                  registry));
  breakpoints.on_reload(gone);
  gone.set_check(&breakpoints);
  for (int i = 0; i < 3; ++i) {
    gone.step();
    CHECK(gone.break_text() == nullptr);
  }
  CHECK_FALSE(breakpoints.items().front().enabled);
}

TEST_CASE("a behaviour two layers have is named with its layer and alone it is ambiguous",
          "[breakpoint]") {
  Registry registry = tooling_registry();
  Manager manager(test::compile_text(R"(arbiter: 1
name: twin
layers:
  - name: upper
    behaviours:
      walk: {type: scripted, params: {activation: [0, 1]}}
  - name: lower
    behaviours:
      walk: {type: scripted, params: {activation: [0, 0, 0, 1]}}
)",
                                     registry));
  ConditionError error;
  auto condition = parse_condition("walk activates", error);
  REQUIRE(condition);
  CHECK_FALSE(resolve_breakpoint(manager.program(), *condition, error));
  CHECK(error.message == "'walk' is ambiguous");
  CHECK(error.column == 1);
  REQUIRE(error.notes.size() == 1);
  CHECK(error.notes[0].text == "write one of: upper/walk, lower/walk");
  condition = parse_condition("lower/walk activates", error);
  REQUIRE(condition);
  auto breakpoint = resolve_breakpoint(manager.program(), *condition, error);
  REQUIRE(breakpoint);
  Breakpoints breakpoints;
  breakpoints.add(std::move(*breakpoint));
  manager.set_check(&breakpoints);
  std::vector<std::uint64_t> fired;
  for (int i = 0; i < 5; ++i) {
    manager.step();
    if (manager.break_text() != nullptr) fired.push_back(manager.steps());
  }
  CHECK(fired == std::vector<std::uint64_t>{4});
}

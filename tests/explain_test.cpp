// explain (engine/tools/explain/explain.cpp) from a trace, and why a state ended as the trace's
// `ended`, run's report (cli/commands/run_report.cpp) and explain tell it.

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "arbiter/explain.hpp"
#include "arbiter/state.hpp"
#include "arbiter/trace.hpp"
#include "commands/run_report.hpp"
#include "tooling_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using namespace arbiter::test;
using Json = nlohmann::json;

namespace {

/// A config of the source tree, loaded as the CLI loads it, and the trace of its first `steps`
/// steps: what explain() is asked about.
struct Explained {
  Explained(const std::string& config, int steps)
      : program(load_config(config, registry, diagnostics)), trace(trace_of(config, steps)) {}

  Explanation at(std::uint64_t step, const std::string& target) const {
    return on(trace, step, target);
  }
  /// The text of an explanation that is expected to succeed; one that does not fails the test.
  std::string text_at(std::uint64_t step, const std::string& target) const {
    const Explanation explanation = at(step, target);
    INFO(explanation.text);
    REQUIRE(explanation.status == Explanation::Status::kOk);
    return explanation.text;
  }
  /// explain() on another trace than the run's own.
  Explanation on(const std::string& trace_text, std::uint64_t step,
                 const std::string& target) const {
    std::istringstream in(trace_text);
    return explain(program, in, step, target);
  }

  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  const Program program;
  const std::string trace;
};

}  // namespace

TEST_CASE("explain tells why search_for_ball is inactive at step 8 of the paper example",
          "[explain]") {
  const std::string text = Explained(kWalkAndKick, 20).text_at(8, "search_for_ball");
  check_golden("explain_search_for_ball.txt", text);
  CHECK(contains(text, "at step 8: inactive, activation 0\n"));
  CHECK(contains(text, "requested: 0.5\n"));
  CHECK(contains(text, "implicit, from chaining kick_ball => go_behind_ball => search_for_ball"));
  CHECK(contains(text, "inactive: go_behind_ball is fully active (factor 0)"));
}

TEST_CASE("explain gives the product of the factors and the normalisation", "[explain]") {
  const std::string text =
      Explained("tests/data/golden/relay.yaml", 6).text_at(2, "planning/retreat");
  // approach 0.6 => retreat 0.3: refined 0.3 × 0.4 = 0.12; wait 0.5 × 0.4 × 0.88 = 0.176;
  // the layer's sum is 0.6 + 0.12 + 0.176 = 0.896.
  CHECK(contains(text, "refined = 0.3 × 0.4 = 0.12\n"));
  CHECK(contains(text, "0.12 / 0.896 (the sum of the layer's refined levels) = 0.133929\n"));
  CHECK_FALSE(contains(text, "note:"));
}

TEST_CASE("explain names what steps an owned state machine", "[explain]") {
  const Explained run("tests/data/golden/relay.yaml", 6);
  CHECK(contains(run.text_at(2, "match"),
                 "stepped by: behaviour control/play, while it is active\n"));
  const std::string child = run.text_at(2, "attack_plan");
  CHECK(contains(child, "stepped by: state match/attack of its parent machine, while it runs\n"));
  CHECK(contains(child, "it was not stepped: match/attack did not step it in this step"));
}

TEST_CASE("explain tells what a state machine did in a step", "[explain]") {
  const Explained run("configs/paper/goalie_plan.yaml", 50);
  const std::string at_6 = run.text_at(6, "goalie");
  check_golden("explain_goalie.txt", at_6);
  CHECK(contains(at_6,
                 "events, in order: deactivate wait_for_button, activate walk_to_pose, execute "
                 "walk_to_pose\n"));
  CHECK(contains(run.text_at(2, "state_machines/goalie"),
                 "wait_for_button executed and held: it runs again at step 3"));
  // The scripted button press: the actual cause, not a list of the possible ones.
  CHECK(contains(run.text_at(40, "goalie"),
                 "    - monitor_ball was deactivated: pre-empted by wait_for_button (preempt: at "
                 "cycle 40); it had asked to proceed\n"));
}

TEST_CASE("explain tells how an aggregated actuator got its value", "[explain]") {
  const Explained run(kWalkAndKick, 20);
  // Step 5: go_behind_ball 0.3 and search_for_ball 0.5 × (1 - 0.3) = 0.35 both write
  // gait_velocity: (0.3 · [0.3, 0.1, 0] + 0.35 · [0, 0, 0.6]) / 0.65.
  const std::string text = run.text_at(5, "gait_velocity");
  check_golden("explain_gait_velocity.txt", text);
  CHECK(contains(text, "aggregated) at step 5: [0.1385, 0.04615, 0.3231], written\n"));
  CHECK(contains(text, "go_behind_ball   activation 0.3   weight 0.3 / 0.65 = 0.461538\n"));
  CHECK(contains(text, "search_for_ball  activation 0.35  weight 0.35 / 0.65 = 0.538462\n"));
  // Step 9: search_for_ball is inhibited, so its writes are ignored.
  const std::string alone = run.text_at(9, "actuators/gait_velocity");
  CHECK(contains(alone, "go_behind_ball  activation 1  weight 1 / 1 = 1\n"));
  CHECK(contains(alone,
                 "inactive writers (activation 0, their writes are ignored): "
                 "search_for_ball\n"));
}

TEST_CASE("explain tells which step's value a held actuator keeps", "[explain]") {
  const Explained run(kWalkAndKick, 20);
  // kick_ball kicks in steps 13 to 15 and is inactive from step 16.
  const std::string held = run.text_at(16, "kick");
  check_golden("explain_kick_held.txt", held);
  CHECK(contains(held, "at step 16: true, held\n"));
  CHECK(contains(held, "it keeps the value written at step 15 (true)\n"));
  CHECK(contains(run.text_at(14, "kick"),
                 "written by kick_ball (activation 1): the most active writer"));
  CHECK(contains(run.text_at(3, "kick"), "held: nothing has written it yet"));
  // The views give explain the steps around the one asked for: here the header and steps 16 to
  // 18, which cannot tell which earlier step wrote the value held.
  std::istringstream lines(run.trace);
  std::string excerpt;
  int line_number = 0;  // 0: the header, then the step of that number
  for (std::string line; std::getline(lines, line); ++line_number) {
    if (line_number == 0 || (line_number >= 16 && line_number <= 18)) excerpt += line + "\n";
  }
  CHECK(contains(run.on(excerpt, 16, "kick").text,
                 "held: nobody wrote it in this step; the trace given starts here"));
  CHECK(contains(run.on(excerpt, 17, "kick").text,
                 "held: nobody wrote it in steps 16 to 17; the trace given starts at step 16, so "
                 "the step it was written in is not known\n"));
}

TEST_CASE("explain tells why a state ran at a step", "[explain][scl]") {
  const Explained run("configs/paper/goalie_plan.yaml", 50);
  // The button pressed again at cycle 40 pre-empts the plan back to wait_for_button.
  const std::string preempted = run.text_at(41, "goalie/wait_for_button");
  check_golden("explain_goalie_wait_for_button.txt", preempted);
  CHECK(contains(preempted, "at step 41: running (cycle 41)\n"));
  CHECK(contains(preempted,
                 "started at step 40: activated when monitor_ball ended: pre-empted by "
                 "wait_for_button (preempt: at cycle 40)"));
  CHECK(contains(preempted, "ended at step 45: proceeded, queue empty\n"));
  // monitor_ball plans a walk and another monitor_ball behind it.
  const std::string planned = run.text_at(38, "goalie/monitor_ball");
  CHECK(contains(planned, "started at step 34: activated when walk_to_pose ended: proceeded\n"));
  CHECK(contains(planned, "planned: entered the queue at step 31, while monitor_ball ran\n"));
  CHECK(contains(planned, "ended at step 40: pre-empted by wait_for_button"));
  const std::string queued = run.text_at(3, "goalie/monitor_ball");
  CHECK(contains(queued,
                 "queued, position 3 of [walk_to_pose, obstacle_ahead, monitor_ball] "
                 "(behind wait_for_button)\n"));
  CHECK(contains(queued, "it runs next from step 18\n"));
  // The views give explain the steps around the one asked for: steps 7 to 9 of walk_to_pose's
  // run from step 6 to 12.
  std::istringstream lines(run.trace);
  std::string excerpt;
  int line_number = 0;  // 0: the header, then the step of that number
  for (std::string line; std::getline(lines, line); ++line_number) {
    if (line_number == 0 || (line_number >= 7 && line_number <= 9)) excerpt += line + "\n";
  }
  const auto part = run.on(excerpt, 8, "goalie/walk_to_pose");
  CHECK(contains(part.text,
                 "at step 8: running (cycle 8)\n  started before step 7, the first of "
                 "the trace given\n"));
  CHECK(contains(run.text_at(41, "goalie/monitor_ball"),
                 "not running and not queued\n  it last ran from step 34 to step 40, and ended: "
                 "pre-empted"));
}

namespace {

/// A run of a config of one state machine `m`, with the test classes: its trace, run's report,
/// and what explain says about `m` at every step.
struct Story {
  std::vector<Json> records;  ///< per step, from 1 (0: the header)
  std::string report;
  std::vector<std::string> explained;  ///< per step, from 1 (0: unused)

  /// The trace's `ended` of `m` at `step` (null when there is none).
  const Json& ended(std::size_t step) const {
    static const Json kNull;
    const Json& entry = records.at(step)["controllers"]["m"];
    return entry.contains("ended") ? entry["ended"] : kNull;
  }
};

Story story_of(const std::string& states, const std::string& queue, int steps,
               const std::string& extra = "", ControllerHooks* hooks = nullptr) {
  const std::string yaml = "arbiter: 1\nname: t\nstate_machines:\n  m:\n    states:\n" + states +
                           "    queue: " + queue + "\n" + extra;
  Registry registry = tooling_registry();
  Manager manager(test::compile_text(yaml, registry));
  if (hooks != nullptr) manager.program().find_controller("m")->set_hooks(hooks);
  std::ostringstream trace_out;
  std::ostringstream report_out;
  TraceWriter trace(trace_out);
  cli::RunReport report(report_out, false);
  manager.add_observer(trace);
  manager.add_observer(report);
  for (int i = 0; i < steps; ++i) manager.step();
  manager.finish();
  Story story;
  story.report = report_out.str();
  std::istringstream lines(trace_out.str());
  for (std::string line; std::getline(lines, line);) story.records.push_back(Json::parse(line));
  story.explained.emplace_back();
  for (int step = 1; step <= steps; ++step) {
    std::istringstream in(trace_out.str());
    const auto explanation = explain(manager.program(), in, static_cast<std::uint64_t>(step), "m");
    REQUIRE(explanation.status == Explanation::Status::kOk);
    story.explained.push_back(explanation.text);
  }
  return story;
}

}  // namespace

TEST_CASE("a state that asked to proceed ended because it proceeded", "[scl][explain][run]") {
  const auto story = story_of("      a: scripted\n      b: scripted\n", "[a, b]", 2);
  CHECK(story.ended(1).is_null());
  CHECK(story.ended(2) == Json::parse(R"([{"state": "a", "cause": "proceeded"}])"));
  CHECK(contains(story.report,
                 "step    2  m: a ended (proceeded)\n"
                 "step    2  m: b (cycle 2; queued: nothing)\n"));
  CHECK(contains(story.explained[2], "    - a was deactivated: proceeded\n"));
  CHECK(contains(story.explained[1], "    - a executed and is deactivated at step 2: proceeded\n"));
}

TEST_CASE("a state that proceeded with nothing queued ended the machine", "[scl][explain][run]") {
  const auto story = story_of("      a: scripted\n", "[a]", 2);
  CHECK(story.ended(2) == Json::parse(R"([{"state": "a", "cause": "queue_empty"}])"));
  CHECK(contains(story.report,
                 "step    2  m: a ended (proceeded, queue empty)\n"
                 "step    2  m: finished\n"));
  CHECK(contains(story.explained[2], "    - a was deactivated: proceeded, queue empty\n"));
}

TEST_CASE("a pre-empted state says what pre-empted it", "[scl][explain][run]") {
  SECTION("the config's preempt: entry") {
    const auto story = story_of(
        "      wait: {type: scripted, params: {hold: 100}}\n"
        "      walk: {type: scripted, params: {hold: 100}}\n",
        "[wait, walk]", 3,
        "    preempt:\n      - {cycle: 2, go_to: wait}\n      - {cycle: 3, go_to: walk}\n");
    CHECK(story.ended(3) ==
          Json::parse(R"([{"state": "wait", "cause": "preempted", "to": "walk", "preempt": 1}])"));
    CHECK(contains(story.report,
                   "step    3  m: wait ended (pre-empted by walk (preempt: at cycle 3))\n"));
    CHECK(contains(story.explained[3],
                   "    - wait was deactivated: pre-empted by walk (preempt: at cycle 3)\n"));
    // At cycle 2 the pre-emption planned wait again: the wait of cycle 1 ended for it.
    CHECK(story.ended(2)[0]["to"] == "wait");
  }
  SECTION("a hook, after the state had asked to proceed") {
    struct ButtonPress : ControllerHooks {
      PlannedState target;
      bool pre_step(Controller& controller, Plan& plan) override {
        if (controller.cycle() != 2) return false;
        // Kept by the hooks: the planned instance refers to it.
        target = test::planned(controller, "walk");
        plan.go_to(target);
        return true;
      }
    } hooks;
    const auto story =
        story_of("      wait: scripted\n      walk: scripted\n      other: scripted\n",
                 "[wait, other]", 2, "", &hooks);
    CHECK(story.ended(2) == Json::parse(R"([{"state": "wait", "cause": "preempted", "to": "walk",
                                             "proceeded": true}])"));
    CHECK(contains(story.report,
                   "step    2  m: wait ended (pre-empted by walk; it had asked to proceed)\n"));
    CHECK(contains(story.explained[2],
                   "    - wait was deactivated: pre-empted by walk; it had asked to proceed\n"));
  }
}

TEST_CASE("a state that went to another with go_to says so", "[scl][explain][run]") {
  const auto story = story_of(
      "      a: {type: test.Planner, params: {op: go_to, target: c}}\n"
      "      b: scripted\n      c: scripted\n",
      "[a, b, b]", 2);
  CHECK(story.ended(2) == Json::parse(R"([{"state": "a", "cause": "go_to", "to": "c"}])"));
  CHECK(contains(story.report, "step    2  m: a ended (go_to c)\n"));
  CHECK(contains(story.explained[2], "    - a was deactivated: go_to c\n"));
}

TEST_CASE("a state that terminated its machine says so", "[scl][explain][run]") {
  SECTION("itself, in the step it ran") {
    const auto story = story_of(
        "      a: {type: scripted, params: {terminate: true}}\n      b: scripted\n", "[a, b]", 1);
    CHECK(story.ended(1) == Json::parse(R"([{"state": "a", "cause": "terminated", "by": "a"}])"));
    CHECK(contains(story.report,
                   "step    1  m: a ended (terminated)\n"
                   "step    1  m: finished\n"));
    CHECK(contains(story.explained[1], "    - a was deactivated: terminated\n"));
  }
  SECTION("the state after a proceeding one, in its activate()") {
    const auto story = story_of(
        "      a: scripted\n      b: {type: test.Planner, params: {op: terminate_in_activate}}\n",
        "[a, b]", 2);
    CHECK(story.ended(2) == Json::parse(R"([{"state": "a", "cause": "proceeded"},
                                            {"state": "b", "cause": "terminated", "by": "b"}])"));
    CHECK(contains(story.report,
                   "step    2  m: a ended (proceeded)\n"
                   "step    2  m: b (cycle 2; queued: nothing)\n"
                   "step    2  m: b ended (terminated)\n"
                   "step    2  m: finished\n"));
    CHECK(contains(story.explained[2],
                   "    - a was deactivated: proceeded\n"
                   "    - b became the current state (the head of the queue) "
                   "and was activated\n"
                   "    - b was deactivated: terminated\n"));
  }
}

TEST_CASE("a planned state shows its per-instance params", "[scl][explain][run]") {
  // From the config's queue, and from a Plan call at run time (x passed by test.Planner).
  const auto story = story_of(
      "      p: test.Pose\n      a: {type: test.Planner, params: {op: append, target: p, "
      "x: 2.5}}\n",
      "[{p: {x: 1.25}}, a]", 4);
  CHECK(story.records[1]["controllers"]["m"]["params"] == Json::parse(R"({"x": 1.25})"));
  CHECK(story.ended(2) ==
        Json::parse(R"([{"state": "p", "params": {"x": 1.25}, "cause": "proceeded"}])"));
  CHECK_FALSE(story.records[2]["controllers"]["m"].contains("params"));  // a has none of its own
  CHECK(story.records[3]["controllers"]["m"]["params"] == Json::parse(R"({"x": 2.5})"));
  CHECK(contains(story.report,
                 "step    1  m: p {x: 1.25} (cycle 1; queued: a)\n"
                 "step    2  m: p {x: 1.25} ended (proceeded)\n"
                 "step    2  m: a (cycle 2; queued: p)\n"
                 "step    3  m: a ended (proceeded)\n"
                 "step    3  m: p {x: 2.5} (cycle 3; queued: nothing)\n"
                 "step    4  m: p {x: 2.5} ended (proceeded, queue empty)\n"));
  CHECK(contains(story.explained[1], "after the step: state p {x: 1.25}; queue: a\n"));
  CHECK(contains(story.explained[2], "    - p {x: 1.25} was deactivated: proceeded\n"));
  CHECK(contains(story.explained[3],
                 "    - p {x: 2.5} became the current state (the head of the queue)"));
}

TEST_CASE("explain reads a trace of a run reloaded with --watch", "[explain][reload]") {
  const Explained run(kWalkAndKick, 10);
  std::vector<std::string> lines;
  {
    std::istringstream in(run.trace);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
  }
  REQUIRE(lines.size() == 11);
  // The header a reload after step 5 writes, for the program it swapped in.
  const auto reload_header = [](std::string header) {
    const std::string start = "{\"arbiter_trace\": 1, ";
    REQUIRE(header.rfind(start, 0) == 0);
    return start + "\"reload\": 1, \"after_step\": 5, " + header.substr(start.size());
  };
  const auto reloaded = [&](const std::string& header) {
    std::string text;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      if (i == 6) text += reload_header(header) + "\n";
      text += lines[i] + "\n";
    }
    return text;
  };
  const auto explain_text = [&](const std::string& trace, std::uint64_t step) {
    return run.on(trace, step, "search_for_ball");
  };
  std::string other_header;
  std::getline(std::istringstream(trace_of("configs/paper/hierarchical.yaml", 1)) >> std::ws,
               other_header);

  // Reloaded into the config given: steps on both sides of the reload are explained.
  const std::string same = reloaded(lines[0]);
  CHECK(explain_text(same, 3).status == Explanation::Status::kOk);
  std::string whole;
  for (const auto& line : lines) whole += line + "\n";
  const auto after = explain_text(same, 7);
  REQUIRE(after.status == Explanation::Status::kOk);
  CHECK(after.text == explain_text(whole, 7).text);

  // Reloaded into another config: the steps before it still match this one, those after do not.
  const std::string other = reloaded(other_header);
  CHECK(explain_text(other, 5).status == Explanation::Status::kOk);
  const auto mismatch = explain_text(other, 7);
  CHECK(mismatch.status == Explanation::Status::kBadTrace);
  CHECK(mismatch.text == "the trace was written for 'hierarchical', not for 'walk_and_kick'");
}

TEST_CASE("a step that a trace lacks is told with the steps the trace has, wherever they start",
          "[explain]") {
  const Explained run(kWalkAndKick, 6);
  // The header and steps 3, 4 and 6: a trace cut at its start, with a step left out.
  std::vector<std::string> lines;
  std::istringstream in(run.trace);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  REQUIRE(lines.size() >= 7);
  const std::string cut = lines[0] + "\n" + lines[3] + "\n" + lines[4] + "\n" + lines[6] + "\n";
  REQUIRE(run.on(cut, 4, "search_for_ball").status == Explanation::Status::kOk);
  auto result = run.on(cut, 1, "search_for_ball");
  CHECK(result.status == Explanation::Status::kNotFound);
  CHECK(result.text == "the trace starts at step 3, after step 1");
  result = run.on(cut, 5, "search_for_ball");
  CHECK(result.status == Explanation::Status::kNotFound);
  CHECK(result.text == "the trace has no step 5: it goes from step 4 to step 6");
  result = run.on(cut, 9, "search_for_ball");
  CHECK(result.status == Explanation::Status::kNotFound);
  CHECK(result.text == "the trace has steps 3 to 6, not step 9");
  // A state is told from the whole run, read to its end: the gap is still named by the steps
  // around it.
  const Explained goalie("configs/paper/goalie_plan.yaml", 12);
  std::vector<std::string> goalie_lines;
  std::istringstream goalie_in(goalie.trace);
  for (std::string line; std::getline(goalie_in, line);) goalie_lines.push_back(line);
  REQUIRE(goalie_lines.size() >= 13);
  std::string gap;
  for (std::size_t i = 0; i < goalie_lines.size(); ++i) {
    if (i != 5) gap += goalie_lines[i] + "\n";
  }
  result = goalie.on(gap, 5, "goalie/walk_to_pose");
  CHECK(result.status == Explanation::Status::kNotFound);
  CHECK(result.text == "the trace has no step 5: it goes from step 4 to step 6");
}

TEST_CASE("a trace whose activation is not a number is noted, not taken as agreeing", "[explain]") {
  const Explained run(kWalkAndKick, 3);
  std::string edited = run.trace;
  const std::string recorded = "\"search_for_ball\": {\"requested\": 1.0, \"activation\": 1.0";
  const auto at = edited.find(recorded, edited.find("\"step\": 2"));
  REQUIRE(at != std::string::npos);
  edited.replace(at, recorded.size(),
                 "\"search_for_ball\": {\"requested\": 1.0, \"activation\": \"x\"");
  const auto result = run.on(edited, 2, "search_for_ball");
  REQUIRE(result.status == Explanation::Status::kOk);
  CHECK(contains(result.text,
                 "note: the trace records no activation level here (its 'activation' is a "
                 "string): the recomputation above is not checked against it"));
  CHECK_FALSE(contains(run.text_at(2, "search_for_ball"), "note:"));
}

TEST_CASE("explain reports what it cannot explain", "[explain]") {
  const Explained run(kWalkAndKick, 20);
  auto result = run.at(8, "search_for_bal");
  CHECK(result.status == Explanation::Status::kNotFound);
  REQUIRE(!result.notes.empty());
  CHECK(contains(result.notes[0].text, "did you mean 'search_for_ball'?"));
  result = run.at(8, "gait_velocty");
  REQUIRE(!result.notes.empty());
  CHECK(contains(result.notes[0].text, "did you mean 'gait_velocity'?"));
  CHECK(result.text ==
        "'gait_velocty' names no behaviour, state machine, state (machine/state) or "
        "actuator of 'walk_and_kick'");
  const auto state = Explained("configs/paper/goalie_plan.yaml", 3).at(2, "goalie/monitor_bal");
  CHECK(state.status == Explanation::Status::kNotFound);
  REQUIRE(!state.notes.empty());
  CHECK(contains(state.notes[0].text, "did you mean 'goalie/monitor_ball'?"));
  result = run.at(21, "search_for_ball");
  CHECK(result.status == Explanation::Status::kNotFound);
  CHECK(result.text == "the trace has steps 1 to 20, not step 21");
  result = run.on(trace_of("configs/paper/hierarchical.yaml", 3), 2, "kick_ball");
  CHECK(result.status == Explanation::Status::kBadTrace);
  CHECK(result.text == "the trace was written for 'hierarchical', not for 'walk_and_kick'");
  result = run.on("{\"arbiter_trace\": 1, \"name\": \"walk_and_kick\"\n", 1, "kick_ball");
  CHECK(result.status == Explanation::Status::kBadTrace);
}

TEST_CASE("arbiter explain runs from a trace file", "[explain][cli]") {
  const fs::path trace =
      fs::temp_directory_path() / ("arbiter_explain_" + std::to_string(::getpid()) + ".jsonl");
  REQUIRE(
      run_cli(std::string("run -q --steps 20 --trace \"") + trace.string() + "\" " + kWalkAndKick)
          .exit_code == 0);
  const std::string base =
      std::string("explain ") + kWalkAndKick + " --trace \"" + trace.string() + "\"";
  const auto ok = run_cli(base + " --step 8 search_for_ball");
  CHECK(ok.exit_code == 0);
  CHECK(ok.out == read_text(kGoldenDir / "explain_search_for_ball.txt"));
  CHECK(run_cli(base + " --step 8 control/search_for_ball").exit_code == 0);
  const auto held = run_cli(base + " --step 16 kick");
  CHECK(held.exit_code == 0);
  CHECK(held.out == read_text(kGoldenDir / "explain_kick_held.txt"));
  const auto unknown = run_cli(base + " --step 8 nobody");
  CHECK(unknown.exit_code == 2);
  CHECK(contains(unknown.err, "arbiter explain: 'nobody' names no behaviour"));
  CHECK(run_cli(base + " --step 99 kick_ball").exit_code == 2);
  CHECK(run_cli(std::string("explain ") + kWalkAndKick + " --step 1 kick_ball").exit_code == 2);
  fs::remove(trace);
}

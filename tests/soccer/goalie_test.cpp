// The goalie demo (configs/soccer/goalie.yaml, plugins/soccer/goalie.cpp): its state machine
// waits, takes its place, re-plans, dives and is pre-empted by the button.

#include <catch2/catch.hpp>
#include <string>

#include "soccer_support.hpp"
#include "test_support.hpp"

using arbiter::Controller;
using arbiter::ControllerStatus;
using arbiter::Manager;
using arbiter::Registry;
using arbiter::soccer::Point;
using arbiter::soccer::Pose;
using arbiter::soccer::World;
using namespace arbiter::soccer::test;

TEST_CASE("the goalie waits for the button, takes its place, re-plans and dives at a shot",
          "[soccer][goalie]") {
  const Registry registry = soccer_registry();
  Manager manager(arbiter::test::compile_text(read_file(kGoalieConfig), registry, kGoalieConfig));
  StoryLog log;
  manager.add_observer(log);
  const Controller& goalie = *manager.program().find_controller("goalie");
  const World& world = *world_link(manager).world();

  for (int i = 0; i < 9; ++i) manager.step();
  CHECK(goalie.current_state() == "wait_for_button");
  CHECK(arbiter::test::activation_of(manager, "control", "goalie") == 1.0);
  for (int i = 0; i < 400; ++i) manager.step();
  INFO(::Catch::Detail::stringify(log.lines));

  const auto activations = lines_with(log, "activate");
  REQUIRE(activations.size() >= 6);
  // The button is pressed in step 10 (config: button_step); the walk starts in the next step.
  CHECK(activations[0] == "1 activate wait_for_button");
  CHECK(activations[1] == "11 activate walk_to_pose");
  CHECK_THAT(activations[2], Catch::EndsWith("activate monitor_ball"));
  // monitor_ball finds a better place than the configured one and plans a walk there, then
  // itself again.
  CHECK_THAT(activations[3], Catch::EndsWith("activate walk_to_pose"));
  CHECK_THAT(activations[4], Catch::EndsWith("activate monitor_ball"));
  // The shot leaves at the end of step 200 (config: shot_step); the goalie dives when it first
  // sees the ball coming, lies for 2 s (30 steps) and monitors again.
  CHECK(activations[5] == "201 activate dive");
  // The world reports the shot in the input pass, before the goalie sees it and dives.
  CHECK(lines_with(log, "201 ") == std::vector<std::string>{"201 world: shot on goal",
                                                            "201 activate dive",
                                                            "201 goalie/dive: goalie dives left"});
  REQUIRE(activations.size() >= 7);
  CHECK(activations[6] == "231 activate monitor_ball");
  CHECK(lines_with(log, "world: ball saved").size() == 1);
  CHECK(lines_with(log, "goal!").empty());
  CHECK(world.goals_at(-1) == 0);

  // The first walk took the robot to the configured pose, the second to one on the line from the
  // goal's centre to the ball, facing the ball: other params, planned at run time.
  const Pose placed = log.poses[2];
  CHECK(placed.x == Approx(-4.2).margin(0.1));
  CHECK(placed.y == Approx(0.0).margin(0.1));
  CHECK(placed.theta == Approx(0.0).margin(0.15));
  const Pose replanned = log.poses[4];
  const Point ball{-1.5, 1.8};  // the config's ball_start
  const Point to_ball = ball - Point{-4.5, 0.0};
  const Point expected = Point{-4.5, 0.0} + (0.5 / arbiter::soccer::norm(to_ball)) * to_ball;
  CHECK(replanned.x == Approx(expected.x).margin(0.1));
  CHECK(replanned.y == Approx(expected.y).margin(0.1));
  CHECK(replanned.theta == Approx(arbiter::soccer::bearing(ball - expected)).margin(0.15));
  CHECK(std::abs(replanned.theta - placed.theta) > 0.3);

  CHECK(goalie.status() == ControllerStatus::kRunning);
  CHECK(goalie.current_state() == "monitor_ball");
  CHECK(goalie.queue_size() == 0);
}

TEST_CASE("a button press pre-empts the goalie back to waiting", "[soccer][goalie]") {
  const Registry registry = soccer_registry();
  Manager manager(arbiter::test::compile_text(read_file(kGoalieConfig), registry, kGoalieConfig));
  StoryLog log;
  manager.add_observer(log);
  const Controller& goalie = *manager.program().find_controller("goalie");
  World& world = *world_link(manager).world();
  const auto step_until = [&](std::uint64_t step) {
    while (manager.steps() < step) manager.step();
  };

  SECTION("while walking: the robot stops where it is") {
    step_until(40);
    REQUIRE(goalie.current_state() == "walk_to_pose");
    world.press_button();
    manager.step();
    CHECK(goalie.current_state() == "wait_for_button");
    CHECK(goalie.queued(0) == "monitor_ball");
    CHECK(lines_with(log, "41 ") ==
          std::vector<std::string>{"41 world: button pressed", "41 activate wait_for_button"});
    const Pose stopped = world.robot();
    step_until(80);
    CHECK(goalie.current_state() == "wait_for_button");
    CHECK(world.robot().x == Approx(stopped.x).margin(0.05));
    CHECK(world.robot().y == Approx(stopped.y).margin(0.05));

    // The next press ends the wait; monitor_ball then looks for the ball and plans the walk to
    // its place.
    world.press_button();
    manager.step();
    CHECK(goalie.current_state() == "wait_for_button");
    manager.step();
    CHECK(goalie.current_state() == "monitor_ball");
    // The head sweeps until it finds the ball, which lies behind the robot's right shoulder.
    step_until(manager.steps() + 60);
    CHECK(lines_with(log, "activate walk_to_pose").size() == 2);
  }
  SECTION("while diving: the shot is not dived for again") {
    step_until(205);
    REQUIRE(goalie.current_state() == "dive");
    world.press_button();
    manager.step();
    CHECK(goalie.current_state() == "wait_for_button");
    step_until(260);
    CHECK(goalie.current_state() == "wait_for_button");
    CHECK(lines_with(log, "activate dive").size() == 1);
  }
}

TEST_CASE("a state the goalie's plan needs but its machine lacks is a clear error",
          "[soccer][goalie][errors]") {
  const Registry registry = soccer_registry();
  const std::string config = read_file(kGoalieConfig);

  SECTION("planned by monitor_ball: the load fails at the state") {
    const std::string without_walk =
        edited(edited(config, "      walk_to_pose: soccer.WalkToPose\n", ""),
               "      - walk_to_pose: {x: -4.2, y: 0.0, theta: 0.0}", "");
    const auto diagnostics = arbiter::test::diagnose_text(without_walk, registry, "goalie.yaml");
    REQUIRE(diagnostics.has_errors());
    CHECK_THAT(arbiter::format(diagnostics),
               Catch::Contains("goalie.yaml:53:7: error: state machine 'goalie' "
                               "has no state 'walk_to_pose'"));
  }
  SECTION("planned by the goalie's hooks: the load fails, naming the state") {
    const std::string without_dive =
        edited(config, "      dive: {type: soccer.Dive, params: {duration: 2.0}}\n", "");
    const auto diagnostics = arbiter::test::diagnose_text(without_dive, registry, "goalie.yaml");
    REQUIRE(diagnostics.has_errors());
    CHECK_THAT(
        arbiter::format(diagnostics),
        Catch::Contains("the goalie plans state 'dive' (dive_state), which state machine "
                        "'goalie' does not declare") &&
            Catch::Contains("note: it declares: monitor_ball, wait_for_button, walk_to_pose"));
  }
}

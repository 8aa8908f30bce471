// The soccer demo config (configs/soccer/walk_and_kick.yaml) run end to end: the robot finds,
// approaches and kicks the ball into the goal, the same way for the same seed.

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <string>

#include "soccer_support.hpp"
#include "test_support.hpp"

using arbiter::Manager;
using arbiter::Registry;
using namespace arbiter::soccer::test;

namespace {

constexpr double kPi = arbiter::soccer::kPi;

struct Outcome {
  std::uint64_t first_kick = 0;  ///< the step in which kick_ball first became active
  std::uint64_t goal = 0;        ///< the step after which the ball was in the goal
  int goal_side = 0;
  int kicks = 0;
  std::uint64_t steps = 0;
  bool kick_and_approach_together = false;
};

/// Steps the manager until a goal or `max_steps`, watching the kick and approach behaviours.
Outcome play(Manager& manager, std::uint64_t max_steps) {
  const auto& program = manager.program();
  const auto kick_ball = *program.find_behaviour("control", "kick_ball");
  const auto go_behind_ball = *program.find_behaviour("control", "go_behind_ball");
  const arbiter::soccer::World& world = *world_link(manager).world();
  Outcome outcome;
  while (manager.steps() < max_steps) {
    manager.step();
    if (manager.active(kick_ball) && manager.active(go_behind_ball)) {
      outcome.kick_and_approach_together = true;
    }
    if (manager.active(kick_ball) && outcome.first_kick == 0) outcome.first_kick = manager.steps();
    if (world.goals_at(1) + world.goals_at(-1) > 0) {
      outcome.goal = manager.steps();
      outcome.goal_side = world.goals_at(1) > 0 ? 1 : -1;
      break;
    }
  }
  outcome.kicks = world.kicks();
  outcome.steps = manager.steps();
  return outcome;
}

}  // namespace

TEST_CASE("the soccer demo config kicks the ball into the goal", "[soccer][demo]") {
  const Registry registry = soccer_registry();
  Manager manager(arbiter::test::compile_text(read_file(kDemoConfig), registry, kDemoConfig));
  const Outcome outcome = play(manager, 1500);
  INFO("first kick at step " << outcome.first_kick << ", goal at step " << outcome.goal);
  CHECK_FALSE(outcome.kick_and_approach_together);
  CHECK(outcome.first_kick > 0);
  CHECK(outcome.goal_side == 1);
}

TEST_CASE("the same config and seed give the same game", "[soccer][demo]") {
  const Registry registry = soccer_registry();
  const auto trajectory = [&](int seed) {
    Manager manager(arbiter::test::compile_text(
        demo_config_with({-3.0, -1.0, 0.0}, {0.5, 1.0}, seed), registry, "seeded.yaml"));
    std::vector<double> xs;
    for (int i = 0; i < 200; ++i) {
      manager.step();
      xs.push_back(world_link(manager).world()->robot().x);
    }
    return xs;
  };
  CHECK(trajectory(5) == trajectory(5));
  CHECK(trajectory(5) != trajectory(6));
}

TEST_CASE("from varied starts the robot finds, approaches and kicks the ball", "[soccer][demo]") {
  struct Start {
    const char* what;
    arbiter::soccer::Pose robot;
    arbiter::soccer::Point ball;
    int seed;
  };
  const Start start =
      GENERATE(Start{"ball straight ahead", {-1.0, 0.0, 0.0}, {1.0, 0.0}, 1},
               Start{"ball ahead to the left", {-3.0, -1.0, 0.0}, {0.5, 1.0}, 2},
               Start{"ball behind the robot", {1.0, 0.0, 0.0}, {-1.0, 0.5}, 3},
               Start{"robot between ball and goal, facing away", {2.5, 0.2, kPi}, {0.5, 0.0}, 4},
               Start{"ball beyond the camera's range", {-4.0, -2.5, kPi / 2}, {3.5, 2.5}, 5},
               Start{"ball near the own goal", {0.0, 2.0, -kPi / 2}, {-4.0, -1.0}, 6},
               Start{"ball on the touch line", {-2.0, 0.0, 0.0}, {2.0, -3.0}, 7},
               Start{"ball in the opponent's corner", {3.0, 2.0, 0.0}, {4.0, -2.9}, 8});
  INFO(start.what);

  const Registry registry = soccer_registry();
  Manager manager(arbiter::test::compile_text(demo_config_with(start.robot, start.ball, start.seed),
                                              registry, "start.yaml"));
  const Outcome outcome = play(manager, 3000);
  INFO("first kick at step " << outcome.first_kick << ", " << outcome.kicks
                             << " kicks, goal at step " << outcome.goal << " (side "
                             << outcome.goal_side << ")");
  CHECK_FALSE(outcome.kick_and_approach_together);
  CHECK(outcome.first_kick > 0);
  CHECK(outcome.first_kick < 1000);
  CHECK(outcome.goal_side == 1);
}

TEST_CASE("the world reports what happens in it", "[soccer][demo]") {
  const Registry registry = soccer_registry();
  Manager manager(arbiter::test::compile_text(read_file(kDemoConfig), registry, kDemoConfig));
  StoryLog log;
  manager.add_observer(log);
  while (manager.steps() < 1500 && world_link(manager).world()->goals_at(1) == 0) manager.step();
  REQUIRE(world_link(manager).world()->goals_at(1) == 1);
  // Events are reported by the input pass: a goal scored in the output pass of step N is
  // reported in step N + 1, like a kick.
  CHECK(lines_with(log, "world: goal!").empty());
  manager.step();
  CHECK(lines_with(log, "world: goal!") ==
        std::vector<std::string>{std::to_string(manager.steps()) + " world: goal!"});
  CHECK_FALSE(lines_with(log, "world: ball kicked").empty());
}

// The soccer demo's world (plugins/soccer/world.cpp): the ball, the robot, the camera, goals and
// kick-offs, shots and dives.

#include <catch2/catch.hpp>
#include <cmath>

#include "world.hpp"

using arbiter::soccer::Command;
using arbiter::soccer::Point;
using arbiter::soccer::Pose;
using arbiter::soccer::World;
using arbiter::soccer::WorldConfig;

namespace {

constexpr double kPi = arbiter::soccer::kPi;

/// A world with the robot out of the ball's way, so that nothing but the ball moves.
/// The default world with the robot starting at `robot` and the ball at `ball`.
WorldConfig starting_at(const Pose& robot, const Point& ball) {
  WorldConfig config;
  config.robot_start = robot;
  config.ball_start = ball;
  return config;
}

WorldConfig quiet_world() {
  return starting_at({-4.0, -2.5, 0.0}, {0.0, 0.0});
}

void run(World& world, int steps, const Command& command = {}) {
  for (int i = 0; i < steps; ++i) world.step(command);
}

/// Steps `world` with no command until a goal is scored at x = +4.5, `most` steps at the most.
void run_until_goal(World& world, int most) {
  for (int i = 0; i < most && world.goals_at(1) == 0; ++i) world.step({});
}

}  // namespace

TEST_CASE("a rolling ball slows down at a constant rate and stops", "[soccer][world]") {
  WorldConfig config = quiet_world();
  World world(config);
  world.place_ball({0.0, 0.0}, {1.2, 0.0});
  world.step({});
  CHECK(world.ball_velocity().x == Approx(1.2 - config.ball_deceleration * config.dt));
  run(world, 100);
  // v² / 2a: 1.44 / 1.2 = 1.2 m, then it lies still.
  CHECK(world.ball_velocity().x == 0.0);
  CHECK(world.ball().x == Approx(1.2));
  CHECK(world.ball().y == 0.0);
}

TEST_CASE("a ball rolling off the field stops on the touch line", "[soccer][world]") {
  World world(quiet_world());
  world.place_ball({1.0, 2.5}, {1.0, 3.0});
  run(world, 30);
  CHECK(world.ball().y == Approx(3.0));
  CHECK(world.ball().x == Approx(1.0 + 0.5 / 3.0));
  CHECK(world.ball_velocity().x == 0.0);
  CHECK(world.ball_velocity().y == 0.0);
  CHECK(world.goals_at(1) + world.goals_at(-1) == 0);
}

TEST_CASE("the camera sees the ball only inside its field of view and range", "[soccer][world]") {
  WorldConfig config;
  config.robot_start = {-2.0, 0.0, 0.0};
  World world(config);
  const auto seen_at = [&](Point relative) {
    world.place_ball(arbiter::soccer::to_field(world.robot(), relative));
    return world.observe().ball_visible;
  };
  CHECK(seen_at({2.0, 0.0}));
  CHECK(seen_at({2.0, 2.0 * std::tan(0.45)}));
  CHECK_FALSE(seen_at({2.0, 2.0 * std::tan(0.55)}));
  CHECK_FALSE(seen_at({2.0, -2.0 * std::tan(0.55)}));
  CHECK_FALSE(seen_at({-1.0, 0.0}));
  CHECK(seen_at({4.9, 0.0}));
  CHECK_FALSE(seen_at({5.1, 0.0}));

  // Turning the head moves the field of view with it.
  world.set_head_yaw(1.0);
  CHECK(seen_at({std::cos(1.0), std::sin(1.0)}));
  CHECK_FALSE(seen_at({2.0, 0.0}));
  world.set_head_yaw(3.0);
  CHECK(world.head_yaw() == 1.5);
}

TEST_CASE("the head turns towards its target at a limited speed within its limits",
          "[soccer][world]") {
  WorldConfig config;
  World world(config);
  Command command;
  command.head_angle = -2.0;
  world.step(command);
  CHECK(world.head_yaw() == Approx(-config.head_speed * config.dt));
  run(world, 20, command);
  CHECK(world.head_yaw() == -config.head_limit);
}

TEST_CASE("the ball is measured relative to the robot with seeded noise", "[soccer][world]") {
  WorldConfig config = starting_at({-1.0, 0.5, kPi / 2}, {-1.0, 2.5});
  config.noise = 0.1;
  config.seed = 3;

  const auto measure = [](const WorldConfig& with, int count) {
    World world(with);
    std::vector<Point> measured;
    for (int i = 0; i < count; ++i) measured.push_back(world.observe().ball);
    return measured;
  };
  const auto first = measure(config, 2000);
  const auto again = measure(config, 2000);
  for (std::size_t i = 0; i < first.size(); ++i) {
    REQUIRE(first[i].x == again[i].x);
    REQUIRE(first[i].y == again[i].y);
  }

  // The ball lies 2 m straight ahead; the mean and spread of the measurement show that.
  double sum_x = 0.0, sum_y = 0.0, square_x = 0.0;
  for (const auto& point : first) {
    sum_x += point.x;
    sum_y += point.y;
    square_x += (point.x - 2.0) * (point.x - 2.0);
  }
  const double n = static_cast<double>(first.size());
  CHECK(sum_x / n == Approx(2.0).margin(0.01));
  CHECK(sum_y / n == Approx(0.0).margin(0.01));
  CHECK(std::sqrt(square_x / n) == Approx(0.1).epsilon(0.1));

  WorldConfig other = config;
  other.seed = 4;
  CHECK(measure(other, 1)[0].x != first[0].x);

  WorldConfig exact = config;
  exact.noise = 0.0;
  const Point truth = measure(exact, 1)[0];
  CHECK(truth.x == Approx(2.0));
  CHECK(truth.y == Approx(0.0).margin(1e-12));
}

TEST_CASE("a kick moves the ball only when it lies within reach in front", "[soccer][world]") {
  WorldConfig config;
  config.robot_start = {0.0, 0.0, 0.5};
  Command kick;
  kick.kick = true;

  SECTION("close in front: the ball leaves along the robot's heading") {
    World world(config);
    world.place_ball(arbiter::soccer::to_field(world.robot(), {0.25, 0.05}));
    world.step(kick);
    CHECK(world.kicks() == 1);
    CHECK(world.observe().ball_kicked);
    const Point velocity = world.ball_velocity();
    CHECK(std::atan2(velocity.y, velocity.x) == Approx(0.5));
    CHECK(std::hypot(velocity.x, velocity.y) ==
          Approx(config.kick_speed - config.ball_deceleration * config.dt));
    world.step({});
    CHECK_FALSE(world.observe().ball_kicked);
  }
  SECTION("too far, to the side or behind: nothing happens") {
    for (Point relative : {Point{0.5, 0.0}, Point{0.2, 0.2}, Point{-0.2, 0.0}}) {
      World world(config);
      world.place_ball(arbiter::soccer::to_field(world.robot(), relative));
      world.step(kick);
      CHECK(world.kicks() == 0);
      CHECK(world.ball_velocity().x == 0.0);
      CHECK(world.ball_velocity().y == 0.0);
    }
  }
  SECTION("within reach but not commanded: nothing happens") {
    World world(config);
    world.place_ball(arbiter::soccer::to_field(world.robot(), {0.25, 0.0}));
    world.step({});
    CHECK(world.kicks() == 0);
  }
}

TEST_CASE("a goal is scored when the ball crosses a goal line between the posts",
          "[soccer][world]") {
  SECTION("into the goal at x = +4.5") {
    World world(quiet_world());
    world.place_ball({3.5, 1.0}, {3.0, 0.3});
    run_until_goal(world, 30);
    CHECK(world.goals_at(1) == 1);
    CHECK(world.observe().goal == 1);
    CHECK(world.ball().x == 4.5);
    CHECK(std::abs(world.ball().y) < 1.3);
    world.step({});
    CHECK(world.observe().goal == 0);
    CHECK(world.goals_at(1) == 1);
  }
  SECTION("into the goal at x = -4.5") {
    World world(quiet_world());
    world.place_ball({-3.0, 0.0}, {-3.0, 0.0});
    run(world, 30);
    CHECK(world.goals_at(-1) == 1);
    CHECK(world.goals_at(1) == 0);
  }
  SECTION("beside the post: the ball stops on the goal line and no goal") {
    World world(quiet_world());
    world.place_ball({3.5, 1.5}, {3.0, 0.0});
    run(world, 30);
    CHECK(world.goals_at(1) == 0);
    CHECK(world.ball().x == 4.5);
    CHECK(world.ball().y == Approx(1.5));
  }
}

TEST_CASE("after a goal the world kicks off again once kick_off_delay has passed",
          "[soccer][world]") {
  WorldConfig config = quiet_world();
  config.kick_off_delay = 1.0;  // 15 steps at 1/15 s
  SECTION("the ball back on the centre spot, the robot at its start, reported once") {
    World world(config);
    world.place_robot({1.0, 1.0, 2.0});
    world.place_ball({4.0, 0.0}, {3.0, 0.0});
    run_until_goal(world, 30);
    REQUIRE(world.goals_at(1) == 1);
    run(world, 14);
    CHECK(world.ball().x == 4.5);
    CHECK_FALSE(world.observe().kick_off);
    world.step({});
    CHECK(world.observe().kick_off);
    CHECK(world.ball().x == 0.0);
    CHECK(world.ball().y == 0.0);
    CHECK(world.ball_velocity().x == 0.0);
    CHECK(world.robot().x == config.robot_start.x);
    CHECK(world.robot().y == config.robot_start.y);
    CHECK(world.robot().theta == config.robot_start.theta);
    world.step({});
    CHECK_FALSE(world.observe().kick_off);
    CHECK(world.goals_at(1) == 1);
  }
  SECTION("a negative delay: never, the ball stays in the goal") {
    config.kick_off_delay = -1.0;
    World world(config);
    world.place_ball({4.0, 0.0}, {3.0, 0.0});
    run(world, 200);
    CHECK(world.goals_at(1) == 1);
    CHECK(world.ball().x == 4.5);
  }
}

TEST_CASE("a ball lying on a line slides along it instead of leaving the field",
          "[soccer][world]") {
  SECTION("on the touch line") {
    World world(quiet_world());
    world.place_ball({0.0, 3.0}, {1.0, 1.0});
    world.step({});
    CHECK(world.ball().y == 3.0);
    CHECK(world.ball().x > 0.0);
  }
  SECTION("on the goal line beside the post, into the goal") {
    World world(quiet_world());
    world.place_ball({4.5, -1.5}, {0.1, 2.0});
    run(world, 10);
    CHECK(world.goals_at(1) == 1);
    CHECK(std::abs(world.ball().y) < 1.3);
  }
  SECTION("a ball in the goal scores once") {
    World world(quiet_world());
    world.place_ball({4.0, 0.0}, {3.0, 0.0});
    run(world, 10);
    REQUIRE(world.goals_at(1) == 1);
    world.place_robot({4.3, 0.0, 0.0});
    Command walk;
    walk.walk = {0.4, 0.0, 0.0};
    run(world, 10, walk);
    CHECK(world.goals_at(1) == 1);
  }
}

TEST_CASE("walking is limited in speed and acceleration", "[soccer][world]") {
  const WorldConfig config = starting_at({0.0, 0.0, 0.0}, {0.0, 2.0});
  World world(config);
  Command command;
  command.walk = {1.0, 0.0, 0.0};
  world.step(command);
  CHECK(world.robot_velocity().forward == Approx(config.linear_acceleration * config.dt));
  run(world, 30, command);
  CHECK(world.robot_velocity().forward == Approx(config.max_forward));
  CHECK(world.robot().y == 0.0);
  CHECK(world.robot().x > 0.0);

  command.walk = {0.0, 0.0, 5.0};
  run(world, 30, command);
  CHECK(world.robot_velocity().turn == Approx(config.max_turn));
  CHECK(world.robot_velocity().forward == Approx(0.0));
}

TEST_CASE("a robot walking into the ball pushes it", "[soccer][world]") {
  const WorldConfig config = starting_at({0.0, 0.0, 0.0}, {0.5, 0.0});
  World world(config);
  Command command;
  command.walk = {0.4, 0.0, 0.0};
  run(world, 45, command);
  CHECK(world.ball().x - world.robot().x == Approx(config.contact_distance));
  CHECK(world.kicks() == 0);
}

TEST_CASE("the button is pressed in the configured step only", "[soccer][world]") {
  WorldConfig config;
  config.button_step = 3;
  World world(config);
  std::vector<bool> pressed;
  for (int i = 0; i < 5; ++i) {
    pressed.push_back(world.observe().button);
    world.step({});
  }
  CHECK(pressed == std::vector<bool>{false, false, true, false, false});

  World never(WorldConfig{});
  for (int i = 0; i < 5; ++i) {
    CHECK_FALSE(never.observe().button);
    never.step({});
  }
}

TEST_CASE("a shot at the configured step rolls the ball towards its target", "[soccer][world]") {
  WorldConfig config = quiet_world();
  config.ball_start = {-1.0, 1.0};
  config.shot_step = 3;
  config.shot_target = {-4.5, 0.0};
  World world(config);
  run(world, 2);
  CHECK(world.ball_velocity().x == 0.0);
  CHECK_FALSE(world.observe().shot);
  world.step({});
  CHECK(world.observe().shot);
  const Point velocity = world.ball_velocity();
  CHECK(std::atan2(velocity.y, velocity.x) == Approx(std::atan2(-1.0, -3.5)));
  CHECK(std::hypot(velocity.x, velocity.y) ==
        Approx(config.shot_speed - config.ball_deceleration * config.dt));
  world.step({});
  CHECK_FALSE(world.observe().shot);
}

TEST_CASE("a diving robot lies across the ball's path and stops a shot", "[soccer][world]") {
  // The shot passes 0.3 m to the robot's left: beside a standing robot, into the goal.
  const WorldConfig config = starting_at({-4.0, 0.0, 0.0}, {-1.0, 0.3});
  // The ball needs about 15 steps to the goal line; the robot lies for 30.
  const auto shoot = [&](int dive) {
    World world(config);
    world.shoot({-4.5, 0.3}, 3.5);
    Command command;
    command.dive = dive;
    world.step(command);
    run(world, 20);
    return world;
  };
  const World standing = shoot(0);
  CHECK(standing.goals_at(-1) == 1);
  CHECK(standing.saves() == 0);

  const World wrong_side = shoot(-1);
  CHECK(wrong_side.goals_at(-1) == 1);

  World diving = shoot(1);
  CHECK(diving.goals_at(-1) == 0);
  CHECK(diving.saves() == 1);
  CHECK(diving.ball().x > -4.0);  // bounced back into the field
  // Down for dive_time: it neither walks nor kicks, then stands again.
  CHECK(diving.down());
  CHECK(diving.dive_side() == 1);
  CHECK(diving.robot().x == -4.0);
  Command walk;
  walk.walk = {0.4, 0.0, 0.0};
  run(diving, 1, walk);
  CHECK(diving.robot().x == -4.0);
  run(diving, static_cast<int>(std::lround(config.dive_time / config.dt)) - 23);
  CHECK(diving.down());
  run(diving, 1);
  CHECK_FALSE(diving.down());
  run(diving, 5, walk);
  CHECK(diving.robot().x > -4.0);
}

TEST_CASE("the button can be pressed from outside", "[soccer][world]") {
  World world(WorldConfig{});
  world.press_button();
  CHECK(world.observe().button);
  world.step({});
  CHECK_FALSE(world.observe().button);
}

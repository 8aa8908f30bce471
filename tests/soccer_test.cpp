#include <algorithm>
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "soccer.hpp"
#include "test_support.hpp"
#include "world.hpp"
#include "world_link.hpp"

using arbiter::Controller;
using arbiter::ControllerStatus;
using arbiter::Manager;
using arbiter::Registry;
using arbiter::soccer::Command;
using arbiter::soccer::Point;
using arbiter::soccer::Pose;
using arbiter::soccer::World;
using arbiter::soccer::WorldConfig;

namespace {

constexpr double kPi = arbiter::soccer::kPi;

/// A world with the robot out of the ball's way, so that nothing but the ball moves.
WorldConfig quiet_world() {
  WorldConfig config;
  config.robot_start = {-4.0, -2.5, 0.0};
  config.ball_start = {0.0, 0.0};
  return config;
}

void run(World& world, int steps, const Command& command = {}) {
  for (int i = 0; i < steps; ++i) world.step(command);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

const std::string kDemoConfig = ARBITER_SOURCE_DIR "/configs/soccer/walk_and_kick.yaml";
const std::string kGoalieConfig = ARBITER_SOURCE_DIR "/configs/soccer/goalie.yaml";

Registry soccer_registry() {
  Registry registry = arbiter::test::make_test_registry();
  registry.set_origin("soccer");
  arbiter::soccer::register_classes(registry);
  return registry;
}

/// The demo config with the world's params replaced, as a user would edit it.
std::string demo_config_with(const Pose& robot, const Point& ball, int seed) {
  std::string text = read_file(kDemoConfig);
  const auto replace = [&](const std::string& key, const std::string& value) {
    const std::regex pattern(key + ": [^\\n#]*");
    REQUIRE(std::regex_search(text, pattern));
    text = std::regex_replace(text, pattern, key + ": " + value,
                              std::regex_constants::format_first_only);
  };
  replace("seed", std::to_string(seed));
  replace("robot_start", "[" + std::to_string(robot.x) + ", " + std::to_string(robot.y) + ", " +
                             std::to_string(robot.theta) + "]");
  replace("ball_start", "[" + std::to_string(ball.x) + ", " + std::to_string(ball.y) + "]");
  return text;
}

arbiter::soccer::WorldLink& world_link(const Manager& manager) {
  for (const auto& layer : manager.program().layers) {
    if (layer.is_interface()) return dynamic_cast<arbiter::soccer::WorldLink&>(*layer.interface);
  }
  throw std::runtime_error("the program has no interface layer");
}

/// `text` with the first occurrence of `from` replaced by `to`, which must be there.
std::string edited(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

/// What happened in each step, in the order it happened: "11 activate walk_to_pose" for a goalie
/// state that became current, "201 world: shot on goal" for an event reported by behaviour or
/// interface code.
class StoryLog : public arbiter::Observer {
 public:
  void on_step(const Manager& manager) override {
    const std::string step = std::to_string(manager.steps());
    std::vector<std::pair<std::uint32_t, std::string>> happened;  // by sequence
    const Controller* goalie = manager.program().find_controller("goalie");
    if (goalie != nullptr) {
      for (std::size_t e = 0; e < goalie->event_count(); ++e) {
        const auto& event = goalie->events()[e];
        if (event.kind != Controller::Event::Kind::kActivate) continue;
        happened.emplace_back(event.sequence,
                              step + " activate " + goalie->states()[event.state].name);
        const Pose robot = world_link(manager).world()->robot();
        poses.push_back(robot);
      }
    }
    for (std::size_t e = 0; e < manager.event_count(); ++e) {
      const auto& event = manager.event(e);
      happened.emplace_back(event.sequence,
                            step + " " + manager.event_source(event) + ": " + event.text);
    }
    std::sort(happened.begin(), happened.end());
    for (auto& [sequence, line] : happened) lines.push_back(std::move(line));
    if (goalie != nullptr && goalie->status() != ControllerStatus::kRunning && !ended) {
      ended = true;
      lines.push_back(step + " " + arbiter::to_string(goalie->status()));
    }
  }

  std::vector<std::string> lines;
  std::vector<Pose> poses;  ///< the robot's pose at each activation, in order
  bool ended = false;
};

/// The lines of `log` that mention `what`.
std::vector<std::string> lines_with(const StoryLog& log, const std::string& what) {
  std::vector<std::string> found;
  for (const auto& line : log.lines) {
    if (line.find(what) != std::string::npos) found.push_back(line);
  }
  return found;
}

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
  const World& world = *world_link(manager).world();
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
  WorldConfig config;
  config.robot_start = {-1.0, 0.5, kPi / 2};
  config.ball_start = {-1.0, 2.5};
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
    int steps = 0;
    while (world.goals_at(1) == 0 && steps < 30) {
      world.step({});
      ++steps;
    }
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
    int steps = 0;
    while (world.goals_at(1) == 0 && steps < 30) {
      world.step({});
      ++steps;
    }
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
  WorldConfig config;
  config.robot_start = {0.0, 0.0, 0.0};
  config.ball_start = {0.0, 2.0};
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
  WorldConfig config;
  config.robot_start = {0.0, 0.0, 0.0};
  config.ball_start = {0.5, 0.0};
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

TEST_CASE("the soccer classes declare described params and ports", "[soccer][classes]") {
  const Registry registry = soccer_registry();
  for (const char* name : {"soccer.WorldLink", "soccer.SearchForBall", "soccer.GoBehindBall",
                           "soccer.KickBall", "soccer.HeadControl"}) {
    INFO(name);
    const auto* info = registry.find_any_class(name);
    REQUIRE(info != nullptr);
    CHECK(info->origin == "soccer");
    CHECK_FALSE(info->description.empty());
    for (const auto& param : info->params) {
      INFO(param.name);
      CHECK_FALSE(param.description.empty());
      CHECK_FALSE(param.required());
    }
    for (const auto& port : info->ports) {
      INFO(port.name);
      CHECK_FALSE(port.description.empty());
    }
  }
}

TEST_CASE("world params outside the field are reported at the param", "[soccer][classes]") {
  const Registry registry = soccer_registry();
  const auto diagnostics = arbiter::test::diagnose_text(
      demo_config_with({-3.0, 0.0, 0.0}, {5.0, 0.0}, 1), registry, "world.yaml");
  REQUIRE(diagnostics.has_errors());
  CHECK_THAT(arbiter::format(diagnostics), Catch::Contains("ball_start [5, 0] is off the field"));
}

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
    Pose robot;
    Point ball;
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
  WorldConfig config;
  config.robot_start = {-4.0, 0.0, 0.0};
  config.ball_start = {-1.0, 0.3};
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

TEST_CASE("the world's dt is the step period unless given", "[soccer][classes]") {
  const Registry registry = soccer_registry();
  const std::string config =
      "arbiter: 1\nname: t\nrate_hz: 10\nlayers:\n"
      "  - name: world\n    interface: soccer.WorldLink\n    params: {PARAMS}\n"
      "    actuators: {ball_visible: {type: bool}, ball_position: {type: vec2}}\n"
      "    sensors: [gait_velocity]\n"
      "  - name: control\n    actuators: {gait_velocity: {type: vec3}}\n";
  const auto dt_of = [&](const std::string& params) {
    Manager manager(arbiter::test::compile_text(edited(config, "PARAMS", params), registry));
    return world_link(manager).world()->config().dt;
  };
  CHECK(dt_of("") == 0.1);
  CHECK(dt_of("dt: 0.05") == 0.05);
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

TEST_CASE("the goalie classes declare described params and ports", "[soccer][classes]") {
  const Registry registry = soccer_registry();
  for (const char* name : {"soccer.WaitForButton", "soccer.WalkToPose", "soccer.MonitorBall",
                           "soccer.Dive", "soccer.Goalie"}) {
    INFO(name);
    const auto* info = registry.find_any_class(name);
    REQUIRE(info != nullptr);
    CHECK(info->origin == "soccer");
    CHECK_FALSE(info->description.empty());
    CHECK_FALSE(info->ports.empty());
    for (const auto& param : info->params) {
      INFO(param.name);
      CHECK_FALSE(param.description.empty());
    }
    for (const auto& port : info->ports) {
      INFO(port.name);
      CHECK_FALSE(port.description.empty());
    }
  }
  std::vector<std::string> required;
  for (const char* name : {"soccer.WalkToPose", "soccer.Goalie"}) {
    for (const auto& param : registry.find_any_class(name)->params) {
      if (param.required()) required.push_back(param.name);
    }
  }
  CHECK(required == std::vector<std::string>{"x", "y", "theta", "machine"});
}

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
                                                            "201 goalie: goalie dives left"});
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

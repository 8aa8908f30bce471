#include "world_link.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "arbiter/init_context.hpp"

namespace arbiter::soccer {

namespace {

constexpr SceneColor kLines{1.0f, 1.0f, 1.0f, 0.9f};
constexpr SceneColor kGoalNegative{1.0f, 0.85f, 0.1f, 1.0f};  // the goal at x = -4.5
constexpr SceneColor kGoalPositive{0.2f, 0.5f, 1.0f, 1.0f};
constexpr SceneColor kRobot{0.1f, 0.2f, 0.7f, 1.0f};
constexpr SceneColor kHeading{0.95f, 0.95f, 0.3f, 1.0f};
constexpr SceneColor kView{1.0f, 1.0f, 1.0f, 0.35f};
constexpr SceneColor kBall{1.0f, 0.45f, 0.0f, 1.0f};
constexpr SceneColor kMotion{0.9f, 0.1f, 0.1f, 1.0f};

ScenePoint at(Point p) {
  return {p.x, p.y};
}

// The field as the world is at the start of the step, in the "field" frame: lines, goals, the
// robot (its heading, what its camera sees, its body when down), the ball and where it rolls.
void draw(const World& world, const Observation& seen, const StepContext& ctx) {
  Scene scene = ctx.scene("field");
  const auto& c = world.config();
  const double x = 0.5 * c.field_length, y = 0.5 * c.field_width, goal = 0.5 * c.goal_width;
  const ScenePoint outline[] = {{-x, -y}, {x, -y}, {x, y}, {-x, y}};
  scene.polygon(outline, 4, kLines, 0.05);
  scene.line({0.0, -y}, {0.0, y}, kLines, 0.05);
  scene.circle({0.0, 0.0}, 0.75, kLines, false, 0.05);
  for (const int side : {-1, 1}) {
    const double depth = 0.6;
    const ScenePoint net[] = {{side * x, -goal},
                              {side * (x + depth), -goal},
                              {side * (x + depth), goal},
                              {side * x, goal}};
    scene.polyline(net, 4, side < 0 ? kGoalNegative : kGoalPositive, 0.08);
  }

  const Pose& robot = world.robot();
  const Point position = robot.position();
  if (world.down()) {
    const Point end = position + (world.dive_side() * c.dive_reach) * unit(robot.theta + 0.5 * kPi);
    scene.line(at(position), at(end), kRobot, 0.2);
  }
  scene.circle(at(position), 0.15, kRobot, true);
  scene.arrow(at(position), at(position + 0.45 * unit(robot.theta)), kHeading, 0.05);
  // What the camera sees: one polyline from one edge of its view to the other through the robot,
  // where two lines would repeat the robot's position in every message.
  const double gaze = robot.theta + world.head_yaw();
  const ScenePoint view[] = {at(position + 1.5 * unit(gaze - c.camera_half_fov)), at(position),
                             at(position + 1.5 * unit(gaze + c.camera_half_fov))};
  scene.polyline(view, 3, kView, 0.02);

  const Point ball = world.ball();
  scene.circle(at(ball), 0.075, kBall, true);
  const Point velocity = world.ball_velocity();
  if (norm(velocity) > 0.2) scene.arrow(at(ball), at(ball + 0.5 * velocity), kMotion, 0.04);
  const ScenePoint label{ball.x, ball.y + 0.35};
  if (seen.ball_kicked) scene.text(label, "kick", kMotion);
  if (seen.shot) scene.text(label, "shot", kMotion);
  if (seen.ball_saved) scene.text(label, "saved", kMotion);
  if (seen.goal != 0) scene.text(label, "goal!", kMotion);

  char score[24];
  std::snprintf(score, sizeof score, "%d : %d", world.goals_at(-1), world.goals_at(1));
  scene.text({0.0, y + 0.4}, score, kLines, 0.4);
}

}  // namespace

void WorldLink::init(InitContext& ctx) {
  WorldConfig config;
  config.seed = static_cast<std::uint32_t>(seed_);
  // Unless told otherwise, simulated time runs at the config's nominal rate.
  config.dt = dt_ > 0.0 ? dt_ : 1.0 / ctx.rate_hz();
  const Vec3& robot = robot_start_;
  config.robot_start = {robot.x, robot.y, robot.z};
  const Vec2& ball = ball_start_;
  config.ball_start = {ball.x, ball.y};
  config.noise = noise_;
  config.button_step = button_step_;
  config.shot_step = shot_step_;
  config.shot_target = {shot_target_.x, shot_target_.y};
  config.shot_speed = shot_speed_;
  config.kick_off_delay = kick_off_delay_;

  // Vector params carry no range in the schema, so the field's bounds are checked here.
  const double half_length = 0.5 * config.field_length;
  const double half_width = 0.5 * config.field_width;
  if (std::abs(ball.x) > half_length || std::abs(ball.y) > half_width) {
    ctx.error(ctx.param_location(&WorldLink::ball_start_),
              fmt::format("ball_start [{}, {}] is off the field (|x| <= {}, |y| <= {})", ball.x,
                          ball.y, half_length, half_width));
  }
  const double x_limit = half_length + config.robot_margin;
  const double y_limit = half_width + config.robot_margin;
  if (std::abs(robot.x) > x_limit || std::abs(robot.y) > y_limit) {
    ctx.error(ctx.param_location(&WorldLink::robot_start_),
              fmt::format("robot_start [{}, {}, {}] is off the field (|x| <= {}, |y| <= {})",
                          robot.x, robot.y, robot.z, x_limit, y_limit));
  }
  world_ = std::make_unique<World>(config);
}

void WorldLink::input(WriteContext& ctx) {
  const Observation seen = world_->observe();
  ctx.write(ball_visible_, seen.ball_visible);
  // Left unwritten when the ball is not seen: the actuator keeps the last measurement and its
  // written flag tells a fresh one from an old one.
  if (seen.ball_visible) {
    ctx.write(ball_position_, Vec2{seen.ball.x, seen.ball.y});
    ctx.write(ball_velocity_, Vec2{seen.ball_velocity.x, seen.ball_velocity.y});
  }
  ctx.write(robot_pose_, Vec3{seen.robot.x, seen.robot.y, seen.robot.theta});
  ctx.write(button_, seen.button);
  ctx.write(ball_kicked_, seen.ball_kicked);
  ctx.write(goal_scored_, seen.goal != 0);

  if (seen.button) ctx.report("button pressed");
  if (seen.shot) ctx.report("shot on goal");
  if (seen.ball_kicked) ctx.report("ball kicked");
  if (seen.ball_saved) ctx.report("ball saved");
  if (seen.goal != 0) ctx.report("goal!");
  if (seen.kick_off) ctx.report("kick-off");
  draw(*world_, seen, ctx);
}

void WorldLink::output(const StepContext& ctx) {
  Command command;
  // Walking and kicking are commands for this step: one that no active behaviour gave this step
  // means stand still and do not kick, not "repeat the last one". The head angle is a position
  // target, so the last one holds.
  if (ctx.written(gait_velocity_)) {
    const Vec3& walk = ctx.read(gait_velocity_);
    command.walk = {walk.x, walk.y, walk.z};
  }
  command.kick = ctx.written(kick_) && ctx.read(kick_);
  if (ctx.written(dive_)) {
    command.dive = static_cast<int>(std::clamp<std::int64_t>(ctx.read(dive_), -1, 1));
  }
  command.head_angle = head_angle_.bound() ? ctx.read(head_angle_) : world_->head_yaw();
  world_->step(command);
}

void register_world_link(Registry& registry) {
  auto& info =
      registry.add_interface<WorldLink>("soccer.WorldLink")
          .describe(
              "A simulated 9 m x 6 m soccer field with one robot and a ball. The input pass "
              "publishes what the robot senses; the output pass applies the walk, head, kick and "
              "dive commands and advances the world by dt. Reports the events 'button pressed', "
              "'shot on goal', 'ball kicked', 'ball saved', 'goal!' and 'kick-off' (after a "
              "goal: the ball back on the centre spot, the robot at robot_start). Draws the "
              "field, the goals, the robot, its heading and view, the ball and its motion in "
              "the frame 'field'.");
  info.param("seed", &WorldLink::seed_)
      .defaults_to(0)
      .range(0.0, 4294967295.0)
      .describe("seed of the measurement noise");
  info.param("dt", &WorldLink::dt_)
      .defaults_to(0.0)
      .range(0.0, 1.0)
      .describe(
          "simulated time per step in seconds; 0 (the default) takes the step period, "
          "1 / rate_hz, so that simulated time runs at the nominal rate");
  info.param("robot_start", &WorldLink::robot_start_)
      .defaults_to(Vec3{-3.0, 0.0, 0.0})
      .describe("the robot's pose at the start: x, y (m, field frame) and heading (rad)");
  info.param("ball_start", &WorldLink::ball_start_)
      .defaults_to(Vec2{0.0, 0.0})
      .describe("the ball's position at the start (m, field frame, origin at the centre spot)");
  info.param("noise", &WorldLink::noise_)
      .defaults_to(0.02)
      .range(0.0, 1.0)
      .describe("standard deviation of each axis of the ball measurement (m)");
  info.param("button_step", &WorldLink::button_step_)
      .defaults_to(-1)
      .at_least(-1.0)
      .describe("the step (from 1) in which the button is pressed; -1 for never");
  info.param("shot_step", &WorldLink::shot_step_)
      .defaults_to(-1)
      .at_least(-1.0)
      .describe(
          "the step (from 1) at the end of which an opponent shoots the ball from where it lies "
          "towards shot_target; -1 for never");
  info.param("shot_target", &WorldLink::shot_target_)
      .defaults_to(Vec2{-4.5, 0.0})
      .describe(
          "where the shot is aimed (m, field frame); the default is the centre of the goal "
          "at x = -4.5");
  info.param("shot_speed", &WorldLink::shot_speed_)
      .defaults_to(3.5)
      .range(0.1, 10.0)
      .describe("the ball's speed when shot (m/s); it then slows down at 0.6 m/s²");
  info.param("kick_off_delay", &WorldLink::kick_off_delay_)
      .defaults_to(2.0)
      .range(-1.0, 60.0)
      .describe(
          "seconds from a goal to the kick-off that follows it (the ball back on the centre "
          "spot, the robot at robot_start, play goes on); negative for never");

  info.port("ball_visible", &WorldLink::ball_visible_)
      .describe("whether the head camera sees the ball");
  info.port("ball_position", &WorldLink::ball_position_)
      .describe(
          "the measured ball position relative to the robot (m, x forward, y left); written "
          "only in steps where the ball is seen");
  info.port("ball_velocity", &WorldLink::ball_velocity_)
      .make_optional()
      .describe(
          "the ball's velocity over the ground in the robot frame (m/s, x forward, y left), as a "
          "ball filter would estimate it; written only in steps where the ball is seen");
  info.port("robot_pose", &WorldLink::robot_pose_)
      .make_optional()
      .describe("the robot's pose on the field: x, y (m) and heading (rad)");
  info.port("button", &WorldLink::button_)
      .make_optional()
      .describe("true in the step the button is pressed");
  info.port("ball_kicked", &WorldLink::ball_kicked_)
      .make_optional()
      .describe("true in the step after a kick hit the ball");
  info.port("goal_scored", &WorldLink::goal_scored_)
      .make_optional()
      .describe("true in the step after the ball crossed a goal line between the posts");
  info.port("gait_velocity", &WorldLink::gait_velocity_)
      .describe(
          "walk command: forward (m/s), sideways (m/s, left), turn rate (rad/s); stands still "
          "in a step where it was not written");
  info.port("head_angle", &WorldLink::head_angle_)
      .make_optional()
      .describe("head yaw target relative to the body (rad, limited to ±1.5)");
  info.port("kick", &WorldLink::kick_)
      .make_optional()
      .describe("kick in a step where it is written true and the ball is within reach");
  info.port("dive", &WorldLink::dive_)
      .make_optional()
      .describe(
          "in a step where it is written +1 (left) or -1 (right), the robot dives to that side: it "
          "lies across the ball's path, reaching 0.7 m, and cannot walk for 2 s");
}

}  // namespace arbiter::soccer

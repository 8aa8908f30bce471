#include "behaviours.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "arbiter/init_context.hpp"
#include "ball_memory.hpp"
#include "geometry.hpp"
#include "walk.hpp"

namespace arbiter::soccer {
namespace {

void register_search_for_ball(Registry& registry);
void register_go_behind_ball(Registry& registry);
void register_kick_ball(Registry& registry);
void register_head_control(Registry& registry);

template <typename T, typename C>
ParamSpec& declare_goal(ClassBinder<T>& info, Vec2 C::*goal) {
  return info.param("goal", goal)
      .defaults_to(Vec2{4.5, 0.0})
      .describe("the point to kick the ball to (m, field frame): the opponent goal's centre");
}

template <typename T, typename C>
ParamSpec& declare_ball_timeout(ClassBinder<T>& info, std::int64_t C::*ball_timeout,
                                std::int64_t steps) {
  return info.param("ball_timeout", ball_timeout)
      .defaults_to(steps)
      .range(0.0, 10000.0)
      .describe("steps after the ball was last seen for which its remembered position is used");
}

/// A behaviour that requests 1 while the ball's position is known: seen within ball_timeout
/// steps (declare_ball_timeout).
class WhileBallKnown : public Behaviour, public BallMemory {
 public:
  void update(const StepContext& ctx) override { remember_ball(ctx); }

  double activation(const StepContext&) override {
    return ball_seen_within(ball_timeout_) ? 1.0 : 0.0;
  }

 protected:
  std::int64_t ball_timeout_ = 0;
};

/// Turns on the spot, sweeping the head, until the ball is seen; after a full turn without
/// seeing it, walks towards the search point (the ball may be beyond the camera's range) and
/// turns again there.
class SearchForBall final : public Behaviour, public BallMemory {
 public:
  void update(const StepContext& ctx) override { remember_ball(ctx); }

  double activation(const StepContext&) override { return ball_age() >= lost_steps_ ? 1.0 : 0.0; }

  void execute(ExecuteContext& ctx) override {
    const Pose& robot = robot_pose();
    if (ctx.just_activated()) {
      walking_ = false;
      turned_ = 0.0;
      sweep_step_ = 0;
      last_heading_ = robot.theta;
      // Turning towards where the ball was last seen finds a ball that rolled out of view soonest.
      turn_sign_ = ball_age() != BallMemory::kNever && ball_relative().y < 0.0 ? -1.0 : 1.0;
    }
    // The turn is measured from the robot's pose rather than integrated from the command, so a
    // slow or blocked turn is not mistaken for a full one.
    turned_ += std::abs(wrap_angle(robot.theta - last_heading_));
    last_heading_ = robot.theta;

    const Point to_search = to_point(search_point_) - robot.position();
    const double distance = norm(to_search);
    if (!walking_ && turned_ >= 2.0 * kPi && distance > kArrived) walking_ = true;
    if (walking_ && distance <= kArrived) {
      walking_ = false;
      turned_ = 0.0;
    }
    Vec3 walk{0.0, 0.0, turn_sign_ * turn_rate_};
    if (walking_) {
      const double error = wrap_angle(bearing(to_search) - robot.theta);
      walk = {walk_speed_ * std::max(0.0, std::cos(error)), 0.0,
              std::clamp(2.0 * error, -turn_rate_, turn_rate_)};
    }
    ctx.write(gait_velocity_, walk);
    ctx.write(head_angle_, sweep_angle());
    ++sweep_step_;
  }

 private:
  friend void register_search_for_ball(Registry& registry);
  static constexpr double kArrived = 0.5;

  /// A triangle wave 0 → +sweep → -sweep → 0 over sweep_steps.
  double sweep_angle() const {
    const double phase =
        static_cast<double>(sweep_step_ % sweep_steps_) / static_cast<double>(sweep_steps_);
    const double triangle = phase < 0.25   ? 4.0 * phase
                            : phase < 0.75 ? 2.0 - 4.0 * phase
                                           : 4.0 * phase - 4.0;
    return turn_sign_ * head_sweep_ * triangle;
  }

  std::int64_t lost_steps_ = 0;
  double turn_rate_ = 0.0;
  double walk_speed_ = 0.0;
  Vec2 search_point_;
  double head_sweep_ = 0.0;
  std::int64_t sweep_steps_ = 1;
  Output<Vec3> gait_velocity_;
  Output<double> head_angle_;

  bool walking_ = false;
  double turned_ = 0.0;
  double last_heading_ = 0.0;
  double turn_sign_ = 1.0;
  std::int64_t sweep_step_ = 0;
};

/// Walks to the point `behind_distance` behind the ball on the line from the goal through the
/// ball, facing the goal. A robot that is not yet behind the ball goes round it on its own side,
/// so as not to push the ball towards the wrong goal.
class GoBehindBall final : public WhileBallKnown, public WalkParams<double> {
 public:
  void execute(ExecuteContext& ctx) override {
    const Pose& robot = robot_pose();
    const Point ball = ball_field();
    const Point to_goal = to_point(goal_) - ball;
    const double aim = norm(to_goal) > 1e-6 ? bearing(to_goal) : robot.theta;
    const Point along_axis = unit(aim);
    const Point across_axis{-along_axis.y, along_axis.x};
    const Point from_ball = robot.position() - ball;

    Point target = ball - behind_distance_ * along_axis;
    if (dot(from_ball, along_axis) > -0.5 * behind_distance_) {
      const double side = dot(from_ball, across_axis) >= 0.0 ? 1.0 : -1.0;
      target = target + (side * clearance_) * across_axis;
    }

    // Close to the target, the robot turns to face the goal.
    const Point relative = to_robot(robot, target);
    const WalkLimits limits{near_distance_, max_forward, max_sideways, max_turn};
    ctx.write(gait_velocity_, walk_towards(relative, gain * norm(relative), gain,
                                           wrap_angle(aim - robot.theta), limits));
  }

 private:
  friend void register_go_behind_ball(Registry& registry);
  Vec2 goal_;
  double behind_distance_ = 0.0;
  double clearance_ = 0.0;
  double near_distance_ = 0.0;
  Output<Vec3> gait_velocity_;
};

/// Kicks when the ball lies close in front of the feet and the robot faces the goal. Its level is
/// exactly 0 or 1 so that `kick_ball => go_behind_ball` silences go_behind_ball completely.
class KickBall final : public Behaviour, public BallMemory {
 public:
  void update(const StepContext& ctx) override { remember_ball(ctx); }

  double activation(const StepContext&) override {
    if (!ball_seen_within(max_age_)) return 0.0;
    const Point ball = ball_relative();
    const double heading_error =
        wrap_angle(bearing(to_point(goal_) - ball_field()) - robot_pose().theta);
    const bool ready = norm(ball) <= max_distance_ && std::abs(bearing(ball)) <= max_bearing_ &&
                       std::abs(heading_error) <= max_heading_error_;
    return ready ? 1.0 : 0.0;
  }

  void execute(ExecuteContext& ctx) override {
    ctx.write(kick_, true);
    // A kick is made standing: the walk command of this layer would otherwise be nobody's.
    ctx.write(gait_velocity_, Vec3{});
  }

 private:
  friend void register_kick_ball(Registry& registry);
  Vec2 goal_;
  std::int64_t max_age_ = 0;
  double max_distance_ = 0.0;
  double max_bearing_ = 0.0;
  double max_heading_error_ = 0.0;
  Output<bool> kick_;
  Output<Vec3> gait_velocity_;
};

/// Points the head at the ball while its position is known.
class HeadControl final : public WhileBallKnown {
 public:
  void execute(ExecuteContext& ctx) override {
    ctx.write(head_angle_, std::clamp(bearing(ball_relative()), -max_angle_, max_angle_));
  }

 private:
  friend void register_head_control(Registry& registry);
  double max_angle_ = 0.0;
  Output<double> head_angle_;
};

void register_search_for_ball(Registry& registry) {
  auto& info = registry.add_behaviour<SearchForBall>("soccer.SearchForBall")
                   .describe(
                       "Requests 1 when the ball has not been seen for lost_steps; turns on the "
                       "spot sweeping the head, and after a full turn without the ball walks to "
                       "the search point and turns again there.");
  info.param("lost_steps", &SearchForBall::lost_steps_)
      .defaults_to(15)
      .range(0.0, 10000.0)
      .describe("steps without seeing the ball before the search starts");
  info.param("turn_rate", &SearchForBall::turn_rate_)
      .defaults_to(0.6)
      .range(0.0, 1.5)
      .describe("turn rate on the spot (rad/s)");
  info.param("walk_speed", &SearchForBall::walk_speed_)
      .defaults_to(0.3)
      .range(0.0, 0.4)
      .describe("walking speed towards the search point (m/s)");
  info.param("search_point", &SearchForBall::search_point_)
      .defaults_to(Vec2{0.0, 0.0})
      .describe(
          "where to walk after a full turn without seeing the ball (m, field frame); the centre "
          "spot sees most of the field");
  info.param("head_sweep", &SearchForBall::head_sweep_)
      .defaults_to(1.2)
      .range(0.0, 1.5)
      .describe("amplitude of the head sweep either side of straight ahead (rad)");
  info.param("sweep_steps", &SearchForBall::sweep_steps_)
      .defaults_to(45)
      .range(2.0, 10000.0)
      .describe("steps for one full head sweep, left and right");
  BallMemory::declare_ports(info);
  info.port("gait_velocity", &SearchForBall::gait_velocity_)
      .describe("the walk command: forward, sideways, turn rate");
  info.port("head_angle", &SearchForBall::head_angle_).describe("the head yaw target (rad)");
}

void register_go_behind_ball(Registry& registry) {
  auto& info =
      registry.add_behaviour<GoBehindBall>("soccer.GoBehindBall")
          .describe(
              "Requests 1 while the ball's position is known; walks to a point behind the ball "
              "on the line from the goal through the ball, facing the goal, going round the "
              "ball when approaching it from the goal's side.");
  declare_goal(info, &GoBehindBall::goal_);
  declare_ball_timeout(info, &GoBehindBall::ball_timeout_, 45);
  info.param("behind_distance", &GoBehindBall::behind_distance_)
      .defaults_to(0.2)
      .range(0.0, 2.0)
      .describe("distance from the ball to the target point (m)");
  info.param("clearance", &GoBehindBall::clearance_)
      .defaults_to(0.4)
      .range(0.0, 2.0)
      .describe("how far to the side of the ball to pass when going round it (m)");
  info.param("near_distance", &GoBehindBall::near_distance_)
      .defaults_to(0.5)
      .range(0.0, 5.0)
      .describe(
          "within this distance of the target the robot steps sideways and turns to face the "
          "goal; further away it walks forwards towards the target (m)");
  WalkParams<double>::declare(info, 0.35, "the fastest forward speed requested (m/s)");
  BallMemory::declare_ports(info);
  info.port("gait_velocity", &GoBehindBall::gait_velocity_)
      .describe("the walk command: forward, sideways, turn rate");
}

void register_kick_ball(Registry& registry) {
  auto& info = registry.add_behaviour<KickBall>("soccer.KickBall")
                   .describe(
                       "Requests exactly 1 when the ball lies close in front of the robot and the "
                       "robot faces the goal, else 0; kicks and stands still while active.");
  declare_goal(info, &KickBall::goal_);
  info.param("max_age", &KickBall::max_age_)
      .defaults_to(2)
      .range(0.0, 100.0)
      .describe("kick only if the ball was seen within this many steps");
  info.param("max_distance", &KickBall::max_distance_)
      .defaults_to(0.27)
      .range(0.0, 1.0)
      .describe("the farthest the ball may be from the robot's centre (m)");
  info.param("max_bearing", &KickBall::max_bearing_)
      .defaults_to(0.3)
      .range(0.0, 1.5)
      .describe("the largest bearing of the ball from straight ahead (rad)");
  info.param("max_heading_error", &KickBall::max_heading_error_)
      .defaults_to(0.15)
      .range(0.0, 3.2)
      .describe(
          "how far the robot's heading may be off the direction from the ball to the goal (rad)");
  BallMemory::declare_ports(info);
  info.port("kick", &KickBall::kick_).describe("true while kicking");
  info.port("gait_velocity", &KickBall::gait_velocity_)
      .describe("zero while kicking: the robot stands");
}

void register_head_control(Registry& registry) {
  auto& info = registry.add_behaviour<HeadControl>("soccer.HeadControl")
                   .describe(
                       "Requests 1 while the ball's position is known and points the head at "
                       "it, so that it stays in view while the robot walks.");
  declare_ball_timeout(info, &HeadControl::ball_timeout_, 45);
  info.param("max_angle", &HeadControl::max_angle_)
      .defaults_to(1.5)
      .range(0.0, 3.2)
      .describe("the head yaw target is limited to this either side of straight ahead (rad)");
  BallMemory::declare_ports(info);
  info.port("head_angle", &HeadControl::head_angle_).describe("the head yaw target (rad)");
}

}  // namespace

void register_behaviours(Registry& registry) {
  register_search_for_ball(registry);
  register_go_behind_ball(registry);
  register_kick_ball(registry);
  register_head_control(registry);
}

}  // namespace arbiter::soccer

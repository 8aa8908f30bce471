#include "goalie.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "arbiter/controller.hpp"
#include "arbiter/init_context.hpp"
#include "arbiter/state.hpp"
#include "ball_memory.hpp"
#include "geometry.hpp"
#include "walk.hpp"

namespace arbiter::soccer {
namespace {

void register_wait_for_button(Registry& registry);
void register_walk_to_pose(Registry& registry);
void register_monitor_ball(Registry& registry);
void register_dive(Registry& registry);
void register_goalie_behaviour(Registry& registry);

constexpr double kHeadLimit = 1.5;

/// A duration in whole steps (at least one) at the config's step period.
std::int64_t steps_for(double seconds, double period) {
  if (period <= 0.0) return 1;
  return std::max<std::int64_t>(1, std::llround(seconds / period));
}

/// The direction from a goal into the field: towards the centre spot.
double out_of_goal(Point goal) {
  return norm(goal) > 1e-9 ? bearing(Point{-goal.x, -goal.y}) : 0.0;
}

template <typename T, typename C, typename M>
ParamSpec& declare_own_goal(ClassBinder<T>& info, M C::*goal) {
  return info.param("goal", goal)
      .defaults_to(Vec2{-4.5, 0.0})
      .describe("the centre of the goal to keep (m, field frame), on its goal line");
}

/// Holds until the button is pressed. A press in the step the state starts does not count: that
/// is the press that sent the goalie back to waiting.
class WaitForButton final : public State {
 public:
  StateResult execute(StateContext& ctx) override {
    const bool pressed = ctx.written(button_) && ctx.read(button_);
    return pressed && ctx.executions() > 0 ? StateResult::kProceed : StateResult::kHold;
  }

 private:
  friend void register_wait_for_button(Registry& registry);
  Input<bool> button_;
};

/// Walks to a field pose: far from it, forwards while turning towards it; close to it, stepping
/// straight there while turning to the pose's heading. Proceeds once within the tolerances.
class WalkToPose final : public State, public WalkParams<StateParam<double>> {
 public:
  void activate(StateContext& ctx) override {
    target_ = {ctx.param(x_), ctx.param(y_), ctx.param(theta_)};
    limits_ = {ctx.param(near_distance_), ctx.param(max_forward), ctx.param(max_sideways),
               ctx.param(max_turn)};
  }

  StateResult execute(StateContext& ctx) override {
    const Pose robot = to_pose(ctx.read(pose_));
    const Point relative = to_robot(robot, target_.position());
    const double distance = norm(relative);
    const double turn = wrap_angle(target_.theta - robot.theta);
    draw(ctx, robot);
    if (distance <= ctx.param(position_tolerance_) &&
        std::abs(turn) <= ctx.param(angle_tolerance_)) {
      ctx.write(gait_velocity_, Vec3{});
      return StateResult::kProceed;
    }
    // Never faster than would cover the rest of the way in one step, whatever the gain.
    const double speed = std::min(
        ctx.param(gain) * distance,
        ctx.period() > 0.0 ? distance / ctx.period() : std::numeric_limits<double>::infinity());
    const double scale = distance > 1e-9 ? speed / distance : 0.0;
    ctx.write(gait_velocity_, walk_towards(relative, speed, scale, turn, limits_));
    return StateResult::kHold;
  }

 private:
  // Where the walk goes, on the world's field: the pose, and the way there.
  void draw(const StepContext& ctx, const Pose& robot) const {
    constexpr SceneColor kTarget{0.3f, 0.9f, 1.0f, 0.9f};
    const Point at = target_.position();
    Scene scene = ctx.scene("field");
    scene.line({robot.x, robot.y}, {at.x, at.y}, SceneColor{0.3f, 0.9f, 1.0f, 0.4f}, 0.02);
    scene.circle({at.x, at.y}, 0.15, kTarget, false, 0.03);
    const Point heading = at + 0.3 * unit(target_.theta);
    scene.arrow({at.x, at.y}, {heading.x, heading.y}, kTarget, 0.03);
  }

  friend void register_walk_to_pose(Registry& registry);
  Input<Vec3> pose_;
  Output<Vec3> gait_velocity_;
  StateParam<double> x_;
  StateParam<double> y_;
  StateParam<double> theta_;
  StateParam<double> position_tolerance_;
  StateParam<double> angle_tolerance_;
  StateParam<double> near_distance_;
  Pose target_;
  WalkLimits limits_;
};

/// Watches the ball with the head. The best goalkeeping pose lies on the line from the goal's
/// centre to the ball, `distance` out from the goal and inside the goal area, facing the ball
/// (without a ball, `distance` straight out, facing the field). When the robot stands too far
/// from it, plans a walk there (`walk_state`) followed by another instance of itself, and
/// proceeds.
class MonitorBall final : public State, public BallMemory {
 public:
  void init(StateInitContext& ctx) override {
    // Resolved here once, so that a re-plan looks up no name and a walk state the machine does
    // not declare fails the load.
    walk_ = ctx.plan_state<double, double, double>(walk_state_, {"x", "y", "theta"},
                                                   ctx.param_location(&MonitorBall::walk_state_));
    again_ = ctx.plan_state<>(ctx.name());
  }

  void activate(StateContext& ctx) override {
    forget_ball();
    goal_ = to_point(ctx.param(goal_param_));
    out_ = out_of_goal(goal_);
    distance_ = ctx.param(distance_param_);
    depth_ = ctx.param(depth_param_);
    half_width_ = ctx.param(half_width_param_);
    replan_distance_ = ctx.param(replan_distance_param_);
    replan_angle_ = ctx.param(replan_angle_param_);
    timeout_steps_ = steps_for(ctx.param(ball_timeout_), ctx.period());
    search_steps_ = steps_for(ctx.param(search_time_), ctx.period());
    head_sweep_ = ctx.param(head_sweep_param_);
    sweep_steps_ = std::max<std::int64_t>(2, steps_for(ctx.param(sweep_time_), ctx.period()));
  }

  StateResult execute(StateContext& ctx) override {
    remember_ball(ctx);
    const bool known = ball_seen_within(timeout_steps_);
    ctx.write(head_angle_, known ? std::clamp(bearing(ball_relative()), -kHeadLimit, kHeadLimit)
                                 : sweep_angle(ctx.executions()));
    Pose best;
    if (known) {
      best = position_for(ball_field());
    } else if (ctx.executions() + 1 >= static_cast<std::uint64_t>(search_steps_)) {
      best = {goal_.x + distance_ * std::cos(out_), goal_.y + distance_ * std::sin(out_), out_};
    } else {
      return StateResult::kHold;
    }
    const Pose& robot = robot_pose();
    if (norm(best.position() - robot.position()) <= replan_distance_ &&
        std::abs(wrap_angle(best.theta - robot.theta)) <= replan_angle_) {
      return StateResult::kHold;
    }
    if (!ctx.plan().append(walk_, best.x, best.y, best.theta)) return StateResult::kHold;
    ctx.plan().append(again_);
    return StateResult::kProceed;
  }

 private:
  static constexpr double kMinDepth = 0.2;  ///< never closer to the goal line than this

  Pose position_for(Point ball) const {
    const Point out = unit(out_);
    const Point across{-out.y, out.x};
    const Point from_goal = ball - goal_;
    Point local{dot(from_goal, out), dot(from_goal, across)};
    const double length = norm(local);
    local = length > 1e-9 ? (distance_ / length) * local : Point{distance_, 0.0};
    local.x = std::clamp(local.x, std::min(kMinDepth, depth_), depth_);
    local.y = std::clamp(local.y, -half_width_, half_width_);
    const Point position = goal_ + local.x * out + local.y * across;
    const Point to_ball = ball - position;
    return {position.x, position.y, norm(to_ball) > 1e-9 ? bearing(to_ball) : out_};
  }

  /// A triangle wave 0 → +sweep → -sweep → 0 over sweep_steps.
  double sweep_angle(std::uint64_t step) const {
    const auto period = static_cast<std::uint64_t>(sweep_steps_);
    const double phase = static_cast<double>(step % period) / static_cast<double>(period);
    const double triangle = phase < 0.25   ? 4.0 * phase
                            : phase < 0.75 ? 2.0 - 4.0 * phase
                                           : 4.0 * phase - 4.0;
    return head_sweep_ * triangle;
  }

  friend void register_monitor_ball(Registry& registry);
  Output<double> head_angle_;
  std::string walk_state_;
  PlannedStateRef<double, double, double> walk_;
  PlannedStateRef<> again_;
  StateParam<Vec2> goal_param_;
  StateParam<double> distance_param_;
  StateParam<double> depth_param_;
  StateParam<double> half_width_param_;
  StateParam<double> replan_distance_param_;
  StateParam<double> replan_angle_param_;
  StateParam<double> ball_timeout_;
  StateParam<double> search_time_;
  StateParam<double> head_sweep_param_;
  StateParam<double> sweep_time_;
  Point goal_;
  double out_ = 0.0;
  double distance_ = 0.0;
  double depth_ = 0.0;
  double half_width_ = 0.0;
  double replan_distance_ = 0.0;
  double replan_angle_ = 0.0;
  std::int64_t timeout_steps_ = 1;
  std::int64_t search_steps_ = 1;
  double head_sweep_ = 0.0;
  std::int64_t sweep_steps_ = 2;
};

/// Dives to the side on which the ball will pass (from its last measured position and velocity),
/// then lies there for `duration` before the plan continues.
class Dive final : public State {
 public:
  void activate(StateContext& ctx) override {
    hold_steps_ = steps_for(ctx.param(duration_), ctx.period());
  }

  StateResult execute(StateContext& ctx) override {
    if (ctx.executions() == 0) {
      const std::int64_t side = side_of_ball(ctx);
      ctx.write(dive_, side);
      ctx.report(side > 0 ? "goalie dives left" : "goalie dives right");
    }
    return ctx.executions() + 1 >= static_cast<std::uint64_t>(hold_steps_) ? StateResult::kProceed
                                                                           : StateResult::kHold;
  }

 private:
  /// +1 (left) or -1 (right): where the ball crosses the robot's sideways axis, or lies now when
  /// it is not coming towards the robot. The ball actuators keep their last measurement.
  std::int64_t side_of_ball(const StateContext& ctx) const {
    const Point ball = to_point(ctx.read(position_));
    const Point velocity = to_point(ctx.read(velocity_));
    double lateral = ball.y;
    if (velocity.x < -1e-6 && ball.x > 0.0) lateral = ball.y + velocity.y * (-ball.x / velocity.x);
    return lateral >= 0.0 ? 1 : -1;
  }

  friend void register_dive(Registry& registry);
  Input<Vec2> position_;
  Input<Vec2> velocity_;
  Output<std::int64_t> dive_;
  StateParam<double> duration_;
  std::int64_t hold_steps_ = 1;
};

/// Owns the goalie's state machine and steps it while active (requesting 1 while it runs). Its
/// hooks pre-empt the plan: a button press sends the goalie back to waiting, a shot on goal that
/// will pass within reach makes it dive; either way monitoring follows.
class Goalie final : public Behaviour, private ControllerHooks {
 public:
  void init(BehaviourInitContext& ctx) override {
    goal_ = to_point(goal_param_);
    out_ = out_of_goal(goal_);
    controller_ = ctx.claim_controller(machine_, ctx.param_location(&Goalie::machine_));
    if (controller_ == nullptr) return;
    const bool found = resolve(ctx, &Goalie::wait_state_, "wait_state", wait_) &&
                       resolve(ctx, &Goalie::dive_state_, "dive_state", dive_) &&
                       resolve(ctx, &Goalie::monitor_state_, "monitor_state", monitor_);
    if (found) controller_->set_hooks(this);
  }

  void update(const StepContext& ctx) override {
    button_pressed_ = ctx.written(button_) && ctx.read(button_);
    shot_ = ctx.read(visible_) && ctx.written(velocity_) &&
            shot_on_goal(to_pose(ctx.read(pose_)), to_point(ctx.read(position_)),
                         to_point(ctx.read(velocity_)));
  }

  double activation(const StepContext&) override {
    return controller_ != nullptr && controller_->status() == ControllerStatus::kRunning ? 1.0
                                                                                         : 0.0;
  }

  void execute(ExecuteContext& ctx) override { controller_->step(ctx, &ctx); }

 private:
  /// Looks a state the hooks plan up once, so that a pre-emption looks up no name. `param` names
  /// the param bound to `member` in messages.
  bool resolve(InitContext& ctx, std::string Goalie::*member, const char* param,
               PlannedState& out) {
    const std::string& name = this->*member;
    const auto& states = controller_->states();
    const auto found = std::find_if(states.begin(), states.end(),
                                    [&](const CompiledState& state) { return state.name == name; });
    if (found == states.end()) {
      std::vector<std::string> known;
      for (const auto& state : states) known.push_back(state.name);
      ctx.error(ctx.param_location(member),
                fmt::format("the goalie plans state '{}' ({}), which state machine '{}' does not "
                            "declare",
                            name, param, controller_->name()))
          .unknown_name(name, known, {}, "it declares");
      return false;
    }
    const CompiledState& state = *found;
    for (const auto& spec : state.cls->params) {
      const bool given = std::any_of(state.params.begin(), state.params.end(),
                                     [&](const Param& p) { return p.name == spec.name; });
      if (spec.required() && !given) {
        ctx.error(ctx.param_location(member),
                  fmt::format("the goalie plans state '{}' ({}) without params, but its class {} "
                              "requires '{}'; set it on the state",
                              name, param, state.cls->name, spec.name));
        return false;
      }
    }
    out = PlannedState{static_cast<std::uint32_t>(found - states.begin()), {}, {}};
    return true;
  }

  bool pre_step(Controller& controller, Plan& plan) override {
    if (!button_pressed_ && !shot_) return false;
    const std::uint32_t current = controller.current_state_index();
    const auto is = [&](const PlannedState& planned) { return current == planned.state; };
    if (current == kNoState || is(wait_)) return false;
    if (button_pressed_) {
      plan.go_to(wait_);
    } else if (is(dive_)) {
      return false;
    } else {
      plan.go_to(dive_);
    }
    plan.append(monitor_);
    return true;
  }

  /// Whether the ball, rolling as it does and slowing down, crosses the goal line between the
  /// posts, passing within reach of the robot within warning_time.
  bool shot_on_goal(const Pose& robot, Point relative_ball, Point relative_velocity) const {
    const Point ball = to_field(robot, relative_ball);
    const Point velocity = rotate(relative_velocity, robot.theta);
    const double speed = norm(velocity);
    if (speed < shot_speed_) return false;
    const Point out = unit(out_);
    const Point across{-out.y, out.x};
    const double closing = -dot(velocity, out);
    const double to_line = dot(ball - goal_, out);
    if (closing <= 0.0 || to_line <= 0.0) return false;
    const double path_to_line = to_line * speed / closing;
    if (time_to_roll(path_to_line, speed) < 0.0) return false;
    const Point direction = (1.0 / speed) * velocity;
    const Point crossing = ball + path_to_line * direction;
    if (std::abs(dot(crossing - goal_, across)) > 0.5 * goal_width_) return false;
    const double along = dot(robot.position() - ball, direction);
    if (along <= 0.0) return false;
    if (norm(robot.position() - (ball + along * direction)) > reach_) return false;
    const double time = time_to_roll(along, speed);
    return time >= 0.0 && time <= warning_time_;
  }

  /// Seconds the ball takes to roll `distance`, slowing down; negative when it stops short.
  double time_to_roll(double distance, double speed) const {
    if (deceleration_ <= 0.0) return distance / speed;
    const double square = speed * speed - 2.0 * deceleration_ * distance;
    if (square < 0.0) return -1.0;
    return (speed - std::sqrt(square)) / deceleration_;
  }

  friend void register_goalie_behaviour(Registry& registry);
  std::string machine_;
  std::string wait_state_;
  std::string dive_state_;
  std::string monitor_state_;
  Vec2 goal_param_;
  Controller* controller_ = nullptr;
  PlannedState wait_;
  PlannedState dive_;
  PlannedState monitor_;
  Input<bool> button_;
  Input<bool> visible_;
  Input<Vec2> position_;
  Input<Vec2> velocity_;
  Input<Vec3> pose_;
  Point goal_;
  double out_ = 0.0;
  double goal_width_ = 0.0;
  double shot_speed_ = 0.0;
  double reach_ = 0.0;
  double warning_time_ = 0.0;
  double deceleration_ = 0.0;
  bool button_pressed_ = false;
  bool shot_ = false;
};

void register_wait_for_button(Registry& registry) {
  auto& info = add_state_class<WaitForButton>(registry, "soccer.WaitForButton")
                   .describe(
                       "Holds until the button is pressed, then proceeds. A press in the step the "
                       "state starts does not count: that is the press that sent the robot back "
                       "to waiting.");
  info.port("button", &WaitForButton::button_).describe("true in the step the button is pressed");
}

void register_walk_to_pose(Registry& registry) {
  auto& info = add_state_class<WalkToPose>(registry, "soccer.WalkToPose")
                   .describe(
                       "Walks to a pose on the field: far from it, forwards while turning towards "
                       "it; within near_distance, stepping straight there while turning to its "
                       "heading. Proceeds once within both tolerances.");
  info.param("x", &WalkToPose::x_).describe("the target's x on the field (m)");
  info.param("y", &WalkToPose::y_).describe("the target's y on the field (m)");
  info.param("theta", &WalkToPose::theta_)
      .range(-2.0 * kPi, 2.0 * kPi)
      .describe("the target heading (rad, from the field's x axis)");
  info.param("position_tolerance", &WalkToPose::position_tolerance_)
      .defaults_to(0.1)
      .range(0.01, 2.0)
      .describe("arrived when this close to the target position (m)");
  info.param("angle_tolerance", &WalkToPose::angle_tolerance_)
      .defaults_to(0.15)
      .range(0.01, 3.2)
      .describe("... and this close to the target heading (rad)");
  info.param("near_distance", &WalkToPose::near_distance_)
      .defaults_to(0.7)
      .range(0.0, 10.0)
      .describe("within this distance of the target, step straight to it (m)");
  WalkParams<StateParam<double>>::declare(
      info, 0.3, "the fastest forward (and backward) speed requested (m/s)");
  info.port("robot_pose", &WalkToPose::pose_)
      .describe("the robot's pose on the field: x, y (m), heading (rad)");
  info.port("gait_velocity", &WalkToPose::gait_velocity_)
      .describe("the walk command: forward, sideways, turn rate");
}

void register_monitor_ball(Registry& registry) {
  auto& info =
      add_state_class<MonitorBall>(registry, "soccer.MonitorBall")
          .describe(
              "Watches the ball with the head (sweeping it while the ball is unknown). When the "
              "best goalkeeping pose (on the line from the goal's centre to the ball, distance "
              "out and inside the goal area, facing the ball) is too far from the robot's, plans "
              "walk_state to it followed by another instance of this state, and proceeds.");
  declare_own_goal(info, &MonitorBall::goal_param_);
  info.param("distance", &MonitorBall::distance_param_)
      .defaults_to(0.5)
      .range(0.0, 3.0)
      .describe("how far out from the goal's centre, towards the ball, to stand (m)");
  info.param("depth", &MonitorBall::depth_param_)
      .defaults_to(1.0)
      .range(0.05, 3.0)
      .describe("the goal area's depth: never farther out from the goal line (m)");
  info.param("half_width", &MonitorBall::half_width_param_)
      .defaults_to(1.1)
      .range(0.0, 3.0)
      .describe("never farther to the side of the goal's centre (m)");
  info.param("replan_distance", &MonitorBall::replan_distance_param_)
      .defaults_to(0.2)
      .range(0.0, 5.0)
      .describe("plan a walk when the best position is farther than this (m)");
  info.param("replan_angle", &MonitorBall::replan_angle_param_)
      .defaults_to(0.35)
      .range(0.0, 3.2)
      .describe("... or the best heading differs by more than this (rad)");
  info.param("ball_timeout", &MonitorBall::ball_timeout_)
      .defaults_to(2.0)
      .range(0.0, 60.0)
      .describe("how long a ball seen by this instance counts as known (s)");
  info.param("search_time", &MonitorBall::search_time_)
      .defaults_to(3.0)
      .range(0.0, 60.0)
      .describe("without a known ball after this long, take the position straight out (s)");
  info.param("head_sweep", &MonitorBall::head_sweep_param_)
      .defaults_to(1.2)
      .range(0.0, kHeadLimit)
      .describe("amplitude of the head sweep while the ball is unknown (rad)");
  info.param("sweep_time", &MonitorBall::sweep_time_)
      .defaults_to(3.0)
      .range(0.1, 60.0)
      .describe("duration of one full head sweep, left and right (s)");
  info.param("walk_state", &MonitorBall::walk_state_)
      .defaults_to(std::string("walk_to_pose"))
      .state_level()
      .describe(
          "the state planned to walk (with params x, y, theta); the state machine must declare "
          "it, else the load fails naming it");
  BallMemory::declare_ports(info);
  info.port("head_angle", &MonitorBall::head_angle_).describe("the head yaw target (rad)");
}

void register_dive(Registry& registry) {
  auto& info = add_state_class<Dive>(registry, "soccer.Dive")
                   .describe(
                       "Dives to the side on which the ball will pass the robot, reports 'goalie "
                       "dives left' or 'goalie dives right', and proceeds after duration.");
  info.param("duration", &Dive::duration_)
      .defaults_to(2.0)
      .range(0.0, 60.0)
      .describe("how long the state lasts from the dive (s)");
  info.port("ball_position", &Dive::position_)
      .describe("the last measured ball position relative to the robot (m, x forward, y left)");
  info.port("ball_velocity", &Dive::velocity_)
      .make_optional()
      .describe(
          "the ball's velocity in the robot frame (m/s); without it, dives towards the side the "
          "ball lies on");
  info.port("dive", &Dive::dive_).describe("+1 dives to the left, -1 to the right");
}

void register_goalie_behaviour(Registry& registry) {
  auto& info = registry.add_behaviour<Goalie>("soccer.Goalie")
                   .describe(
                       "Steps the goalie's state machine while active and requests 1 while it "
                       "runs. Pre-empts its plan: a button press goes back to wait_state, a shot "
                       "on goal that will pass within reach goes to dive_state; monitor_state is "
                       "queued after either.");
  info.param("machine", &Goalie::machine_).describe("the state machine to own and step");
  info.param("wait_state", &Goalie::wait_state_)
      .defaults_to(std::string("wait_for_button"))
      .describe("the machine's state that waits for the button");
  info.param("dive_state", &Goalie::dive_state_)
      .defaults_to(std::string("dive"))
      .describe("the machine's state that dives");
  info.param("monitor_state", &Goalie::monitor_state_)
      .defaults_to(std::string("monitor_ball"))
      .describe("the machine's state that watches the ball, queued after a pre-emption");
  declare_own_goal(info, &Goalie::goal_param_);
  info.param("goal_width", &Goalie::goal_width_)
      .defaults_to(2.6)
      .range(0.1, 10.0)
      .describe("the distance between the posts (m)");
  info.param("shot_speed", &Goalie::shot_speed_)
      .defaults_to(1.0)
      .range(0.0, 20.0)
      .describe("a ball slower than this is no shot (m/s)");
  info.param("reach", &Goalie::reach_)
      .defaults_to(0.85)
      .range(0.0, 5.0)
      .describe("dive only for a ball that will pass this close to the robot's centre (m)");
  info.param("warning_time", &Goalie::warning_time_)
      .defaults_to(1.0)
      .range(0.0, 10.0)
      .describe("dive when the ball will pass the robot within this time (s)");
  info.param("ball_deceleration", &Goalie::deceleration_)
      .defaults_to(0.6)
      .range(0.0, 10.0)
      .describe("the rolling ball's loss of speed, for predicting where it stops (m/s²)");
  info.port("button", &Goalie::button_).describe("true in the step the button is pressed");
  info.port("ball_visible", &Goalie::visible_)
      .describe("whether the camera sees the ball this step");
  info.port("ball_position", &Goalie::position_)
      .describe("the measured ball position relative to the robot (m, x forward, y left)");
  info.port("ball_velocity", &Goalie::velocity_)
      .describe("the ball's velocity over the ground in the robot frame (m/s)");
  info.port("robot_pose", &Goalie::pose_)
      .describe("the robot's pose on the field: x, y (m), heading (rad)");
}

}  // namespace

void register_goalie(Registry& registry) {
  register_wait_for_button(registry);
  register_walk_to_pose(registry);
  register_monitor_ball(registry);
  register_dive(registry);
  register_goalie_behaviour(registry);
}

}  // namespace arbiter::soccer

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

namespace arbiter::soccer {
namespace {

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

ParamSpec& declare_own_goal(ClassInfo& info) {
  return info.param<Vec2>("goal")
      .defaults_to(Vec2{-4.5, 0.0})
      .describe("the centre of the goal to keep (m, field frame), on its goal line");
}

/// Holds until the button is pressed. A press in the step the state starts does not count: that
/// is the press that sent the goalie back to waiting.
class WaitForButton final : public State {
 public:
  void init(StateInitContext& ctx) override { button_ = ctx.input<bool>("button"); }

  StateResult execute(StateContext& ctx) override {
    const bool pressed = ctx.written(button_) && ctx.read(button_);
    return pressed && ctx.executions() > 0 ? StateResult::kProceed : StateResult::kHold;
  }

 private:
  Input<bool> button_;
};

/// Walks to a field pose: far from it, forwards while turning towards it; close to it, stepping
/// straight there while turning to the pose's heading. Proceeds once within the tolerances.
class WalkToPose final : public State {
 public:
  void init(StateInitContext& ctx) override {
    pose_ = ctx.input<Vec3>("robot_pose");
    gait_velocity_ = ctx.output<Vec3>("gait_velocity");
    x_ = ctx.param_handle<double>("x");
    y_ = ctx.param_handle<double>("y");
    theta_ = ctx.param_handle<double>("theta");
    position_tolerance_param_ = ctx.param_handle<double>("position_tolerance");
    angle_tolerance_param_ = ctx.param_handle<double>("angle_tolerance");
    near_distance_param_ = ctx.param_handle<double>("near_distance");
    gain_param_ = ctx.param_handle<double>("gain");
    max_forward_param_ = ctx.param_handle<double>("max_forward");
    max_sideways_param_ = ctx.param_handle<double>("max_sideways");
    max_turn_param_ = ctx.param_handle<double>("max_turn");
  }

  void activate(StateContext& ctx) override {
    target_ = {ctx.param(x_), ctx.param(y_), ctx.param(theta_)};
    position_tolerance_ = ctx.param(position_tolerance_param_);
    angle_tolerance_ = ctx.param(angle_tolerance_param_);
    near_distance_ = ctx.param(near_distance_param_);
    gain_ = ctx.param(gain_param_);
    max_forward_ = ctx.param(max_forward_param_);
    max_sideways_ = ctx.param(max_sideways_param_);
    max_turn_ = ctx.param(max_turn_param_);
  }

  StateResult execute(StateContext& ctx) override {
    const Pose robot = to_pose(ctx.read(pose_));
    const Point relative = to_robot(robot, target_.position());
    const double distance = norm(relative);
    const double turn = wrap_angle(target_.theta - robot.theta);
    if (distance <= position_tolerance_ && std::abs(turn) <= angle_tolerance_) {
      ctx.write(gait_velocity_, Vec3{});
      return StateResult::kProceed;
    }
    // Never faster than would cover the rest of the way in one step, whatever the gain.
    const double speed =
        std::min(gain_ * distance, ctx.period() > 0.0 ? distance / ctx.period()
                                                      : std::numeric_limits<double>::infinity());
    Vec3 walk;
    if (distance > near_distance_) {
      const double error = bearing(relative);
      walk.x = std::min(max_forward_, speed) * std::max(0.0, std::cos(error));
      walk.z = std::clamp(2.0 * error, -max_turn_, max_turn_);
    } else {
      const double scale = distance > 1e-9 ? speed / distance : 0.0;
      walk.x = std::clamp(scale * relative.x, -max_forward_, max_forward_);
      walk.y = std::clamp(scale * relative.y, -max_sideways_, max_sideways_);
      walk.z = std::clamp(2.0 * turn, -max_turn_, max_turn_);
    }
    ctx.write(gait_velocity_, walk);
    return StateResult::kHold;
  }

 private:
  Input<Vec3> pose_;
  Output<Vec3> gait_velocity_;
  StateParam<double> x_;
  StateParam<double> y_;
  StateParam<double> theta_;
  StateParam<double> position_tolerance_param_;
  StateParam<double> angle_tolerance_param_;
  StateParam<double> near_distance_param_;
  StateParam<double> gain_param_;
  StateParam<double> max_forward_param_;
  StateParam<double> max_sideways_param_;
  StateParam<double> max_turn_param_;
  Pose target_;
  double position_tolerance_ = 0.0;
  double angle_tolerance_ = 0.0;
  double near_distance_ = 0.0;
  double gain_ = 0.0;
  double max_forward_ = 0.0;
  double max_sideways_ = 0.0;
  double max_turn_ = 0.0;
};

/// Watches the ball with the head. The best goalkeeping pose lies on the line from the goal's
/// centre to the ball, `distance` out from the goal and inside the goal area, facing the ball
/// (without a ball, `distance` straight out, facing the field). When the robot stands too far
/// from it, plans a walk there (`walk_state`) followed by another instance of itself, and
/// proceeds.
class MonitorBall final : public State {
 public:
  void init(StateInitContext& ctx) override {
    memory_.init(ctx);
    head_angle_ = ctx.output<double>("head_angle");
    // Resolved here once, so that a re-plan looks up no name and a walk state the machine does
    // not declare fails the load.
    walk_ = ctx.plan_state<double, double, double>(ctx.param<std::string>("walk_state"),
                                                   {"x", "y", "theta"},
                                                   ctx.param_location("walk_state"));
    again_ = ctx.plan_state<>(ctx.name());
    goal_param_ = ctx.param_handle<Vec2>("goal");
    distance_param_ = ctx.param_handle<double>("distance");
    depth_param_ = ctx.param_handle<double>("depth");
    half_width_param_ = ctx.param_handle<double>("half_width");
    replan_distance_param_ = ctx.param_handle<double>("replan_distance");
    replan_angle_param_ = ctx.param_handle<double>("replan_angle");
    ball_timeout_ = ctx.param_handle<double>("ball_timeout");
    search_time_ = ctx.param_handle<double>("search_time");
    head_sweep_param_ = ctx.param_handle<double>("head_sweep");
    sweep_time_ = ctx.param_handle<double>("sweep_time");
  }

  void activate(StateContext& ctx) override {
    memory_.reset();
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
    memory_.update(ctx);
    const bool known = memory_.seen_within(timeout_steps_);
    ctx.write(head_angle_, known ? std::clamp(bearing(memory_.relative()), -kHeadLimit, kHeadLimit)
                                 : sweep_angle(ctx.executions()));
    Pose best;
    if (known) {
      best = position_for(memory_.field());
    } else if (ctx.executions() + 1 >= static_cast<std::uint64_t>(search_steps_)) {
      best = {goal_.x + distance_ * std::cos(out_), goal_.y + distance_ * std::sin(out_), out_};
    } else {
      return StateResult::kHold;
    }
    const Pose& robot = memory_.robot();
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

  BallMemory memory_;
  Output<double> head_angle_;
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
  void init(StateInitContext& ctx) override {
    position_ = ctx.input<Vec2>("ball_position");
    velocity_ = ctx.input<Vec2>("ball_velocity");
    dive_ = ctx.output<std::int64_t>("dive");
    duration_ = ctx.param_handle<double>("duration");
  }

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
    button_ = ctx.input<bool>("button");
    visible_ = ctx.input<bool>("ball_visible");
    position_ = ctx.input<Vec2>("ball_position");
    velocity_ = ctx.input<Vec2>("ball_velocity");
    pose_ = ctx.input<Vec3>("robot_pose");
    goal_ = to_point(ctx.param<Vec2>("goal"));
    out_ = out_of_goal(goal_);
    goal_width_ = ctx.param<double>("goal_width");
    shot_speed_ = ctx.param<double>("shot_speed");
    reach_ = ctx.param<double>("reach");
    warning_time_ = ctx.param<double>("warning_time");
    deceleration_ = ctx.param<double>("ball_deceleration");

    controller_ =
        ctx.claim_controller(ctx.param<std::string>("machine"), ctx.param_location("machine"));
    if (controller_ == nullptr) return;
    const bool found = resolve(ctx, "wait_state", wait_) && resolve(ctx, "dive_state", dive_) &&
                       resolve(ctx, "monitor_state", monitor_);
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
  /// Looks a state the hooks plan up once, so that a pre-emption looks up no name.
  bool resolve(InitContext& ctx, const char* param, PlannedState& out) {
    const std::string name = ctx.param<std::string>(param);
    const auto& states = controller_->states();
    const auto found = std::find_if(states.begin(), states.end(),
                                    [&](const CompiledState& state) { return state.name == name; });
    if (found == states.end()) {
      std::vector<std::string> known;
      for (const auto& state : states) known.push_back(state.name);
      ctx.error(ctx.param_location(param),
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
        ctx.error(ctx.param_location(param),
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
  info.input<bool>("button").describe("true in the step the button is pressed");
}

void register_walk_to_pose(Registry& registry) {
  auto& info = add_state_class<WalkToPose>(registry, "soccer.WalkToPose")
                   .describe(
                       "Walks to a pose on the field: far from it, forwards while turning towards "
                       "it; within near_distance, stepping straight there while turning to its "
                       "heading. Proceeds once within both tolerances.");
  info.param<double>("x").describe("the target's x on the field (m)");
  info.param<double>("y").describe("the target's y on the field (m)");
  info.param<double>("theta")
      .range(-2.0 * kPi, 2.0 * kPi)
      .describe("the target heading (rad, from the field's x axis)");
  info.param<double>("position_tolerance")
      .defaults_to(0.1)
      .range(0.01, 2.0)
      .describe("arrived when this close to the target position (m)");
  info.param<double>("angle_tolerance")
      .defaults_to(0.15)
      .range(0.01, 3.2)
      .describe("... and this close to the target heading (rad)");
  info.param<double>("near_distance")
      .defaults_to(0.7)
      .range(0.0, 10.0)
      .describe("within this distance of the target, step straight to it (m)");
  info.param<double>("gain").defaults_to(1.5).range(0.0, 10.0).describe(
      "walking speed per metre of distance to the target (1/s)");
  info.param<double>("max_forward")
      .defaults_to(0.3)
      .range(0.0, 1.0)
      .describe("the fastest forward (and backward) speed requested (m/s)");
  info.param<double>("max_sideways")
      .defaults_to(0.2)
      .range(0.0, 1.0)
      .describe("the fastest sideways speed requested (m/s)");
  info.param<double>("max_turn")
      .defaults_to(1.0)
      .range(0.0, 3.0)
      .describe("the fastest turn rate requested (rad/s)");
  info.input<Vec3>("robot_pose").describe("the robot's pose on the field: x, y (m), heading (rad)");
  info.output<Vec3>("gait_velocity").describe("the walk command: forward, sideways, turn rate");
}

void register_monitor_ball(Registry& registry) {
  auto& info =
      add_state_class<MonitorBall>(registry, "soccer.MonitorBall")
          .describe(
              "Watches the ball with the head (sweeping it while the ball is unknown). When the "
              "best goalkeeping pose (on the line from the goal's centre to the ball, distance "
              "out and inside the goal area, facing the ball) is too far from the robot's, plans "
              "walk_state to it followed by another instance of this state, and proceeds.");
  declare_own_goal(info);
  info.param<double>("distance")
      .defaults_to(0.5)
      .range(0.0, 3.0)
      .describe("how far out from the goal's centre, towards the ball, to stand (m)");
  info.param<double>("depth").defaults_to(1.0).range(0.05, 3.0).describe(
      "the goal area's depth: never farther out from the goal line (m)");
  info.param<double>("half_width")
      .defaults_to(1.1)
      .range(0.0, 3.0)
      .describe("never farther to the side of the goal's centre (m)");
  info.param<double>("replan_distance")
      .defaults_to(0.2)
      .range(0.0, 5.0)
      .describe("plan a walk when the best position is farther than this (m)");
  info.param<double>("replan_angle")
      .defaults_to(0.35)
      .range(0.0, 3.2)
      .describe("... or the best heading differs by more than this (rad)");
  info.param<double>("ball_timeout")
      .defaults_to(2.0)
      .range(0.0, 60.0)
      .describe("how long a ball seen by this instance counts as known (s)");
  info.param<double>("search_time")
      .defaults_to(3.0)
      .range(0.0, 60.0)
      .describe("without a known ball after this long, take the position straight out (s)");
  info.param<double>("head_sweep")
      .defaults_to(1.2)
      .range(0.0, kHeadLimit)
      .describe("amplitude of the head sweep while the ball is unknown (rad)");
  info.param<double>("sweep_time")
      .defaults_to(3.0)
      .range(0.1, 60.0)
      .describe("duration of one full head sweep, left and right (s)");
  info.param<std::string>("walk_state")
      .defaults_to(std::string("walk_to_pose"))
      .state_level()
      .describe(
          "the state planned to walk (with params x, y, theta); the state machine must declare "
          "it, else the load fails naming it");
  BallMemory::declare_ports(info);
  info.output<double>("head_angle").describe("the head yaw target (rad)");
}

void register_dive(Registry& registry) {
  auto& info = add_state_class<Dive>(registry, "soccer.Dive")
                   .describe(
                       "Dives to the side on which the ball will pass the robot, reports 'goalie "
                       "dives left' or 'goalie dives right', and proceeds after duration.");
  info.param<double>("duration")
      .defaults_to(2.0)
      .range(0.0, 60.0)
      .describe("how long the state lasts from the dive (s)");
  info.input<Vec2>("ball_position")
      .describe("the last measured ball position relative to the robot (m, x forward, y left)");
  info.input<Vec2>("ball_velocity")
      .make_optional()
      .describe(
          "the ball's velocity in the robot frame (m/s); without it, dives towards the side the "
          "ball lies on");
  info.output<std::int64_t>("dive").describe("+1 dives to the left, -1 to the right");
}

void register_goalie_behaviour(Registry& registry) {
  auto& info = registry.add_behaviour<Goalie>("soccer.Goalie")
                   .describe(
                       "Steps the goalie's state machine while active and requests 1 while it "
                       "runs. Pre-empts its plan: a button press goes back to wait_state, a shot "
                       "on goal that will pass within reach goes to dive_state; monitor_state is "
                       "queued after either.");
  info.param<std::string>("machine").describe("the state machine to own and step");
  info.param<std::string>("wait_state")
      .defaults_to(std::string("wait_for_button"))
      .describe("the machine's state that waits for the button");
  info.param<std::string>("dive_state")
      .defaults_to(std::string("dive"))
      .describe("the machine's state that dives");
  info.param<std::string>("monitor_state")
      .defaults_to(std::string("monitor_ball"))
      .describe("the machine's state that watches the ball, queued after a pre-emption");
  declare_own_goal(info);
  info.param<double>("goal_width")
      .defaults_to(2.6)
      .range(0.1, 10.0)
      .describe("the distance between the posts (m)");
  info.param<double>("shot_speed")
      .defaults_to(1.0)
      .range(0.0, 20.0)
      .describe("a ball slower than this is no shot (m/s)");
  info.param<double>("reach").defaults_to(0.85).range(0.0, 5.0).describe(
      "dive only for a ball that will pass this close to the robot's centre (m)");
  info.param<double>("warning_time")
      .defaults_to(1.0)
      .range(0.0, 10.0)
      .describe("dive when the ball will pass the robot within this time (s)");
  info.param<double>("ball_deceleration")
      .defaults_to(0.6)
      .range(0.0, 10.0)
      .describe("the rolling ball's loss of speed, for predicting where it stops (m/s²)");
  info.input<bool>("button").describe("true in the step the button is pressed");
  info.input<bool>("ball_visible").describe("whether the camera sees the ball this step");
  info.input<Vec2>("ball_position")
      .describe("the measured ball position relative to the robot (m, x forward, y left)");
  info.input<Vec2>("ball_velocity")
      .describe("the ball's velocity over the ground in the robot frame (m/s)");
  info.input<Vec3>("robot_pose").describe("the robot's pose on the field: x, y (m), heading (rad)");
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

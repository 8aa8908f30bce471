#include "world.hpp"

#include <algorithm>
#include <cmath>

namespace arbiter::soccer {
namespace {

double approach(double from, double to, double max_change) {
  return from + std::clamp(to - from, -max_change, max_change);
}

}  // namespace

World::World(const WorldConfig& config)
    : config_(config), rng_(config.seed), robot_(config.robot_start), ball_(config.ball_start) {}

Observation World::observe() {
  Observation seen;
  seen.robot = robot_;
  seen.button = button_pressed_ || (config_.button_step >= 1 && steps_ + 1 == config_.button_step);
  seen.ball_kicked = kicked_;
  seen.goal = goal_;
  seen.shot = shot_;
  seen.ball_saved = saved_;
  seen.kick_off = kicked_off_;
  seen.ball_visible = ball_in_view();
  if (seen.ball_visible) {
    seen.ball = to_robot(robot_, ball_);
    seen.ball_velocity = rotate(ball_velocity_, -robot_.theta);
    if (config_.noise > 0.0) {
      seen.ball.x += config_.noise * noise_(rng_);
      seen.ball.y += config_.noise * noise_(rng_);
    }
  }
  return seen;
}

bool World::ball_in_view() const {
  const Point relative = to_robot(robot_, ball_);
  const double distance = norm(relative);
  if (distance > config_.camera_range) return false;
  return std::abs(wrap_angle(bearing(relative) - head_yaw_)) <= config_.camera_half_fov;
}

bool World::ball_in_reach() const {
  const Point relative = to_robot(robot_, ball_);
  return norm(relative) <= config_.kick_reach &&
         std::abs(bearing(relative)) <= config_.kick_half_angle;
}

void World::step(const Command& command) {
  kicked_ = false;
  goal_ = 0;
  button_pressed_ = false;
  saved_ = false;
  kicked_off_ = false;
  // Counted before this step can score, so that the kick-off comes kick_off_delay after the goal.
  const bool kick_off_due = kick_off_steps_ > 0 && --kick_off_steps_ == 0;
  shot_ = config_.shot_step >= 1 && steps_ + 1 == config_.shot_step;
  if (shot_) shoot(config_.shot_target, config_.shot_speed);
  if (command.kick && !down() && ball_in_reach()) {
    ball_velocity_ = config_.kick_speed * unit(robot_.theta);
    kicked_ = true;
    ++kicks_;
  }
  if (command.dive != 0 && !down()) {
    dive_side_ = command.dive > 0 ? 1 : -1;
    down_steps_ = std::max<std::int64_t>(1, std::lround(config_.dive_time / config_.dt));
  }
  // A robot on the ground neither walks nor keeps the speed it had.
  if (down()) {
    velocity_ = {};
  } else {
    walk(command.walk);
  }
  roll();
  push_ball();
  const double target = std::clamp(command.head_angle, -config_.head_limit, config_.head_limit);
  head_yaw_ = approach(head_yaw_, target, config_.head_speed * config_.dt);
  if (down_steps_ > 0 && --down_steps_ == 0) dive_side_ = 0;
  if (kick_off_due) kick_off();
  ++steps_;
}

void World::walk(const Twist& command) {
  const double dt = config_.dt;
  const Twist limited{std::clamp(command.forward, -config_.max_backward, config_.max_forward),
                      std::clamp(command.sideways, -config_.max_sideways, config_.max_sideways),
                      std::clamp(command.turn, -config_.max_turn, config_.max_turn)};
  velocity_.forward =
      approach(velocity_.forward, limited.forward, config_.linear_acceleration * dt);
  velocity_.sideways =
      approach(velocity_.sideways, limited.sideways, config_.linear_acceleration * dt);
  velocity_.turn = approach(velocity_.turn, limited.turn, config_.turn_acceleration * dt);

  // Integrating along the mid-step heading keeps a turning walk on its arc.
  const double heading = robot_.theta + 0.5 * velocity_.turn * dt;
  const Point moved = rotate({velocity_.forward * dt, velocity_.sideways * dt}, heading);
  const double x_limit = 0.5 * config_.field_length + config_.robot_margin;
  const double y_limit = 0.5 * config_.field_width + config_.robot_margin;
  robot_.x = std::clamp(robot_.x + moved.x, -x_limit, x_limit);
  robot_.y = std::clamp(robot_.y + moved.y, -y_limit, y_limit);
  robot_.theta = wrap_angle(robot_.theta + velocity_.turn * dt);
}

void World::roll() {
  const double speed = norm(ball_velocity_);
  if (speed == 0.0) return;
  const double dt = config_.dt;
  // Constant deceleration: the ball covers the mean of its old and new speed, and stops exactly
  // when the speed would turn negative.
  const double stop_time = speed / config_.ball_deceleration;
  const double time = std::min(dt, stop_time);
  const double new_speed = speed - config_.ball_deceleration * time;
  const Point direction = (1.0 / speed) * ball_velocity_;
  ball_velocity_ = new_speed * direction;
  const Point target = ball_ + (0.5 * (speed + new_speed) * time) * direction;
  double fraction = 1.0;
  Point contact;
  if (down() && hits_body(target, fraction, contact)) {
    // The ball bounces off the lying body: its speed towards the body is reversed and damped.
    const Point at = ball_ + fraction * (target - ball_);
    const Point offset = at - contact;
    const Point normal = (1.0 / norm(offset)) * offset;
    const double towards = dot(ball_velocity_, normal);
    if (towards < 0.0) {
      ball_velocity_ = ball_velocity_ - ((1.0 + config_.save_restitution) * towards) * normal;
    }
    saved_ = true;
    ++saves_;
    move_ball_to(at);
    return;
  }
  move_ball_to(target);
}

bool World::hits_body(Point target, double& fraction, Point& contact) const {
  const Point path = target - ball_;
  // Sampled finely enough that even a hard shot cannot pass through the body between samples.
  constexpr double kSampleLength = 0.02;
  const int samples = std::max(1, static_cast<int>(std::ceil(norm(path) / kSampleLength)));
  for (int k = 1; k <= samples; ++k) {
    const double s = static_cast<double>(k) / samples;
    const Point at = ball_ + s * path;
    const Point closest = closest_on_body(at);
    const Point offset = at - closest;
    const double distance = norm(offset);
    if (distance <= config_.contact_distance && distance > 1e-9 && dot(path, offset) < 0.0) {
      fraction = s;
      contact = closest;
      return true;
    }
  }
  return false;
}

Point World::body_end() const {
  if (!down()) return robot_.position();
  return robot_.position() + (dive_side_ * config_.dive_reach) * unit(robot_.theta + 0.5 * kPi);
}

Point World::closest_on_body(Point point) const {
  if (!down()) return robot_.position();
  const Point start = robot_.position();
  const Point along = body_end() - start;
  const double t = std::clamp(dot(point - start, along) / dot(along, along), 0.0, 1.0);
  return start + t * along;
}

void World::push_ball() {
  const Point body = closest_on_body(ball_);
  const Point offset = ball_ - body;
  const double distance = norm(offset);
  if (distance >= config_.contact_distance) return;
  const Point normal = distance > 1e-9 ? (1.0 / distance) * offset : unit(robot_.theta);
  // The ball gets at least the robot's speed away from it, so a walking robot dribbles it.
  const Point robot_velocity = rotate({velocity_.forward, velocity_.sideways}, robot_.theta);
  const double away = std::max({dot(ball_velocity_, normal), dot(robot_velocity, normal), 0.0});
  ball_velocity_ = ball_velocity_ + (away - dot(ball_velocity_, normal)) * normal;
  move_ball_to(body + config_.contact_distance * normal);
}

void World::move_ball_to(Point target) {
  const double half_length = 0.5 * config_.field_length;
  const double half_width = 0.5 * config_.field_width;
  const double half_goal = 0.5 * config_.goal_width;
  const Point from = ball_;
  Point path = target - from;
  // A ball lying on a line is not moved out over it but slides along it, so that a ball stuck in
  // a corner can still be played; between the posts, out over the goal line means into the goal.
  if (std::abs(from.x) >= half_length && from.x * path.x > 0.0) {
    if (std::abs(from.y) < half_goal) {
      score(from.x > 0.0 ? 1 : -1);
      ball_velocity_ = {};
      return;
    }
    path.x = 0.0;
  }
  if (std::abs(from.y) >= half_width && from.y * path.y > 0.0) path.y = 0.0;
  target = from + path;

  // Otherwise the first line the path crosses stops the ball on it.
  double fraction = 1.0;
  int crossed_x = 0;
  bool crossed = false;
  if (std::abs(target.x) > half_length) {
    const double line = std::copysign(half_length, target.x);
    fraction = std::clamp((line - from.x) / path.x, 0.0, 1.0);
    crossed_x = target.x > 0.0 ? 1 : -1;
    crossed = true;
  }
  if (std::abs(target.y) > half_width) {
    const double line = std::copysign(half_width, target.y);
    const double t = std::clamp((line - from.y) / path.y, 0.0, 1.0);
    if (t < fraction) {
      fraction = t;
      crossed_x = 0;
    }
    crossed = true;
  }
  ball_ = from + fraction * path;
  if (crossed) {
    ball_.x = std::clamp(ball_.x, -half_length, half_length);
    ball_.y = std::clamp(ball_.y, -half_width, half_width);
    ball_velocity_ = {};
    if (crossed_x != 0 && std::abs(ball_.y) < half_goal) score(crossed_x);
  }
  if (std::abs(ball_.x) < half_length) in_goal_ = false;
}

void World::score(int side) {
  // A ball that lies in the goal is pushed about in it without scoring again.
  if (in_goal_) return;
  in_goal_ = true;
  goal_ = side;
  ++(side > 0 ? goals_positive_ : goals_negative_);
  if (config_.kick_off_delay >= 0.0) {
    kick_off_steps_ = std::max<std::int64_t>(1, std::lround(config_.kick_off_delay / config_.dt));
  }
}

void World::kick_off() {
  place_ball({0.0, 0.0});
  place_robot(config_.robot_start);
  down_steps_ = 0;
  dive_side_ = 0;
  kicked_off_ = true;
}

void World::place_ball(Point position, Point velocity) {
  ball_ = position;
  ball_velocity_ = velocity;
  in_goal_ = false;
}

void World::shoot(Point target, double speed) {
  const Point to_target = target - ball_;
  if (norm(to_target) < 1e-9) return;
  ball_velocity_ = speed * unit(bearing(to_target));
  in_goal_ = false;
}

void World::place_robot(const Pose& pose) {
  robot_ = pose;
  velocity_ = {};
}

void World::set_head_yaw(double yaw) {
  head_yaw_ = std::clamp(yaw, -config_.head_limit, config_.head_limit);
}

}  // namespace arbiter::soccer

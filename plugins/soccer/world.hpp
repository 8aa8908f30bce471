#pragma once
// A small deterministic 2-D soccer world: one robot, one ball, two goals, a head camera, a
// button, and a dive that lays the robot down across the ball's path. Plain C++ without engine
// types so that it can be tested on its own; soccer.WorldLink connects it to a behaviour manager.
// Units are metres, seconds and radians.

#include <cstdint>
#include <random>

#include "geometry.hpp"

namespace arbiter::soccer {

/// A walking command or velocity in the robot frame.
struct Twist {
  double forward = 0.0;   ///< m/s
  double sideways = 0.0;  ///< m/s, positive to the left
  double turn = 0.0;      ///< rad/s, positive counter-clockwise
};

struct WorldConfig {
  // Field: 9 m x 6 m, goals 2.6 m wide centred on the goal lines at x = ±4.5.
  double field_length = 9.0;
  double field_width = 6.0;
  double goal_width = 2.6;

  /// One step; 1/15 s matches the configs' rate_hz of 15.
  double dt = 1.0 / 15.0;
  std::uint32_t seed = 0;
  Pose robot_start{-3.0, 0.0, 0.0};
  Point ball_start{0.0, 0.0};
  /// Standard deviation of each axis of the ball measurement (m); 0 measures exactly.
  double noise = 0.0;
  /// The step (counting from 1, like the manager's) in which the button is pressed; -1: never.
  std::int64_t button_step = -1;
  /// The step (counting from 1) at the end of which the ball is shot from where it lies towards
  /// shot_target at shot_speed, as an opponent's shot on goal; -1: never.
  std::int64_t shot_step = -1;
  Point shot_target{-4.5, 0.0};
  double shot_speed = 3.5;  ///< m/s
  /// Seconds from a goal to the kick-off that follows it: the ball back on the centre spot and
  /// the robot at robot_start, so that play goes on; negative: never (the ball stays in the goal).
  double kick_off_delay = 2.0;

  double ball_deceleration = 0.6;  ///< rolling friction, m/s²
  /// Robot radius plus ball radius: closer than this, the robot pushes the ball.
  double contact_distance = 0.15;
  double kick_speed = 3.0;       ///< the ball's speed after a kick, m/s
  double kick_reach = 0.3;       ///< from the robot's centre (its feet) to the ball's centre
  double kick_half_angle = 0.4;  ///< the ball must lie within this bearing to be kicked

  double max_forward = 0.4;
  double max_backward = 0.2;
  double max_sideways = 0.25;
  double max_turn = 1.5;
  double linear_acceleration = 1.0;  ///< m/s², per axis
  double turn_acceleration = 4.0;    ///< rad/s²
  /// The robot stays within this margin around the field lines.
  double robot_margin = 0.5;

  /// A dive lays the robot down on its left or right side: its body then reaches this far from
  /// its centre (m), blocks the ball along that length, and it cannot walk for dive_time (s).
  double dive_reach = 0.7;
  double dive_time = 2.0;
  /// The share of the ball's speed towards a diving robot that it keeps, bouncing back.
  double save_restitution = 0.3;

  double head_limit = 1.5;  ///< head yaw, either side of straight ahead
  double head_speed = 6.0;  ///< rad/s
  double camera_half_fov = 0.5;
  double camera_range = 5.0;
};

/// What the robot senses at the start of a step.
struct Observation {
  bool ball_visible = false;
  Point ball;  ///< robot frame, with measurement noise; zero when not visible
  /// The ball's velocity over the ground in the robot frame, as a ball filter would estimate it;
  /// zero when not visible.
  Point ball_velocity;
  Pose robot;  ///< as a perfect localisation would report it
  bool button = false;
  bool ball_kicked = false;  ///< a kick happened in the last step()
  int goal = 0;             ///< +1 or -1: the ball entered the goal at x = ±4.5 in the last step()
  bool shot = false;        ///< the ball was shot on goal (shot_step) in the last step()
  bool ball_saved = false;  ///< a diving robot stopped the ball in the last step()
  bool kick_off = false;    ///< the last step() ended with a kick-off after a goal
};

struct Command {
  Twist walk;
  double head_angle = 0.0;  ///< target yaw of the head relative to the body
  bool kick = false;
  /// +1 dives to the left, -1 to the right, 0 not; ignored while the robot is down.
  int dive = 0;
};

class World {
 public:
  explicit World(const WorldConfig& config);

  /// The robot's senses now. Draws measurement noise, so it is called once per step.
  Observation observe();
  /// Advances the world by one dt: shot, kick, dive, walk, roll, push, move the head, then the
  /// kick-off when a goal's kick_off_delay has passed.
  void step(const Command& command);

  const WorldConfig& config() const { return config_; }
  const Pose& robot() const { return robot_; }
  const Twist& robot_velocity() const { return velocity_; }
  Point ball() const { return ball_; }
  Point ball_velocity() const { return ball_velocity_; }
  double head_yaw() const { return head_yaw_; }
  /// Steps taken so far.
  std::int64_t steps() const { return steps_; }
  int goals_at(int side) const { return side > 0 ? goals_positive_ : goals_negative_; }
  int kicks() const { return kicks_; }
  int saves() const { return saves_; }
  /// Whether the robot lies on the ground after a dive, and to which side (+1 left, -1 right).
  bool down() const { return down_steps_ > 0; }
  int dive_side() const { return dive_side_; }

  /// Ground truth without noise: whether the camera sees the ball, and whether a kick would hit it.
  bool ball_in_view() const;
  bool ball_in_reach() const;

  /// For tests and resets: puts the ball (or the robot) somewhere, without events.
  void place_ball(Point position, Point velocity = {});
  void place_robot(const Pose& pose);
  void set_head_yaw(double yaw);
  /// Presses the button: the next observe() reports it.
  void press_button() { button_pressed_ = true; }
  /// Shoots the ball from where it lies towards `target` at `speed` (m/s).
  void shoot(Point target, double speed);

 private:
  void walk(const Twist& command);
  void roll();
  void push_ball();
  void move_ball_to(Point target);
  void score(int side);
  void kick_off();
  /// Whether the ball, moving from where it lies to `target`, runs into the body of the robot
  /// lying after a dive; if so, `fraction` is the part of the path it covers until it touches,
  /// and `contact` the body's point closest to it there.
  bool hits_body(Point target, double& fraction, Point& contact) const;
  /// The robot's body as a segment: its centre, and while down the end of the outstretched body.
  Point body_end() const;
  Point closest_on_body(Point point) const;

  WorldConfig config_;
  std::mt19937 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  Pose robot_;
  Twist velocity_;
  Point ball_;
  Point ball_velocity_;
  double head_yaw_ = 0.0;
  std::int64_t steps_ = 0;
  bool kicked_ = false;
  int goal_ = 0;
  bool in_goal_ = false;
  bool button_pressed_ = false;
  bool shot_ = false;
  bool saved_ = false;
  bool kicked_off_ = false;
  /// Steps left until the kick-off after a goal; 0: none pending.
  std::int64_t kick_off_steps_ = 0;
  std::int64_t down_steps_ = 0;
  int dive_side_ = 0;
  int kicks_ = 0;
  int saves_ = 0;
  int goals_positive_ = 0;
  int goals_negative_ = 0;
};

}  // namespace arbiter::soccer

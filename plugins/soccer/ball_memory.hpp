#pragma once
// What a behaviour or state of the soccer demo knows of the ball, and the conversions between the
// engine's vector types and the demo's geometry.

#include <cstdint>
#include <limits>

#include "arbiter/behaviour.hpp"
#include "arbiter/registry.hpp"
#include "geometry.hpp"

namespace arbiter::soccer {

inline Pose to_pose(const Vec3& pose) {
  return {pose.x, pose.y, pose.z};
}
inline Point to_point(const Vec2& point) {
  return {point.x, point.y};
}

/// What one behaviour or state knows of the ball: where on the field it was last seen, and how
/// many steps ago. Kept in the field frame so that it stays right while the robot walks. A class
/// that needs it derives from it (publicly: its ports are bound to these members) and declares
/// its ports with declare_ports(). Every behaviour keeps its own, updated in update() whether or
/// not the behaviour is active; a state instance keeps its own from activate()
/// (forget_ball()) on, updated in each execute().
class BallMemory {
 public:
  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();

  template <typename C>
  static void declare_ports(ClassBinder<C>& info) {
    info.port("ball_visible", &BallMemory::visible_)
        .describe("whether the camera sees the ball this step");
    info.port("ball_position", &BallMemory::position_)
        .describe("the measured ball position relative to the robot (m, x forward, y left)");
    info.port("robot_pose", &BallMemory::pose_)
        .describe("the robot's pose on the field: x, y (m) and heading (rad)");
  }

  void remember_ball(const StepContext& ctx) {
    robot_ = to_pose(ctx.read(pose_));
    if (ctx.read(visible_)) {
      field_ = to_field(robot_, to_point(ctx.read(position_)));
      age_ = 0;
    } else if (age_ != kNever) {
      ++age_;
    }
  }

  /// Forgets the ball, for a state instance taken from the pool.
  void forget_ball() { age_ = kNever; }

  /// Steps since the ball was last seen: 0 when it is seen now, kNever before it was ever seen.
  std::int64_t ball_age() const { return age_; }
  bool ball_seen_within(std::int64_t steps) const { return age_ <= steps; }
  const Pose& robot_pose() const { return robot_; }
  /// Where the ball was last seen, on the field.
  Point ball_field() const { return field_; }
  /// Where the ball was last seen, relative to the robot as it stands now.
  Point ball_relative() const { return to_robot(robot_, field_); }

 private:
  Input<bool> visible_;
  Input<Vec2> position_;
  Input<Vec3> pose_;
  Pose robot_;
  Point field_;
  std::int64_t age_ = kNever;
};

}  // namespace arbiter::soccer

#pragma once
// Plane geometry shared by the soccer world and its behaviours. Field frame: origin at the centre
// spot, x towards the goal at x = +4.5, y to the left of it. Robot frame: x forward, y left.

#include <cmath>

namespace arbiter::soccer {

inline constexpr double kPi = 3.14159265358979323846;

struct Point {
  double x = 0.0;
  double y = 0.0;
};

inline Point operator+(Point a, Point b) {
  return {a.x + b.x, a.y + b.y};
}
inline Point operator-(Point a, Point b) {
  return {a.x - b.x, a.y - b.y};
}
inline Point operator*(double k, Point a) {
  return {k * a.x, k * a.y};
}
inline double dot(Point a, Point b) {
  return a.x * b.x + a.y * b.y;
}
inline double norm(Point a) {
  return std::hypot(a.x, a.y);
}
inline double bearing(Point a) {
  return std::atan2(a.y, a.x);
}
inline Point unit(double angle) {
  return {std::cos(angle), std::sin(angle)};
}
inline Point rotate(Point a, double angle) {
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  return {c * a.x - s * a.y, s * a.x + c * a.y};
}

/// The angle in (-π, π].
inline double wrap_angle(double angle) {
  angle = std::remainder(angle, 2.0 * kPi);
  return angle <= -kPi ? angle + 2.0 * kPi : angle;
}

struct Pose {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;  ///< heading, radians from the field's x axis
  Point position() const { return {x, y}; }
};

/// A point of the field frame seen from `pose`, in the robot frame.
inline Point to_robot(const Pose& pose, Point field) {
  return rotate(field - pose.position(), -pose.theta);
}
/// A point of the robot frame at `pose`, in the field frame.
inline Point to_field(const Pose& pose, Point robot) {
  return pose.position() + rotate(robot, pose.theta);
}

}  // namespace arbiter::soccer

#pragma once
// The walk command of the soccer classes that walk to a target (soccer.GoBehindBall,
// soccer.WalkToPose), and the params that limit it.

#include <algorithm>
#include <cmath>

#include "arbiter/registry.hpp"
#include "geometry.hpp"

namespace arbiter::soccer {

/// How a walk to a target is commanded: within near_distance the robot steps straight there,
/// farther away it walks forwards; never faster than the max_ speeds and turn rate.
struct WalkLimits {
  double near_distance = 0.0;
  double max_forward = 0.0;
  double max_sideways = 0.0;
  double max_turn = 0.0;
};

/// The params that set the walk towards a target, as a base of the class that walks: values for
/// a behaviour, StateParam<double> handles for a state (which reads them per planned instance).
template <typename T>
struct WalkParams {
  T gain{};
  T max_forward{};
  T max_sideways{};
  T max_turn{};

  /// Declares `gain`, `max_forward`, `max_sideways` and `max_turn`, bound to these members.
  template <typename C>
  static void declare(ClassBinder<C>& info, double forward_default, const char* forward_text) {
    info.param("gain", &WalkParams::gain)
        .defaults_to(1.5)
        .range(0.0, 10.0)
        .describe("walking speed per metre of distance to the target (1/s)");
    info.param("max_forward", &WalkParams::max_forward)
        .defaults_to(forward_default)
        .range(0.0, 1.0)
        .describe(forward_text);
    info.param("max_sideways", &WalkParams::max_sideways)
        .defaults_to(0.2)
        .range(0.0, 1.0)
        .describe("the fastest sideways speed requested (m/s)");
    info.param("max_turn", &WalkParams::max_turn)
        .defaults_to(1.0)
        .range(0.0, 3.0)
        .describe("the fastest turn rate requested (rad/s)");
  }
};

/// The walk command towards `relative`, the target in the robot frame. Far away: forwards at
/// `speed`, slower while facing away from it, turning towards it. Close: stepping straight to it
/// at `scale` times its offset while turning by `turn`, what is left of the target heading.
inline Vec3 walk_towards(Point relative, double speed, double scale, double turn,
                         const WalkLimits& limits) {
  Vec3 walk;
  if (norm(relative) > limits.near_distance) {
    const double error = bearing(relative);
    walk.x = std::min(limits.max_forward, speed) * std::max(0.0, std::cos(error));
    walk.z = std::clamp(2.0 * error, -limits.max_turn, limits.max_turn);
  } else {
    walk.x = std::clamp(scale * relative.x, -limits.max_forward, limits.max_forward);
    walk.y = std::clamp(scale * relative.y, -limits.max_sideways, limits.max_sideways);
    walk.z = std::clamp(2.0 * turn, -limits.max_turn, limits.max_turn);
  }
  return walk;
}

}  // namespace arbiter::soccer

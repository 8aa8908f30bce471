#include <arbiter/init_context.hpp>
#include <cmath>

#include "beacon.hpp"
#include "patrol.hpp"

namespace patrol {
namespace {

using arbiter::Vec2;

/// Stands in for the robot's base: publishes the position in the input pass; in the output pass
/// drives at the commanded velocity (at most `max_speed`) for one step.
class Odometry final : public arbiter::Interface {
 public:
  void input(arbiter::WriteContext& ctx) override {
    ctx.write(position_, here_);
    // The robot on the live page and in a recording's 3D panel ("Drawing the world").
    ctx.scene("map").circle({here_.x, here_.y}, 0.2, arbiter::SceneColor{0.1f, 0.2f, 0.7f, 1.0f},
                            /*filled=*/true);
  }

  void output(const arbiter::StepContext& ctx) override {
    // Values persist until overwritten: the base stops in a step in which nobody commands it.
    const Vec2 velocity = ctx.written(velocity_) ? ctx.read(velocity_) : Vec2{};
    const double speed = std::hypot(velocity.x, velocity.y);
    const double scale = speed > max_speed_ ? max_speed_ / speed : 1.0;
    here_.x += scale * velocity.x * ctx.period();
    here_.y += scale * velocity.y * ctx.period();

    // Likewise the beacon flashes only in steps in which someone asks for it.
    const bool flashing = ctx.written(beacon_) && ctx.read(beacon_).on;
    if (flashing != flashing_) ctx.report(flashing ? "beacon on" : "beacon off");
    flashing_ = flashing;
  }

 private:
  friend void patrol::register_odometry(arbiter::Registry& registry);
  Vec2 here_;
  double max_speed_ = 0.0;
  bool flashing_ = false;
  arbiter::Output<Vec2> position_;
  arbiter::Input<Vec2> velocity_;
  arbiter::Input<Beacon> beacon_;
};

}  // namespace

void register_odometry(arbiter::Registry& registry) {
  auto& info = registry.add_interface<Odometry>("patrol.Odometry")
                   .describe("A simulated robot base that drives at the commanded velocity.");
  info.param("start", &Odometry::here_)
      .defaults_to(Vec2{0.0, 0.0})
      .describe("where the robot starts: x, y (m)");
  info.param("max_speed", &Odometry::max_speed_)
      .defaults_to(0.5)
      .range(0.0, 2.0)
      .describe("the fastest the base drives (m/s)");
  info.port("position", &Odometry::position_).describe("where the robot is: x, y (m)");
  info.port("velocity", &Odometry::velocity_).describe("the commanded velocity: x, y (m/s)");
  info.port("beacon", &Odometry::beacon_).make_optional().describe("the beacon command");
}

}  // namespace patrol

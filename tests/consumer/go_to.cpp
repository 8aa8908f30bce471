#include <arbiter/init_context.hpp>
#include <cmath>

#include "beacon.hpp"
#include "patrol.hpp"

namespace patrol {
namespace {

using arbiter::Vec2;

/// Drives towards `target` (a proportional controller) and asks to be active until the robot
/// is within `tolerance` of it. Flashes the beacon while it drives. Its params and ports are
/// members that the engine fills before the first step, as register_go_to() binds them.
class GoTo final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext& ctx) override {
    return distance(ctx) > tolerance_ ? 1.0 : 0.0;
  }

  void execute(arbiter::ExecuteContext& ctx) override {
    if (ctx.just_activated()) ctx.report("setting off");
    const Vec2 here = ctx.read(position_);
    ctx.write(velocity_, Vec2{gain_ * (target_.x - here.x), gain_ * (target_.y - here.y)});
    ctx.write(beacon_, Beacon{true, 2.0});
  }

  void inhibited(const arbiter::InhibitedContext& ctx) override {
    if (ctx.just_deactivated() && distance(ctx) <= tolerance_) ctx.report("arrived");
  }

 private:
  double distance(const arbiter::StepContext& ctx) const {
    const Vec2 here = ctx.read(position_);
    return std::hypot(target_.x - here.x, target_.y - here.y);
  }

  friend void patrol::register_go_to(arbiter::Registry& registry);
  Vec2 target_;
  double gain_ = 0.0;
  double tolerance_ = 0.0;
  arbiter::Input<Vec2> position_;
  arbiter::Output<Vec2> velocity_;
  arbiter::Output<Beacon> beacon_;
};

}  // namespace

void register_go_to(arbiter::Registry& registry) {
  auto& info = registry.add_behaviour<GoTo>("patrol.GoTo")
                   .describe("Drives to a point and is active until it is there.");
  info.param("target", &GoTo::target_).describe("where to go: x, y (m)");
  info.param("gain", &GoTo::gain_)
      .defaults_to(1.0)
      .range(0.0, 10.0)
      .describe("commanded speed per metre still to go (1/s)");
  info.param("tolerance", &GoTo::tolerance_)
      .defaults_to(0.05)
      .range(0.001, 1.0)
      .describe("how close counts as there (m)");
  info.port("position", &GoTo::position_).describe("where the robot is: x, y (m)");
  info.port("velocity", &GoTo::velocity_).describe("the commanded velocity: x, y (m/s)");
  info.port("beacon", &GoTo::beacon_).make_optional().describe("flashes while driving");
}

}  // namespace patrol

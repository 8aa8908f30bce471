#include <arbiter/behaviour.hpp>

#include "classes.hpp"

namespace @NAME@_plugin {
namespace {

/// A behaviour: asks to be active while an obstacle is closer than `threshold`, and while active
/// commands a speed of 0. Its param and ports are members, filled by the engine before the first
/// step as register_stop() binds them; the step reads and writes through them, by index.
class Stop final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext& ctx) override {
    return ctx.read(distance_) < threshold_ ? 1.0 : 0.0;
  }

  void execute(arbiter::ExecuteContext& ctx) override {
    if (ctx.just_activated()) ctx.report("obstacle at {:.2f} m", ctx.read(distance_));
    ctx.write(speed_, 0.0);
  }

 private:
  friend void @NAME@_plugin::register_stop(arbiter::Registry& registry);
  double threshold_ = 0.0;
  arbiter::Input<double> distance_;
  arbiter::Output<double> speed_;
};

}  // namespace

void register_stop(arbiter::Registry& registry) {
  auto& info = registry.add_behaviour<Stop>("@NAME@.Stop")
                   .describe("Stops while an obstacle is closer than threshold.");
  info.param("threshold", &Stop::threshold_)
      .defaults_to(0.5)
      .range(0.0, 100.0)
      .describe("stop when the obstacle is closer than this (m)");
  info.port("distance", &Stop::distance_).describe("how far the nearest obstacle ahead is (m)");
  info.port("speed", &Stop::speed_).describe("the commanded forward speed (m/s)");
}

}  // namespace @NAME@_plugin

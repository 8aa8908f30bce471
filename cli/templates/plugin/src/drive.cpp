#include <arbiter/init_context.hpp>
#include <arbiter/state.hpp>
#include <cstdint>

#include "classes.hpp"

namespace @NAME@_plugin {
namespace {

/// A state: commands `speed` for `steps` executions, then proceeds to the next planned state.
/// Its params may differ per planned instance, so they bind to StateParam handles, read in the
/// step with ctx.param(). Objects are pooled and reused: activate() sets up each instance.
class Drive final : public arbiter::State {
 public:
  void activate(arbiter::StateContext& ctx) override { left_ = ctx.param(steps_param_); }

  arbiter::StateResult execute(arbiter::StateContext& ctx) override {
    ctx.write(speed_, ctx.param(speed_param_));
    return --left_ > 0 ? arbiter::StateResult::kHold : arbiter::StateResult::kProceed;
  }

 private:
  friend void @NAME@_plugin::register_drive(arbiter::Registry& registry);
  arbiter::StateParam<double> speed_param_;
  arbiter::StateParam<std::int64_t> steps_param_;
  arbiter::Output<double> speed_;
  std::int64_t left_ = 0;
};

}  // namespace

void register_drive(arbiter::Registry& registry) {
  auto& info = arbiter::add_state_class<Drive>(registry, "@NAME@.Drive")
                   .describe("Drives at a speed for a number of steps.");
  info.param("speed", &Drive::speed_param_).range(-2.0, 2.0).describe("the forward speed (m/s)");
  info.param("steps", &Drive::steps_param_)
      .defaults_to(10)
      .range(1, 100000)
      .describe("how many steps it drives before it proceeds");
  info.port("speed", &Drive::speed_).describe("the commanded forward speed (m/s)");
}

}  // namespace @NAME@_plugin

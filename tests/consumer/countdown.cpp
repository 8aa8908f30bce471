#include <arbiter/init_context.hpp>
#include <arbiter/state.hpp>
#include <cstdint>
#include <string>

#include "patrol.hpp"

namespace patrol {
namespace {

/// Holds for `steps` executions, then proceeds. With `rounds` above 1 it first plans itself
/// again, at the head of the queue, with one round fewer.
class Countdown final : public arbiter::State {
 public:
  // The planned state's params are named here, resolved once: a typo fails the load at the
  // state's location.
  void init(arbiter::StateInitContext& ctx) override {
    again_ = ctx.plan_state<std::int64_t, std::int64_t>(ctx.name(), {"steps", "rounds"});
  }

  void activate(arbiter::StateContext& ctx) override { left_ = ctx.param(steps_); }

  arbiter::StateResult execute(arbiter::StateContext& ctx) override {
    if (--left_ > 0) return arbiter::StateResult::kHold;
    const std::int64_t rounds = ctx.param(rounds_);
    if (rounds > 1) ctx.plan().prepend(again_, ctx.param(steps_), rounds - 1);
    return arbiter::StateResult::kProceed;
  }

 private:
  friend void patrol::register_countdown(arbiter::Registry& registry);
  arbiter::StateParam<std::int64_t> steps_;
  arbiter::StateParam<std::int64_t> rounds_;
  // This state again, with two run-time params.
  arbiter::PlannedStateRef<std::int64_t, std::int64_t> again_;
  std::int64_t left_ = 0;
};

}  // namespace

void register_countdown(arbiter::Registry& registry) {
  auto& info = arbiter::add_state_class<Countdown>(registry, "patrol.Countdown")
                   .describe("Waits a number of steps, a number of times in a row.");
  info.param("steps", &Countdown::steps_)
      .defaults_to(3)
      .range(1, 1000)
      .describe("executions before it proceeds");
  info.param("rounds", &Countdown::rounds_)
      .defaults_to(1)
      .range(1, 100)
      .describe("how many times it runs in a row");
}

}  // namespace patrol

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
  void init(arbiter::InitContext& ctx) override { name_ = ctx.name(); }

  void activate(arbiter::StateContext& ctx) override { left_ = ctx.param<std::int64_t>("steps"); }

  arbiter::StateResult execute(arbiter::StateContext& ctx) override {
    if (--left_ > 0) return arbiter::StateResult::kHold;
    const auto rounds = ctx.param<std::int64_t>("rounds");
    if (rounds > 1) {
      ctx.plan().prepend(name_,
                         {{"steps", ctx.param<std::int64_t>("steps")}, {"rounds", rounds - 1}});
    }
    return arbiter::StateResult::kProceed;
  }

 private:
  std::string name_;  // the state's name in its state machine, for planning itself
  std::int64_t left_ = 0;
};

}  // namespace

void register_countdown(arbiter::Registry& registry) {
  auto& info = arbiter::add_state_class<Countdown>(registry, "patrol.Countdown")
                   .describe("Waits a number of steps, a number of times in a row.");
  info.param<std::int64_t>("steps").defaults_to(3).range(1, 1000).describe(
      "executions before it proceeds");
  info.param<std::int64_t>("rounds").defaults_to(1).range(1, 100).describe(
      "how many times it runs in a row");
}

}  // namespace patrol

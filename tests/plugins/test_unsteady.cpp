// A behaviour that breaks the replay rule on purpose: test_unsteady.Dice requests a level drawn
// from the operating system's entropy, so that no two runs agree. Replay must catch and name it.
// test_unsteady.Counter, an interface class, writes the step number to every actuator its layer
// declares (each a double or an int) and reports "LAYER ticked" every other step: inputs for replay to record and feed
// back, each layer its own.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "arbiter/init_context.hpp"
#include "arbiter/plugin.hpp"

namespace {

class Dice final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext&) override {
    return std::uniform_real_distribution<double>(0.1, 1.0)(device_);
  }

 private:
  std::random_device device_;
};

class Counter final : public arbiter::Interface {
 public:
  void init(arbiter::InitContext& ctx) override {
    tick_ = ctx.name() + " ticked";
    for (const auto& actuator : ctx.layer_actuators()) {
      outputs_.push_back(ctx.output_to_actuator(actuator.name, actuator.location));
    }
  }
  void input(arbiter::WriteContext& ctx) override {
    for (const auto& output : outputs_) {
      arbiter::ValueBox value(*output.type);
      if (output.type->name == "int") {
        *static_cast<std::int64_t*>(value.data()) = static_cast<std::int64_t>(ctx.step());
      } else {
        *static_cast<double*>(value.data()) = static_cast<double>(ctx.step());
      }
      ctx.write(output, value);
    }
  }
  void output(const arbiter::StepContext& ctx) override {
    if (ctx.step() % 2 == 0) ctx.report(tick_.c_str());
  }

 private:
  std::vector<arbiter::AnyOutput> outputs_;
  std::string tick_;
};

}  // namespace

ARBITER_PLUGIN(registry) {
  registry.add_behaviour<Dice>("test_unsteady.Dice");
  registry.add_interface<Counter>("test_unsteady.Counter");
}

// A behaviour that breaks the replay rule on purpose: test_unsteady.Dice requests a level drawn
// from the operating system's entropy, so that no two runs agree. Replay must catch and name it.

#include <random>

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

}  // namespace

ARBITER_PLUGIN(registry) {
  registry.add_behaviour<Dice>("test_unsteady.Dice");
}

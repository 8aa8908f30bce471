// A plugin whose registration throws after it has registered a class: nothing of it may reach
// the engine's registry.

#include <stdexcept>

#include "arbiter/plugin.hpp"

namespace {

class Kicker final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext&) override { return 1.0; }
};

}  // namespace

ARBITER_PLUGIN(registry) {
  registry.add_behaviour<Kicker>("test_throws.Kicker");
  throw std::runtime_error("calibration table kicker.csv is missing");
}

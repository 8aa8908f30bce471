// Registers a behaviour class named like the built-in `scripted`.

#include "arbiter/plugin.hpp"

namespace {

class Impostor final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext&) override { return 1.0; }
};

}  // namespace

ARBITER_PLUGIN(registry) {
  registry.add_behaviour<Impostor>("scripted");
}

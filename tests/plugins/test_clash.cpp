// Registers clash.Same. Built twice, as test_clash_a and test_clash_b: two plugins that clash.

#include "arbiter/plugin.hpp"

namespace {

class Same final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext&) override { return 1.0; }
};

}  // namespace

ARBITER_PLUGIN(registry) {
  registry.add_behaviour<Same>("clash.Same");
}

// A plugin the dynamic loader can really unload: its entry points are written by hand, because
// ARBITER_PLUGIN's thread_local failure message keeps a library loaded until its thread exits,
// and it uses nothing (such as std::variant's in_place_index) that the compiler emits as a
// STB_GNU_UNIQUE symbol, which would keep it loaded for good. Lets the tests see that a library
// stays loaded exactly as long as something it made lives.

#include "arbiter/plugin.hpp"

namespace {

class Still final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext&) override { return 0.75; }
};

}  // namespace

ARBITER_PLUGIN_EXPORT int arbiter_plugin_api_version() {
  return ARBITER_PLUGIN_API_VERSION;
}

ARBITER_PLUGIN_EXPORT const char* arbiter_plugin_register(arbiter::Registry* registry) {
  registry->add_behaviour<Still>("test_unloadable.Still");
  return nullptr;
}

// The DDS bridge as a shared-library plugin: `plugins: [dds]` in a config loads it.

#include "arbiter/plugin.hpp"
#include "dds.hpp"

ARBITER_PLUGIN(registry) {
  arbiter::dds::register_classes(registry);
}

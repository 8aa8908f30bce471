// The soccer demo as a shared-library plugin: `plugins: [soccer]` in a config loads it.

#include "arbiter/plugin.hpp"
#include "soccer.hpp"

ARBITER_PLUGIN(registry) {
  arbiter::soccer::register_classes(registry);
}

// The plugin's entry points: the plugin API version it was built for, and the function that
// registers its classes (a class added to the project is registered here too).

#include <arbiter/plugin.hpp>

#include "classes.hpp"

ARBITER_PLUGIN(registry) {
  @NAME@_plugin::register_stop(registry);
  @NAME@_plugin::register_drive(registry);
}

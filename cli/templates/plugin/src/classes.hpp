#pragma once
// The plugin's classes: each source file defines one and registers it with its function here;
// plugin.cpp calls them all.

#include <arbiter/registry.hpp>

// The plugin's name alone could be a name the C library declares or defines as a macro (time,
// random, linux): the namespace adds "_plugin" to it.
namespace @NAME@_plugin {

void register_stop(arbiter::Registry& registry);
void register_drive(arbiter::Registry& registry);

}  // namespace @NAME@_plugin

#pragma once
// The plugin's classes: each source file defines one and registers it with its function here;
// plugin.cpp calls them all.

#include <arbiter/registry.hpp>

namespace @NAME@ {

void register_stop(arbiter::Registry& registry);
void register_drive(arbiter::Registry& registry);

}  // namespace @NAME@

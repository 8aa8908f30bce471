#pragma once
// A patrol robot's classes, as a plugin outside the Arbiter source tree: each file registers its
// classes; plugin.cpp wraps them in the plugin's entry points.

#include <arbiter/registry.hpp>

namespace patrol {

void register_beacon(arbiter::Registry& registry);
void register_odometry(arbiter::Registry& registry);
void register_go_to(arbiter::Registry& registry);
void register_countdown(arbiter::Registry& registry);

}  // namespace patrol

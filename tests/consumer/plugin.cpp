#include <arbiter/plugin.hpp>

#include "patrol.hpp"

ARBITER_PLUGIN(registry) {
  patrol::register_beacon(registry);
  patrol::register_odometry(registry);
  patrol::register_go_to(registry);
  patrol::register_countdown(registry);
}

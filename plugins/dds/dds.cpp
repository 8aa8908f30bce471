#include "dds.hpp"

#include "bridge.hpp"
#include "hold.hpp"

namespace arbiter::dds {

void register_classes(Registry& registry) {
  register_bridge(registry);
  register_holds(registry);
}

}  // namespace arbiter::dds

#include "beacon.hpp"

#include "patrol.hpp"

namespace patrol {

void register_beacon(arbiter::Registry& registry) {
  registry.add_value_type<Beacon>("patrol.Beacon");
}

}  // namespace patrol

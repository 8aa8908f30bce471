#include "soccer.hpp"

#include "behaviours.hpp"
#include "goalie.hpp"
#include "world_link.hpp"

namespace arbiter::soccer {

void register_classes(Registry& registry) {
  register_world_link(registry);
  register_behaviours(registry);
  register_goalie(registry);
}

}  // namespace arbiter::soccer

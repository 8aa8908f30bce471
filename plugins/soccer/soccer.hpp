#pragma once
// The soccer demo's classes: a simulated world (soccer.WorldLink), the behaviours of the paper's
// ball approach and kick example, and its goalie's states and behaviour.

#include "arbiter/registry.hpp"

namespace arbiter::soccer {

/// Adds every class of the soccer plugin to `registry`. The one place that lists them, so that
/// the plugin's entry point and a statically linked host register the same set.
void register_classes(Registry& registry);

}  // namespace arbiter::soccer

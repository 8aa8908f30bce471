#pragma once
// The behaviours of the paper's ball approach and kick example.

#include "arbiter/registry.hpp"

namespace arbiter::soccer {

/// Registers soccer.SearchForBall, soccer.GoBehindBall, soccer.KickBall and soccer.HeadControl.
void register_behaviours(Registry& registry);

}  // namespace arbiter::soccer

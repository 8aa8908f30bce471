#pragma once
// The goalie of Allgeuer & Behnke (2013) as real classes: the states of its plan
// (soccer.WaitForButton, soccer.WalkToPose, soccer.MonitorBall, soccer.Dive) and the behaviour
// that owns and steps its state machine, pre-empting the plan on a button press or a shot on goal
// (soccer.Goalie).

#include "arbiter/registry.hpp"

namespace arbiter::soccer {

/// Registers the goalie's four state classes and the soccer.Goalie behaviour.
void register_goalie(Registry& registry);

}  // namespace arbiter::soccer

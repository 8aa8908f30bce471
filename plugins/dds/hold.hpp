#pragma once
// dds.Hold<Type>: a lower layer's behaviour that turns values received at a low rate into a value
// written every step, until a timeout. A process stepping at 100 Hz that receives a command from a
// 10 Hz process sees it written in one step out of ten; a Hold behaviour writes it on in the steps
// between, and stops (so its actuator goes unwritten) when no new value came for `timeout`
// seconds: the command's sender stopped sending it, or is gone.

#include "arbiter/registry.hpp"

namespace arbiter::dds {

/// Registers dds.HoldBool, dds.HoldInt, dds.HoldDouble, dds.HoldVec2, dds.HoldVec3 and
/// dds.HoldString.
void register_holds(Registry& registry);

}  // namespace arbiter::dds

#pragma once
// The dds plugin's classes: dds.Bridge and the dds.Hold behaviours (docs/dds.md).

#include "arbiter/registry.hpp"

namespace arbiter::dds {

void register_classes(Registry& registry);

}  // namespace arbiter::dds

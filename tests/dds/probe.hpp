#pragma once
// Test classes for the DDS bridge: probe.Stamp writes values of every type the bridge carries,
// derived from the step, so that a receiver can tell which step a value came from.

#include "arbiter/registry.hpp"

namespace arbiter::dds_test {

/// Registers probe.Stamp.
void register_probe(Registry& registry);

/// The seconds of the monotonic clock that every process on the machine shares.
double monotonic_seconds();

}  // namespace arbiter::dds_test

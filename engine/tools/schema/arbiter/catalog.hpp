#pragma once
// The registry's classes described for people and tools (`arbiter plugins`): each class with its
// kind, origin, description, params (type, default, range, description) and ports (direction,
// type, description), then the value types. The declarations that validate configs are the ones
// described, so the listing cannot drift from what is checked.

#include <string>

#include "arbiter/registry.hpp"

namespace arbiter {

/// For people: classes grouped by kind (behaviour, interface, state), each group by name.
std::string catalog_text(const Registry& registry);

/// For tools: `{"classes": [...], "value_types": [...]}`, described in docs/cli.md.
std::string catalog_json(const Registry& registry);

}  // namespace arbiter

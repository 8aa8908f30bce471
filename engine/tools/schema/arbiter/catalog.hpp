#pragma once
// The registry's classes described for people and tools (`arbiter plugins`): each class with its
// kind, origin, description, params (type, default, range, description) and ports (direction,
// type, description), then the value types. The declarations that validate configs are the ones
// described, so the listing cannot drift from what is checked.

#include <string>
#include <vector>

#include "arbiter/plugin.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

/// For people: classes grouped by kind (behaviour, interface, state), each group by name.
std::string catalog_text(const Registry& registry);

/// For tools: `{"classes": [...], "value_types": [...]}`, described in docs/cli.md.
std::string catalog_json(const Registry& registry);

/// The names of the plugins on the search path (`arbiter_NAME.so`), each once: the first
/// directory that has it wins, as when a config names it.
std::vector<std::string> plugins_on_path(const PluginOptions& options);

}  // namespace arbiter

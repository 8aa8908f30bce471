#pragma once
// The classes every Arbiter config can use without a plugin (docs/config.md, "Built-in classes").

#include "arbiter/registry.hpp"

namespace arbiter {

/// Registers the built-in classes (`scripted` behaviour, ...) into `registry`.
void register_builtin_behaviours(Registry& registry);

/// The built-in interface class (`interface: inputs`), whose layers scenario `inputs:` and
/// `arbiter run --inputs FILE` feed without a substitution.
inline constexpr const char* kInputsInterface = "inputs";

void register_inputs_interface(Registry& registry);
void register_scripted_behaviour(Registry& registry);
void register_scripted_state(Registry& registry);
void register_state_machine_behaviour(Registry& registry);

}  // namespace arbiter

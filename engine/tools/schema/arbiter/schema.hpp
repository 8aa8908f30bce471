#pragma once
// engine/tools/schema: the Registry in; the config's JSON Schema (schema.hpp) and the class catalog
// (catalog.hpp) out, for editors, CI and `arbiter plugins`.
//
// The JSON Schema (draft-07) of the config format, for editors and CI. The schema checks a
// config's structure; semantic checks it cannot express (names resolve, types match, no cycles)
// are the pipeline's (build_model, compile).

#include <string>

#include "arbiter/registry.hpp"

namespace arbiter {

/// schema/arbiter.schema.json, as compiled into the engine: any class name is accepted and params
/// are not checked, so it serves every config whatever plugins it uses.
std::string config_schema();

/// The same schema extended with the registry's classes and value types: `type:`, `interface:` and
/// actuator types name one of them (so editors complete them), each class's `params:` and `ports:`
/// are checked against its declaration, and `aggregate: true` needs a type that can be averaged.
/// Per-instance params of queued states are not checked (their class depends on the state).
/// Deterministic: classes by name, params and ports in declaration order.
std::string config_schema(const Registry& registry);

}  // namespace arbiter

#pragma once
// Substitution: a config's model with some of its classes replaced, so that a behaviour graph can
// be run without the robot, the simulator or the code it normally runs with (`arbiter test`). It
// acts between build_model and compile: the program compiled from the edited model runs the
// replacements in place of the originals, with every name, inhibition and actuator of the config
// unchanged.

#include <optional>
#include <string>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/model.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

/// One replacement.
struct Substitution {
  /// What is replaced, as written: a behaviour (`layer/name`, or `name` when no other layer has
  /// one), a state (`machine/state`, or `state` when no other machine has one), an interface
  /// layer (its name), or a class (its registered name: every behaviour, state or interface layer
  /// of the config that has that class). A name that fits several of these is ambiguous.
  std::string target;
  SourceLocation location;  ///< where the target is written
  /// The replacement, as a config declares an instance: a class name, or `{type: CLASS,
  /// params: {...}, ports: {...}}` (no ports for a state). Unused when `cls` is set.
  Node declaration;
  /// Instead of a declaration, a class made by the caller, such as an interface that writes its
  /// layer's actuators from a per-step source of values (a scenario's `inputs:`, a recording).
  /// It must be of the target's kind, declare no params and no ports, and outlive the program.
  const ClassInfo* cls = nullptr;
};

/// Replaces, in `model` (built without error), the class of each target of `substitutions`.
/// Reports at its location a target that names nothing of the config (with the names it could
/// have meant) or several things (with the qualified names to choose from), and a replacement of
/// the wrong kind or whose params and ports do not fit. Queue entries of a replaced state lose
/// their per-instance params (they were the replaced class's). Returns false when anything was
/// an error; the model must then not be compiled.
bool substitute(Model& model, const std::vector<Substitution>& substitutions,
                const Registry& registry, Diagnostics& diagnostics);

}  // namespace arbiter

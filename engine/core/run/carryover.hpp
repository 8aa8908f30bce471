#pragma once
// The carry-over of a hot reload: what the Reloader matched and Manager::stage() applies.
// Internal to the engine (embedders reload through Reloader).

#include <cstdint>
#include <vector>

#include "arbiter/behaviour.hpp"

namespace arbiter::detail {

/// No part of the running program matches: the new part starts afresh.
inline constexpr std::uint32_t kNoMatch = kNoIndex;

/// How the parts of a program staged for hot reload map onto the running program's, by index
/// (Reloader builds it; docs/hot_reload.md). kNoMatch: nothing carries over, the part starts
/// afresh.
struct Carryover {
  /// Per behaviour of the new program: the running behaviour of the same layer, name and class.
  std::vector<std::uint32_t> behaviour_from;
  /// Per behaviour: non-zero when it keeps the running instance as it is (declaration and port
  /// handles unchanged); else a matched behaviour's new instance is offered carry_over().
  std::vector<char> behaviour_kept;
  /// Per actuator: the running actuator of the same name and type, whose value it keeps.
  std::vector<std::uint32_t> actuator_from;
  /// Per layer: the running layer of the same name and interface class, and whether it keeps
  /// that interface object (else its new one is offered carry_over()), as for behaviours.
  std::vector<std::uint32_t> interface_from;
  std::vector<char> interface_kept;
  /// Per controller: the running controller it keeps, with its current state and queue.
  std::vector<std::uint32_t> controller_kept;
};

}  // namespace arbiter::detail

#pragma once
// engine/tools/dump: a Program in; the compiled graph out as text, DOT or JSON (`arbiter dump`).
//
// The compiled graph describing itself, for people (text) and tools.

#include <string>
#include <string_view>

#include "arbiter/program.hpp"

namespace arbiter {

/// Layers in execution order, each with its behaviours in topological order, its declared and
/// implicit inhibitions and its actuator → sensor wiring. `layer` (optional) limits the output
/// to one layer.
std::string dump_text(const Program& program, std::string_view layer = {});

/// The same graph in Graphviz DOT (`dot -Tsvg`): each layer a cluster of its behaviours (numbered
/// in execution order), actuators and sensors; chaining inhibitions drawn as double lines,
/// non-chaining ones single, implicit ones (from the chaining closure) dashed; writes from
/// behaviours to actuators, and data flow from actuators to the sensors that read them (dashed
/// where a sensor sees last step's value); each state machine a cluster of its states with its
/// initial queue, and an edge to the child machine a state steps. With `layer`, that layer alone
/// (and the actuators its sensors read). Byte-identical for the same program.
std::string dump_dot(const Program& program, std::string_view layer = {});

/// What steps an owned state machine of `program`: its behaviour (`layer/name`) or the state of a
/// parent machine (`machine/state`); empty when it is standalone.
std::string owner_of(const Program& program, const Controller& controller);

/// The same graph as JSON (`{"arbiter_dump": 1, ...}`, described in docs/cli.md), for tools;
/// `indent` as nlohmann::json::dump's (-1: on one line, for a page that parses it).
std::string dump_json(const Program& program, std::string_view layer = {}, int indent = 2);

}  // namespace arbiter

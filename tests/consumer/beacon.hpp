#pragma once
// patrol.Beacon: a value type of the plugin's own, carried by actuators like the built-in ones.

#include <fmt/format.h>

#include <arbiter/value.hpp>
#include <cmath>
#include <string>

namespace patrol {

/// The flashing light on top of the robot.
struct Beacon {
  bool on = false;
  double hz = 0.0;
};

}  // namespace patrol

/// How a Beacon is read from a config (`{on: true, hz: 2}`) and written to a trace. Without a
/// `mean`, an actuator of this type cannot be `aggregate: true`.
template <>
struct arbiter::ValueTraits<patrol::Beacon> {
  static bool from_node(const arbiter::Node& node, patrol::Beacon& to, std::string& expected) {
    expected = "a mapping {on: BOOL, hz: NUMBER}";
    const arbiter::Node* on = node.is_mapping() ? node.find("on") : nullptr;
    const arbiter::Node* hz = node.is_mapping() ? node.find("hz") : nullptr;
    if (on == nullptr || hz == nullptr || node.size() != 2) return false;
    const auto on_value = on->as_bool();
    const auto hz_value = hz->as_double();
    if (!on_value || !hz_value || !std::isfinite(*hz_value)) return false;
    to = {*on_value, *hz_value};
    return true;
  }
  static void append_json(const patrol::Beacon& value, std::string& out) {
    out += fmt::format("{{\"on\": {}, \"hz\": {}}}", value.on, value.hz);
  }
};

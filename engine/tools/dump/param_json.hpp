#pragma once
// Param values as JSON, for the tools that describe classes and configs (schema, catalog, dump).
// Internal.

#include <cmath>
#include <nlohmann/json.hpp>

#include "arbiter/registry.hpp"

namespace arbiter::detail {

/// The JSON of a param value; null for a value JSON cannot show (a document node, NaN).
inline nlohmann::ordered_json param_json(const ParamValue& value) {
  using Json = nlohmann::ordered_json;
  struct Visitor {
    Json operator()(bool v) const { return v; }
    Json operator()(std::int64_t v) const { return v; }
    Json operator()(double v) const { return std::isfinite(v) ? Json(v) : Json(); }
    Json operator()(const std::string& v) const { return v; }
    Json operator()(const Vec2& v) const { return Json::array({v.x, v.y}); }
    Json operator()(const Vec3& v) const { return Json::array({v.x, v.y, v.z}); }
    Json operator()(const std::vector<double>& v) const { return v; }
    Json operator()(const std::vector<std::string>& v) const { return v; }
    Json operator()(const Node&) const { return Json(); }
  };
  return std::visit(Visitor{}, value);
}

}  // namespace arbiter::detail

#include "arbiter/value.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace arbiter::detail {

void append_json_number(double value, std::string& out) {
  // JSON has no inf/nan; the engine never stores them, but a plugin value might.
  if (!std::isfinite(value)) {
    out += "null";
    return;
  }
  fmt::memory_buffer digits;
  fmt::format_to(std::back_inserter(digits), "{}", value);
  out.append(digits.data(), digits.size());
  // Keep doubles recognisable as such in JSON ("1.0", not "1").
  if (std::find_if(digits.begin(), digits.end(), [](char c) { return c == '.' || c == 'e'; }) ==
      digits.end()) {
    out += ".0";
  }
}

void append_json_string(const std::string& value, std::string& out) {
  out += '"';
  for (const char c : value) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          fmt::format_to(std::back_inserter(out), "\\u{:04x}", static_cast<int>(c));
        } else {
          out += c;
        }
    }
  }
  out += '"';
}

bool read_finite(const Node& node, double& to) {
  const auto value = node.as_double();
  if (!value || !std::isfinite(*value)) return false;
  to = *value;
  return true;
}

bool read_components(const Node& node, double* to, std::size_t count) {
  if (!node.is_sequence() || node.items().size() != count) return false;
  for (std::size_t i = 0; i < count; ++i) {
    if (!read_finite(node.items()[i], to[i])) return false;
  }
  return true;
}

}  // namespace arbiter::detail

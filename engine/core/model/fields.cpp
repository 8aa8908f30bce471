#include "arbiter/fields.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace arbiter {

namespace {

std::vector<std::string> keys_of(const std::vector<std::string_view>& keys) {
  return {keys.begin(), keys.end()};
}
}  // namespace

Fields::Fields(const Node& node, std::string what, std::vector<std::string_view> allowed,
               Diagnostics& diagnostics, std::string_view shape)
    : node_(node), what_(std::move(what)), diagnostics_(diagnostics) {
  if (!node.is_mapping()) {
    diagnostics.error(node.location(), "wrong-type",
                      fmt::format("{} must be {}, found {}", what_, shape, node.describe()));
    ok_ = false;
    return;
  }
  for (const auto& entry : node.entries()) {
    bool known = false;
    for (auto key : allowed) known = known || key == entry.key;
    if (!known) {
      diagnostics
          .error(entry.key_location, "unknown-key",
                 fmt::format("unknown key '{}' in {}", entry.key, what_))
          .unknown_name(entry.key, keys_of(allowed));
      // A misspelt required key is reported once, as misspelt, not also as missing.
      if (auto meant = closest(entry.key, keys_of(allowed))) {
        misspelt_.push_back(*meant);
      } else {
        unknown_.emplace_back(entry.key, diagnostics.items().size() - 1);
      }
    }
  }
}

const Node* Fields::required(std::string_view key) const {
  if (!ok_) return nullptr;
  const Node* value = node_.find(key);
  if (value == nullptr && std::find(misspelt_.begin(), misspelt_.end(), key) == misspelt_.end()) {
    diagnostics_.error(node_.location(), "missing-key",
                       fmt::format("{} is missing the required key '{}'", what_, key));
  }
  return value;
}

SourceLocation Fields::key_location(std::string_view key) const {
  for (const auto& entry : node_.entries()) {
    if (entry.key == key) return entry.key_location;
  }
  return node_.location();
}

}  // namespace arbiter

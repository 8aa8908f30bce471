#pragma once
// Fields reads one mapping of a config: it checks that the node is a mapping with only the allowed
// keys, reports missing required keys, and hands out the values. The model reads its sections with
// it; a class reads a structured param (a `Node` param) with it too, so that its mistakes are
// reported as the model's are: `unknown-key` with a suggestion, `missing-key`, `wrong-type`, each
// at its place (InitContext::diagnostics() is the sink).

#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"

namespace arbiter {

/// Checks that a node is a mapping with only the given keys; hands out the values.
class Fields {
 public:
  /// `shape` says what was expected when the node is not a mapping.
  Fields(const Node& node, std::string what, std::vector<std::string_view> allowed,
         Diagnostics& diagnostics, std::string_view shape = "a mapping");

  bool ok() const { return ok_; }

  /// The unknown keys that are no misspelling of an allowed one, with the index of their error.
  const std::vector<std::pair<std::string, std::size_t>>& unknown() const { return unknown_; }

  const Node* optional(std::string_view key) const { return ok_ ? node_.find(key) : nullptr; }

  const Node* required(std::string_view key) const;

  /// Where `key` was written (the mapping's location when it is absent).
  SourceLocation key_location(std::string_view key) const;

 private:
  const Node& node_;
  std::string what_;
  Diagnostics& diagnostics_;
  std::vector<std::string> misspelt_;
  std::vector<std::pair<std::string, std::size_t>> unknown_;
  bool ok_ = true;
};

}  // namespace arbiter

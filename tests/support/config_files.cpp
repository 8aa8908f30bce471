#include "config_files.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace arbiter::test {

Outcome load_file(const fs::path& path, const LoadOptions& options) {
  Registry fresh = make_test_registry();  // loading may add plugins to it
  Outcome outcome;
  outcome.loaded = load(path.string(), fresh, outcome.diagnostics, options).has_value();
  // Every message must be printable as text and as JSON (which needs valid UTF-8).
  if (outcome.diagnostics.error_count() > 0) CHECK_FALSE(format(outcome.diagnostics).empty());
  CHECK_NOTHROW(nlohmann::json::parse(format_json(outcome.diagnostics)));
  return outcome;
}

std::vector<std::string> error_codes(const Diagnostics& diagnostics) {
  std::vector<std::string> codes;
  for (const auto& item : diagnostics.items()) {
    if (item.severity == Severity::kError) codes.push_back(item.code);
  }
  return codes;
}

}  // namespace arbiter::test

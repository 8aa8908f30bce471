#pragma once
// `arbiter test`: runs scenario test files and reports one line per test, each failed
// expectation at its place with the explanation of what it names, and optionally JUnit XML.

#include <ostream>
#include <string>
#include <vector>

#include "arbiter/registry.hpp"
#include "arbiter/scenario_run.hpp"

namespace arbiter::cli {

struct TestCommand {
  std::vector<std::string> paths;  ///< test files and directories
  std::string junit;               ///< where to write JUnit XML; empty: nowhere
  ScenarioOptions options;
  /// How diagnostics and failed expectations are printed (`arbiter validate`'s format).
  FormatOptions format;
};

/// Prints on `out` one line per test, each followed by its diagnostics and failed expectations,
/// then the counts. `err` gets usage errors only. Exit code: 0 all passed, 1 a test failed, 2 a
/// usage error or an invalid test file.
int run_tests(const TestCommand& command, Registry& registry, std::ostream& out, std::ostream& err);

/// JUnit XML for CI systems: one testcase per test file, one failure per failed expectation, an
/// error for a test file that could not run.
std::string junit_xml(const std::vector<ScenarioResult>& results);

}  // namespace arbiter::cli

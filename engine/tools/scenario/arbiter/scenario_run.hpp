#pragma once
// Runs a scenario test (scenario.hpp) against its config: the config is loaded with the
// scenario's substitutions (substitute.hpp), its inputs feed the interface layers substituted by
// `inputs`, the manager is stepped `steps:` times, and after each step every expectation that
// covers it is checked. A failed expectation is told at its own place in the test file, followed
// by the explanation (explain.hpp) of its behaviour or state machine at that step.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/model.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/registry.hpp"
#include "arbiter/scenario.hpp"

namespace arbiter {

class ScheduledInputs;

/// `arbiter run --inputs FILE`: the values a file gives by step (read_inputs_file), written by
/// the layers of a config bound to the built-in interface class `inputs`.
class InputFeed {
 public:
  InputFeed();
  ~InputFeed();
  InputFeed(const InputFeed&) = delete;
  InputFeed& operator=(const InputFeed&) = delete;

  /// Reads the file; false after reporting into `diagnostics`.
  bool read(const std::string& path, Diagnostics& diagnostics, const ReadLimits& limits = {});
  /// For LoadOptions::edit_model, once: feeds the built-in `inputs` layers of `model` from the
  /// file and checks its names and values against them. This object must outlive the program.
  bool edit(Model& model, const Registry& registry, Diagnostics& diagnostics);

 private:
  std::unique_ptr<ScheduledInputs> inputs_;
  std::vector<ScenarioInput> entries_;
  SourceLocation where_;
};

struct ScenarioOptions {
  /// How far a level or number may be from one expected as a single number.
  double tolerance = 1e-6;
  ReadLimits limits;
  PluginOptions plugins;
};

/// One failed expectation: at most one per expectation, at the first step where it failed.
struct ScenarioFailure {
  Diagnostic diagnostic;  ///< at the expectation: "expected ..., got ..."
  std::uint64_t step = 0;
  std::string explanation;  ///< explain() at that step of what it names
};

struct ScenarioResult {
  enum class Status {
    kPassed,
    kFailed,
    kInvalid,  ///< the test file or its config has errors: nothing was run
  };
  Status status = Status::kInvalid;
  std::string file;
  std::string name;
  /// The files the test file names (its config, recording, expected trace), resolved: a report
  /// written over one of them would destroy it.
  std::vector<std::string> named_files;
  Diagnostics diagnostics;  ///< why it could not run, and warnings
  std::vector<ScenarioFailure> failures;
  std::size_t expectations = 0;
  std::uint64_t steps = 0;  ///< steps run
  double seconds = 0.0;     ///< wall time (run_scenario_file(): reading the file included)
};

/// Runs a scenario read by read_scenario(). Plugins the config names are loaded into `registry`
/// (which should know the built-in classes).
ScenarioResult run_scenario(const Scenario& scenario, Registry& registry,
                            const ScenarioOptions& options = {});

/// Reads a test file and runs it.
ScenarioResult run_scenario_file(const std::string& path, Registry& registry,
                                 const ScenarioOptions& options = {});

/// What `arbiter test` prints under a test's PASS/FAIL/INVALID line: its diagnostics, then each
/// failed expectation at its place followed by its explanation, indented.
std::string format_failures(const ScenarioResult& result, const FormatOptions& options = {});

}  // namespace arbiter

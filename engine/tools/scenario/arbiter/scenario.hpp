#pragma once
// engine/tools/scenario: a scenario test file and the config it names in; each expectation's
// pass or failure out, at its place, with explain's reason (`arbiter test`).
//
// A scenario test file (`arbiter_test: 1`, YAML or JSON; docs/testing.md) read into a model in
// which every item keeps the place it was written, for `arbiter test`. Reading checks the file's
// own shape; names of the config under test are checked when the scenario is run against it
// (scenario_run.hpp).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"

namespace arbiter {

/// A name as written in the test file.
struct ScenarioName {
  std::string text;
  SourceLocation location;
};

/// `substitute:` entry: what is replaced, and by a class (`declaration`, as a config declares an
/// instance) or by the values of `inputs:` (for an interface layer).
struct ScenarioSubstitution {
  ScenarioName target;
  bool inputs = false;
  Node declaration;
};

/// `inputs:` entry: from `step` on, the interface-layer actuators it names hold these values
/// (until a later entry changes them).
struct ScenarioInput {
  std::uint64_t step = 0;
  SourceLocation location;
  struct Value {
    ScenarioName actuator;
    Node value;
  };
  std::vector<Value> values;
};

/// One thing that must hold at every step of [first_step, last_step]. An `expect:` entry gives
/// one expectation per name it lists, each at the place that name is written.
struct Expectation {
  enum class Kind {
    kActive,       ///< target is a behaviour
    kInactive,     ///< target is a behaviour
    kActivation,   ///< target is a behaviour: its activation in [low, high]
    kRequested,    ///< target is a behaviour: its requested level in [low, high]
    kInhibitedBy,  ///< target is a behaviour: its inhibited_by list equals `names`
    kActuator,     ///< target is an actuator: its value equals `value`
    kState,        ///< target is a state machine: its current state is `state`
    kQueue,        ///< target is a state machine: its queue equals `names`
  };
  Kind kind = Kind::kActive;
  std::uint64_t first_step = 0;
  std::uint64_t last_step = 0;
  ScenarioName target;  ///< its location is the expectation's own
  double low = 0.0;
  double high = 0.0;
  bool within_tolerance = false;  ///< one number was given: [low, high] widens by the tolerance
  std::vector<std::string> names;
  std::string state;
  Node value;
};

/// A run compared whole with another, step record by step record, all but the timing:
/// `expect: identical` (with the recording of `replay:`) or `expect_trace: FILE`.
struct TraceExpectation {
  enum class Kind { kIdentical, kTrace };
  Kind kind = Kind::kIdentical;
  ScenarioName file;  ///< as written: the value of `expect_trace:`, or `identical`
  std::string path;   ///< kTrace: resolved against the test file's directory
};

struct Scenario {
  std::string file;         ///< the test file, as named
  std::string name;         ///< the file's name without `.test.yaml` / `.test.json`
  ScenarioName config;      ///< as written
  std::string config_path;  ///< resolved against the test file's directory
  std::vector<ScenarioSubstitution> substitutions;
  SourceLocation inputs_location;     ///< where `inputs:` is written, if it is
  std::vector<ScenarioInput> inputs;  ///< by step
  /// `replay:`: the recording whose inputs feed the interface layers (text empty when none).
  ScenarioName replay;
  std::string replay_path;  ///< resolved against the test file's directory
  std::vector<Expectation> expectations;
  std::vector<TraceExpectation> trace_expectations;
  /// 0 when `steps:` is not given: with `replay:`, the recording's steps.
  std::uint64_t steps = 0;
  SourceLocation steps_location;  ///< where `steps:`'s value is, if it is given
  /// False when reading the file reported an error: what could be read is still checked against
  /// the config, so that one run reports every mistake, but it is not run.
  bool complete = true;
};

/// Whether `path` names a scenario test file (`*.test.yaml`, `*.test.yml`, `*.test.json`).
bool is_scenario_file(std::string_view path);

/// Checks a parsed test file and reads it. Reports every problem at its place; returns nullopt
/// when the file is not a mapping, and a scenario that is not `complete` when anything else was
/// an error.
std::optional<Scenario> build_scenario(const Node& root, Diagnostics& diagnostics);

/// Reads a file of inputs (`arbiter run --inputs FILE`): a list of `{step: N, ACTUATOR: VALUE,
/// ...}` entries, as a test's `inputs:` has them.
std::optional<std::vector<ScenarioInput>> read_inputs_file(const std::string& path,
                                                           Diagnostics& diagnostics,
                                                           const ReadLimits& limits = {});

/// Reads and checks a test file (as build_scenario(); nullopt too when it does not parse).
std::optional<Scenario> read_scenario(const std::string& path, Diagnostics& diagnostics,
                                      const ReadLimits& limits = {});

}  // namespace arbiter

#pragma once
// The expectations of a scenario resolved against the program under test and checked after each
// step of a manager that runs it. Each expectation fails at most once: at the first step of its
// range where it does not hold.

#include <cstdint>
#include <string>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/controller.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/scenario.hpp"
#include "arbiter/trace_diff.hpp"
#include "arbiter/trace_reader.hpp"

namespace arbiter {

class ExpectationChecks {
 public:
  /// A failed expectation: "expected ..., got ..." at its place, and what explains it.
  struct Failure {
    std::size_t expectation = 0;
    std::uint64_t step = 0;
    std::string message;
    /// explain() targets for that step: the behaviour (`layer/name`), the state machine
    /// (`state_machines/name`) or, for an actuator, its writers that were active.
    std::vector<std::string> explain;
  };

  /// Resolves the scenario's names against `program` (`name`, or `layer/name` when several
  /// layers have one) and reads expected actuator values as their types. Reports at the places;
  /// false when anything was wrong.
  bool resolve(const Scenario& scenario, const Program& program, Diagnostics& diagnostics);

  /// Checks every expectation that covers the manager's last step and has not failed yet.
  void check(const Manager& manager, double tolerance);

  const std::vector<Failure>& failures() const { return failures_; }
  std::size_t size() const { return resolved_.size(); }

 private:
  struct Resolved {
    const Expectation* expectation = nullptr;
    std::uint32_t index = 0;    // behaviour, actuator or controller
    std::string expected_json;  // an actuator's expected value as the trace writes it
    bool failed = false;
    // kState: the expected state, and its last run so far, to tell how it ended when it is
    // expected later (steps 0: none).
    std::uint32_t state = 0;
    std::uint64_t started = 0;
    std::uint64_t ended = 0;
    std::uint64_t ended_cycle = 0;
    Controller::Event ending;
  };
  void follow_state(Resolved& resolved, const Manager& manager);
  std::string state_history(const Resolved& resolved, const Manager& manager) const;
  std::string check_one(const Resolved& resolved, const Manager& manager, double tolerance);

  std::vector<Resolved> resolved_;
  std::vector<Failure> failures_;
  std::vector<std::uint32_t> inhibitors_;  // scratch, kept between steps
  std::string json_;                       // scratch
};

/// The trace expectations of a scenario (`expect: identical`, `expect_trace:`): after each step,
/// the run's step record (append_step_record) is compared with the one of the same step in the
/// trace it must repeat, all but the timing, as `arbiter diff` compares (TraceDiffer).
class TraceChecks {
 public:
  /// A run that differs: "expected ..., got ..." at the expectation, and `arbiter diff`'s summary.
  struct Failure {
    std::size_t expectation = 0;  ///< in Scenario::trace_expectations
    std::uint64_t step = 0;       ///< the first divergence
    std::string message;
    std::string summary;
  };

  /// Reads the traces compared with: `recorded` (the replayed recording's steps, for `identical`)
  /// or the `expect_trace:` file, each cut to the `steps` the test runs. Reports at the
  /// expectation a trace that cannot be read or was cut off; false when anything was wrong.
  bool resolve(const Scenario& scenario, const Trace* recorded, std::uint64_t steps,
               Diagnostics& diagnostics);

  /// Compares the manager's last step with each trace.
  void check(const Manager& manager);

  /// Ends the comparison after `steps` steps run; a trace that differs is a failure.
  void finish(std::uint64_t steps);

  const std::vector<Failure>& failures() const { return failures_; }
  std::size_t size() const { return compared_.size(); }

 private:
  struct Compared {
    const TraceExpectation* expectation = nullptr;
    std::size_t index = 0;
    std::string name;  // the trace as the test file names it
    Trace trace;
    std::size_t next = 0;           // the first step record of `trace` not compared yet
    std::uint64_t first_extra = 0;  // the first step the run has past the trace's end
    TraceDiffer differ{0.0, true};  // every field bit for bit, as replay checks determinism
  };
  std::vector<Compared> compared_;
  std::vector<Failure> failures_;
  std::string record_;  // scratch
};

}  // namespace arbiter

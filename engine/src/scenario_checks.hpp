#pragma once
// The expectations of a scenario resolved against the program under test and checked after each
// step of a manager that runs it. Each expectation fails at most once: at the first step of its
// range where it does not hold.

#include <cstdint>
#include <string>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/scenario.hpp"

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
  };
  std::string check_one(const Resolved& resolved, const Manager& manager, double tolerance);

  std::vector<Resolved> resolved_;
  std::vector<Failure> failures_;
  std::vector<std::uint32_t> inhibitors_;  // scratch, kept between steps
  std::string json_;                       // scratch
};

}  // namespace arbiter

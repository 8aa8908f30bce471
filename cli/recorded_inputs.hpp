#pragma once
// Replay's stand-in for interface classes: each interface layer writes, step by step, the values
// its actuators had in the recorded run, instead of talking to a world, a robot or DDS.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "arbiter/model.hpp"
#include "arbiter/registry.hpp"

namespace arbiter::cli {

/// The recorded inputs of a run, by actuator name and step.
class RecordedInputs {
 public:
  /// `messages`: each step's `/arbiter/inputs` message (arbiter::RecordedRun::inputs).
  explicit RecordedInputs(const std::vector<std::pair<std::uint64_t, std::string>>& messages);
  RecordedInputs(const RecordedInputs&) = delete;
  RecordedInputs& operator=(const RecordedInputs&) = delete;

  /// Binds every interface layer of `model` to the recorded inputs: the layer's class is not
  /// created, its params are not used. Reports, at the config, each recorded input that no
  /// interface layer declares; a type that does not fit is reported when the program compiles.
  void replace_interfaces(Model& model, Diagnostics& diagnostics) const;

  /// The step numbers recorded.
  std::uint64_t steps() const { return steps_; }

  struct Column {
    std::string name;
    /// Per step (index step - 1): the value as JSON ("" where the step was not recorded).
    std::vector<std::string> values;
    std::vector<char> written;
  };
  const Column* find(const std::string& name) const;
  /// True for every caller but the first (the interface that reports what was reported).
  bool claim_reports() const;
  /// What interface code reported in `step` (empty when nothing).
  const std::vector<std::string>& reported(std::uint64_t step) const;

 private:
  std::vector<Column> columns_;
  std::vector<std::vector<std::string>> reported_;  // per step - 1
  std::uint64_t steps_ = 0;
  ClassInfo class_;
  mutable bool reports_claimed_ = false;
};

}  // namespace arbiter::cli

#pragma once
// The inputs of a recorded run (recording.hpp) as an interface class: each interface layer that
// has it writes, step by step, the values its actuators had in the recorded run, and reports
// again what that layer reported, instead of talking to a world, a robot or DDS. It feeds
// `arbiter replay` and the scenario tests that replay a recording (`replay:`, scenario.hpp).

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/model.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

/// What replay needs of a recording besides its steps (read those with open_trace()).
struct RecordedRun {
  RecordingInfo info;
  /// Each step's `/arbiter/inputs` message, in order.
  std::vector<std::pair<std::uint64_t, std::string>> inputs;
  /// Each hot reload: the last step before it, and the files (path, text) of the config it
  /// loaded (empty in recordings that did not keep them).
  struct Reload {
    std::uint64_t after_step = 0;
    std::vector<std::pair<std::string, std::string>> files;
  };
  std::vector<Reload> reloads;
  std::uint64_t dropped = 0;               ///< steps the recorder dropped (its gap records)
  std::optional<std::uint64_t> first_gap;  ///< the last step before the first dropped one
};

/// Reads the config, inputs and reloads of the recording at `path`; nullopt with `error` set when
/// it is not a readable recording. A recording cut off while written gives what it holds.
std::optional<RecordedRun> read_recorded_run(const std::string& path, Diagnostic& error);

/// The recorded inputs of a run, by actuator name and step.
class RecordedInputs {
 public:
  /// `messages`: each step's `/arbiter/inputs` message (RecordedRun::inputs).
  explicit RecordedInputs(const std::vector<std::pair<std::uint64_t, std::string>>& messages);
  RecordedInputs(const RecordedInputs&) = delete;
  RecordedInputs& operator=(const RecordedInputs&) = delete;

  /// The interface class that writes the recorded inputs: substitute it for interface layers
  /// (substitute.hpp). It must outlive the program compiled with it, and so must this object.
  const ClassInfo& interface_class() const { return class_; }

  /// Binds every interface layer of `model` to interface_class(): the layer's class is not
  /// created, its params are not used. Then check_places().
  void replace_interfaces(Model& model, Diagnostics& diagnostics) const;

  /// Reports, at `where`, each recorded input that no layer of `model` bound to
  /// interface_class() declares; a type that does not fit is reported when the program compiles.
  void check_places(const Model& model, const SourceLocation& where,
                    Diagnostics& diagnostics) const;

  /// The step numbers recorded.
  std::uint64_t steps() const { return steps_; }

  struct Column {
    std::string name;
    /// Per step (index step - 1): the value as JSON ("" where the step was not recorded).
    std::vector<std::string> values;
    std::vector<char> written;
  };
  const Column* find(const std::string& name) const;

  /// What interface code reported in a step, which interface layer reported it ("" in
  /// recordings that did not say: the first interface layer reports those again), and whether
  /// in the input pass (else the output pass, as recordings that did not say are replayed).
  struct Report {
    std::string layer;
    std::string text;
    bool input_pass = false;
  };
  /// What was reported in `step` (empty when nothing).
  const std::vector<Report>& reported(std::uint64_t step) const;
  /// True for the first caller only: the layer that reports what a recording did not attribute.
  bool claim_unattributed() const;

 private:
  std::vector<Column> columns_;
  std::vector<std::vector<Report>> reported_;  // per step - 1
  std::uint64_t steps_ = 0;
  ClassInfo class_;
  mutable bool unattributed_claimed_ = false;
};

}  // namespace arbiter

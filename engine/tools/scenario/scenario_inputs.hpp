#pragma once
// The input source of a scenario: the values its `inputs:` gives interface-layer actuators, from
// a step on and held until changed, written by the class that replaces those layers
// (`substitute: {LAYER: inputs}`).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/model.hpp"
#include "arbiter/registry.hpp"
#include "arbiter/scenario.hpp"

namespace arbiter {

class ScheduledInputs {
 public:
  ScheduledInputs();
  ScheduledInputs(const ScheduledInputs&) = delete;
  ScheduledInputs& operator=(const ScheduledInputs&) = delete;

  /// The interface class that writes the values: substitute it for the fed layers. It must
  /// outlive the program compiled with it, and so must this object.
  const ClassInfo& interface_class() const { return class_; }

  /// Feeds the layers of `model` bound to the built-in interface class `inputs` (which writes
  /// nothing itself): gives them interface_class().
  void feed_builtin_layers(Model& model, const Registry& registry) const;

  /// Reads `inputs` (a scenario's `inputs:`, or a file's, written at `where`) against `model`,
  /// in which the fed layers have interface_class(): each name must be an actuator of a fed
  /// layer and each value fit its type. Reports at the places; false when anything was wrong.
  bool prepare(const std::vector<ScenarioInput>& inputs, const SourceLocation& where,
               const Model& model, Diagnostics& diagnostics);

  /// One actuator's values, by step (written in the input pass of each step from the first).
  struct Track {
    std::string actuator;
    SourceLocation location;  ///< where it is first named
    std::vector<std::uint64_t> steps;
    std::vector<ValueBox> values;
  };
  const std::vector<Track>& tracks() const { return tracks_; }

 private:
  ClassInfo class_;
  std::vector<Track> tracks_;
};

}  // namespace arbiter

#include "tools/scenario/scenario_inputs.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "arbiter/init_context.hpp"

namespace arbiter {
namespace {

// Writes, in each step's input pass, the value each of its layer's tracks holds at that step.
class InputsInterface final : public Interface {
 public:
  explicit InputsInterface(const std::vector<ScheduledInputs::Track>& tracks) : tracks_(tracks) {}

  void init(InitContext& ctx) override {
    for (const auto& item : ctx.layer_actuators()) {
      for (const auto& track : tracks_) {
        if (track.actuator != item.name) continue;
        bound_.push_back({&track, ctx.output_to_actuator(item.name, track.location), 0});
      }
    }
  }

  void input(WriteContext& ctx) override {
    for (auto& bound : bound_) {
      const auto& steps = bound.track->steps;
      while (bound.next < steps.size() && steps[bound.next] <= ctx.step()) ++bound.next;
      if (bound.next > 0) ctx.write(bound.output, bound.track->values[bound.next - 1]);
    }
  }

 private:
  struct Bound {
    const ScheduledInputs::Track* track;
    AnyOutput output;
    std::size_t next;  // the first value not yet due
  };
  const std::vector<ScheduledInputs::Track>& tracks_;
  std::vector<Bound> bound_;
};

}  // namespace

ScheduledInputs::ScheduledInputs() {
  class_.name = "inputs";
  class_.kind = ClassKind::kInterface;
  class_.origin = "the test file's 'inputs:'";
  class_.description = "Writes the values the test file's 'inputs:' gives, from their step on.";
  class_.make_interface = [this] { return std::make_unique<InputsInterface>(tracks_); };
}

void ScheduledInputs::feed_builtin_layers(Model& model, const Registry& registry) const {
  // The built-in class is registered by behaviours/, which the tools do not link: by its name.
  const ClassInfo* builtin = registry.find_class(ClassKind::kInterface, "inputs");
  if (builtin == nullptr) return;
  for (auto& layer : model.layers) {
    if (layer.interface == builtin) layer.interface = &class_;
  }
}

bool ScheduledInputs::prepare(const std::vector<ScenarioInput>& inputs, const SourceLocation& where,
                              const Model& model, Diagnostics& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  std::vector<std::string> fed_layers;
  std::vector<std::string> fed_actuators;
  for (const auto& layer : model.layers) {
    if (layer.interface != &class_) continue;
    fed_layers.push_back(layer.name.text);
    for (const auto& actuator : layer.actuators) fed_actuators.push_back(actuator.name.text);
  }
  if (!inputs.empty() && fed_layers.empty()) {
    auto& error = diagnostics.error(where, "inputs-without-layer",
                                    "'inputs:' gives values, but no interface layer is fed from "
                                    "them");
    for (const auto& layer : model.layers) {
      if (!layer.is_interface()) continue;
      error.notes.push_back(
          fmt::format("feed interface layer '{}' with 'substitute: {{{}: inputs}}'",
                      layer.name.text, layer.name.text));
    }
    error.notes.push_back(
        "or declare a layer of the config with the built-in 'interface: inputs' (docs/config.md)");
    return false;
  }
  for (const auto& input : inputs) {
    for (const auto& value : input.values) {
      const std::string& name = value.actuator.text;
      const ActuatorDecl* actuator = model.find_actuator(name);
      bool fed = false;
      for (const auto& layer : fed_layers)
        fed = fed || (actuator != nullptr && actuator->layer == layer);
      if (!fed) {
        auto& error = diagnostics.error(
            value.actuator.location, "unknown-input",
            actuator == nullptr
                ? fmt::format("'{}' is not an actuator of the config", name)
                : fmt::format("'{}' is an actuator of layer '{}', which is not fed from "
                              "'inputs:'",
                              name, actuator->layer));
        if (actuator == nullptr) {
          error.unknown_name(name, fed_actuators);
        } else {
          error.notes.push_back(
              fmt::format("inputs write the actuators of layer {}", fmt::join(fed_layers, ", ")));
        }
        continue;
      }
      ValueBox box(*actuator->type);
      std::string expected;
      if (!actuator->type->from_node(value.value, box.data(), expected)) {
        diagnostics.error(value.value.location(), "wrong-type",
                          fmt::format("input '{}' has type {}: it needs {}, found {}", name,
                                      actuator->type->name, expected, value.value.describe()));
        continue;
      }
      Track* track = nullptr;
      for (auto& existing : tracks_) {
        if (existing.actuator == name) track = &existing;
      }
      if (track == nullptr) {
        track = &tracks_.emplace_back();
        track->actuator = name;
        track->location = value.actuator.location;
      }
      track->steps.push_back(input.step);
      track->values.push_back(std::move(box));
    }
  }
  return diagnostics.error_count() == errors;
}

}  // namespace arbiter

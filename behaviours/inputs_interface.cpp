#include "builtins.hpp"

namespace arbiter {
namespace {

/// Writes nothing itself: its layer's actuators are what the config declares, fed by a scenario's
/// `inputs:` or by `arbiter run --inputs FILE`, which put their own class in its place. Without
/// them each actuator holds its default, so the config still runs as it is.
class InputsInterface final : public Interface {};

}  // namespace

void register_inputs_interface(Registry& registry) {
  registry.add_interface<InputsInterface>(kInputsInterface)
      .describe(
          "An interface layer whose actuators are fed from values given by step: a test's "
          "'inputs:' or 'arbiter run --inputs FILE'. Without them, each actuator holds its "
          "default.");
}

}  // namespace arbiter

#pragma once
// The actuators and sensors of the layer a bridge is initialised for.
//
// Stopgap: InitContext can bind an actuator of the own layer by name (output_to_actuator) but
// cannot list the layer's actuators and sensors, nor bind a sensor named in the config rather
// than declared as a port. Until it can (see docs/dds.md, "Engine support"), they are read again
// from the config file, following its includes in the engine's order, which gives each sensor's
// actuator index (actuators are numbered layer by layer, as declared; see Program::actuators).
// So the layer must be declared in a config file on disk, in the top-level file. A test compares
// the result with the compiled program.

#include <cstdint>
#include <string>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/init_context.hpp"

namespace arbiter::dds {

/// An actuator the layer declares, or a sensor it reads.
struct LayerItem {
  std::string name;
  std::string type;          ///< the value type's name
  SourceLocation location;   ///< where the layer names it
  std::uint32_t actuator{};  ///< the actuator's index in the program
};

struct LayerItems {
  std::vector<LayerItem> actuators;  ///< in declaration order
  std::vector<LayerItem> sensors;    ///< in the order listed
};

/// The items of the layer `ctx` initialises. Problems go to ctx.error(); returns false then.
bool read_layer_items(InitContext& ctx, LayerItems& out);

/// The same for layer `layer` of the config `file`, reporting into `diagnostics` at `where`.
bool read_layer_items(const std::string& file, const std::string& layer,
                      const SourceLocation& where, LayerItems& out, Diagnostics& diagnostics);

}  // namespace arbiter::dds

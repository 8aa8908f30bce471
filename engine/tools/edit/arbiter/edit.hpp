#pragma once
// engine/tools/edit: changes to a behaviour graph made as edits of its configs' text, each what a
// person would have typed: the lines an operation does not need to change stay byte for byte as
// they were, comments and key order included, in YAML and JSON alike, in the file that declares
// the element. The language server's rename and code actions and the studio's edits use them,
// the last two naming an operation and its arguments as a JSON request (apply_operation).

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "arbiter/document.hpp"
#include "arbiter/load.hpp"
#include "arbiter/model.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

/// Bytes [begin, end) of `file`'s text, replaced with `text`.
struct TextEdit {
  std::string file;
  std::size_t begin = 0;
  std::size_t end = 0;
  std::string text;
};

/// What an operation gives: its edits, or why it was refused (and no edit).
struct EditResult {
  std::vector<TextEdit> edits;
  std::string refused;
  bool ok() const { return refused.empty(); }
};

/// A declared inhibition, by its layer and its endpoints' names.
struct InhibitionRef {
  std::string layer;
  std::string inhibitor;
  std::string inhibited;
};

// What a config declares and uses, by place: the index the operations and an editor's
// navigation (definition, references, hover) read.

enum class SymbolKind { kBehaviour, kActuator, kState, kMachine, kLayer, kClass, kInclude };

/// A name in a config's text: its declaration, or a use of it.
struct Occurrence {
  SymbolKind kind;
  std::string scope;  ///< a behaviour's layer, a state's machine
  std::string name;
  std::string file;
  std::size_t begin = 0;  ///< bytes of the name in the file's text
  std::size_t end = 0;
  bool definition = false;
  std::string detail;  ///< a definition's class or type
};

/// An inhibition item as written.
struct InhibitionSite {
  std::string layer;
  std::string inhibitor;
  std::string inhibited;
  bool chaining = false;
  std::string file;
  std::size_t begin = 0;  ///< the whole item
  std::size_t end = 0;
};

/// A behaviour, or a layer's interface, that binds ports: where a `ports:` entry would go.
struct PortOwner {
  std::string layer;
  std::string behaviour;  ///< empty for the layer's interface
  std::string file;
  const Node* node = nullptr;  ///< the behaviour's value, or the layer's mapping (in the Loaded)
};

/// An item of a state machine's `queue:` as written, by its position there: what the queue
/// operations take (an editor finds it by place, a name can be queued twice).
struct QueueItemSite {
  std::string machine;
  std::string state;
  std::size_t index = 0;
  std::string file;
  std::size_t begin = 0;  ///< the state's name
  std::size_t end = 0;
};

struct ConfigIndex {
  std::vector<Occurrence> occurrences;  ///< in the order of the files and their text
  std::vector<InhibitionSite> inhibitions;
  std::vector<QueueItemSite> queue_items;
  std::vector<PortOwner> port_owners;
};

/// Indexes the files of `loaded` (which must outlive the index); `registry`, the one it was
/// loaded with, tells which state params plan states (plans_states).
ConfigIndex index_config(const Loaded& loaded, const Registry* registry);

/// Whether a state class's param names states to plan (scripted's append: and prepend:): one
/// declared with the queue's entry schema, so that its items are the queue's, in the state's
/// machine.
bool plans_states(const ParamSpec& param);

/// Renames what `symbol` names (its declaration and every use) to `name`; an actuator's rename
/// also adds the `ports:` entries that keep ports bound to it by name bound. Refused when `name`
/// is not an identifier or is taken, or when which ports bind by name is not known.
EditResult rename_symbol(const Loaded& loaded, const ConfigIndex& index, const Occurrence& symbol,
                         const std::string& name);

struct EditedConfig;

/// `result` checked by loading the config with its edits (load_edited, into `registry`): when
/// that reports an error and `loaded` had none, the edits are withdrawn and the result refused
/// with the first error. It catches a use of a name no operation knows how to follow (an
/// actuator named in a scripted behaviour's `writes:`), rather than leave a config that fails.
/// With `edited`, the load of the accepted edits is kept there, for a caller that goes on with
/// the edited config (left empty when `loaded` had errors: then nothing was loaded).
EditResult checked(const Loaded& loaded, EditResult result, Registry& registry,
                   const LoadOptions& options = {}, EditedConfig* edited = nullptr);

/// The end of the token at `begin` of `text`: a quoted string with its quotes, or a name.
std::size_t token_end(const std::string& text, std::size_t begin);

/// Removes the inhibition from the layer's `inhibitions:` (the whole key when it was the only
/// one), wherever `loaded`'s files declare it.
EditResult remove_inhibition(const Loaded& loaded, const InhibitionRef& inhibition);

/// Declares the inhibition, chaining (`=>`) or not (`->`): after the last item of the layer's
/// `inhibitions:` (a line of its own in a block sequence), or the key added with it. Refused
/// when the layer is not declared or the inhibition already is.
EditResult add_inhibition(const Loaded& loaded, const InhibitionRef& inhibition, bool chaining);

/// Makes a chaining inhibition (`=>`) non-chaining (`->`) and the other way round.
EditResult flip_chaining(const Loaded& loaded, const InhibitionRef& inhibition);

/// Sets the param `param` of behaviour `behaviour` of layer `layer` to `value`, written as it is
/// to be in the file (`0.6`, `true`, `"text"`, `[1, 2]`): the value replaced where the param is
/// written, else the param added to `params:` (which is added when missing). A value written as
/// a block collection is refused: replacing its lines is not an edit of one value.
EditResult set_param(const Loaded& loaded, const std::string& layer, const std::string& behaviour,
                     const std::string& param, const std::string& value);

/// Declares behaviour `name` of class `type` in layer `layer`: `name: {type: TYPE}` after the last
/// entry of the layer's `behaviours:` (the key added with it when the layer has none). Refused
/// when `name` is not an identifier or is taken, or the layer is not declared.
EditResult add_behaviour(const Loaded& loaded, const std::string& layer, const std::string& name,
                         const std::string& type);

/// Removes behaviour `name` of layer `layer`: its lines (with the `behaviours:` key when it was
/// the only one) and every inhibition of the layer that names it. Other uses (a port bound to it,
/// a state machine's owner) are left for checked() to refuse. In a flow mapping (and so in JSON)
/// its text goes with one comma. Refused when its key shares a line with another.
EditResult remove_behaviour(const Loaded& loaded, const std::string& layer,
                            const std::string& name);

/// Moves behaviour `name` of layer `layer` to position `index` (from 0) of the behaviours of
/// `to_layer` (its own layer when empty), as a person would cut and paste its lines: in its own
/// layer the others keep their order (the order of declaration breaks ties in the execution
/// order); to another layer its lines are indented as that layer's behaviours are. Refused when
/// the position is past the end or already its own, when an inhibition of its layer names it
/// (an inhibition cannot join two layers: remove it first), when the other layer is an
/// interface, or the name is taken there; ports that the new layer cannot bind are left for
/// checked() to refuse.
EditResult move_behaviour(const Loaded& loaded, const std::string& layer, const std::string& name,
                          const std::string& to_layer, std::size_t index);

/// Moves layer `layer` to position `index` (from 0) of the config's layer order, the others
/// keeping theirs. An included file's layers come before the including file's, so a layer moves
/// among the layers of the file that declares it: a position held by another file's layer is
/// refused.
EditResult move_layer(const Loaded& loaded, const std::string& layer, std::size_t index);

/// A position past every item: add_layer and add_queue_entry append there.
inline constexpr std::size_t kAtEnd = static_cast<std::size_t>(-1);

/// Declares layer `name` at position `index` (from 0; the number of layers or kAtEnd appends)
/// of the config's layer order, in the config's own file: `- name: NAME` (with `interface:
/// CLASS` for an interface layer, when `interface` is not empty), which is a valid layer with no
/// behaviours yet; a `layers: []` of a YAML file becomes a block list, and `layers:` is added
/// when missing. Refused when `name` is not an identifier or is a layer already, or the
/// position is past the end or holds an included file's layer (they come first).
EditResult add_layer(const Loaded& loaded, const std::string& name, std::size_t index = kAtEnd,
                     const std::string& interface = {});

/// Removes layer `name` with everything it declares (behaviours, actuators, inhibitions): its
/// item of `layers:` (the last one leaves `layers: []`). Refused, naming them, while other
/// layers read its actuators as sensors; what else would be left dangling (a state machine its
/// behaviour owned) is left for checked() to refuse.
EditResult remove_layer(const Loaded& loaded, const std::string& name);

/// Declares actuator `name` of value type `type` in layer `layer`: `name: {type: TYPE}` after
/// the last of its `actuators:` (the key added when it has none). Refused when `name` is not an
/// identifier or is an actuator of any layer already (actuator names are the manager's).
EditResult add_actuator(const Loaded& loaded, const std::string& layer, const std::string& name,
                        const std::string& type);

/// Removes actuator `name` of layer `layer` (its lines, and `actuators:` with its only one).
/// Refused, naming every use, while anything uses it: a layer reading it as a sensor, a port
/// bound to it (by a `ports:` entry or by name). Uses are not followed: dropping a sensor or
/// unbinding a port changes what the graph does, which is the user's call. A use in a class's
/// own params (a scripted behaviour's `writes:`) is left for checked() to refuse.
EditResult remove_actuator(const Loaded& loaded, const std::string& layer, const std::string& name);

/// Binds port `port` of behaviour `behaviour` of layer `layer` to `target` (a sensor or actuator
/// name): the `ports:` entry's value replaced, else the entry added (`ports:` added when
/// missing). Whether the class has the port and the layer the name is left for checked().
EditResult wire_port(const Loaded& loaded, const std::string& layer, const std::string& behaviour,
                     const std::string& port, const std::string& target);

/// Plans state `state` at position `index` (from 0; the queue's length or kAtEnd appends) of the
/// queue of state machine `machine`, with per-instance `params` (name, value as it is to be
/// written):
/// `- state` or `- state: {param: value}` in a block queue, `state` or `{state: {...}}` in a
/// flow one.
EditResult add_queue_entry(const Loaded& loaded, const std::string& machine,
                           const std::string& state,
                           const std::vector<std::pair<std::string, std::string>>& params,
                           std::size_t index);

/// Removes the item at position `index` of the queue of state machine `machine` (the last one
/// leaves `queue: []`).
EditResult remove_queue_entry(const Loaded& loaded, const std::string& machine, std::size_t index);

/// Moves the queue item at position `from` of state machine `machine` to position `to`, its
/// params and comments with it.
EditResult move_queue_entry(const Loaded& loaded, const std::string& machine, std::size_t from,
                            std::size_t to);

/// Declares state `name` of class `type` in state machine `machine`: `name: {type: TYPE}` after
/// the last of its `states:`. Refused when `name` is not an identifier or is a state of the
/// machine already.
EditResult add_state(const Loaded& loaded, const std::string& machine, const std::string& name,
                     const std::string& type);

/// Removes state `name` of state machine `machine` (its lines, or its entry and comma). Refused,
/// with the places (file:line:column), while the config names it (its queue, a pre-emption, a
/// state's append: or prepend:, as `index` of `loaded` finds them); a state that a class plans
/// by name (the soccer goalie's dive) is left for checked() to refuse.
EditResult remove_state(const Loaded& loaded, const ConfigIndex& index, const std::string& machine,
                        const std::string& name);

/// Names plugin `plugin` (a name looked up on the plugin path) in the config's `plugins:`, after
/// its last (`plugins: [NAME]` added when missing), so that its classes can be used. Refused when
/// it is named already or is not a plugin name; whether it is found is left for checked().
EditResult add_plugin(const Loaded& loaded, const std::string& plugin);

/// Makes layer `layer` read actuator `name` of another layer: `name` appended to its `sensors:`
/// list (`sensors: [NAME]` added when missing). Refused when it reads it already or its sensors
/// are written as a mapping with types; whether `name` is an actuator it may read is left for
/// checked().
EditResult add_sensor(const Loaded& loaded, const std::string& layer, const std::string& name);

/// Removes `name` from the `sensors:` list of layer `layer` (the last one leaves `sensors: []`).
/// A port bound to it is left for checked() to refuse.
EditResult remove_sensor(const Loaded& loaded, const std::string& layer, const std::string& name);

/// Declares state machine `name` with no states and an empty plan, `name: {states: {}, queue:
/// []}` (in a block `state_machines:` its keys on lines of their own), in the config's own file
/// (`state_machines:` added when missing). Refused when `name` is not an identifier or is a
/// state machine already.
EditResult add_state_machine(const Loaded& loaded, const std::string& name);

/// Removes state machine `name` with its states and queue. Refused, with the places
/// (file:line:column), while the config names it (a `state_machine` behaviour's or a state's
/// `machine:`, as `index` of `loaded` finds them).
EditResult remove_state_machine(const Loaded& loaded, const ConfigIndex& index,
                                const std::string& name);

/// What apply_operation gives: why the request is not an operation it can apply (`invalid`:
/// not a JSON object, an unknown op, a member missing or of the wrong type; then no result), or
/// the operation's result.
struct OperationResult {
  std::string invalid;
  EditResult result;
};

/// Applies the operation that `request` names, a JSON object in the studio's words
/// (docs/studio.md, `POST /studio/edit`): `{"op": "add_layer", "name": "io", "index": 0}`,
/// names as strings, positions as integers from 0, a param's value as a JSON value (written as
/// it is, JSON being a YAML flow value too); members it does not read are ignored. `invalid`
/// names the first member missing or mistyped and what it must be (`move_layer needs 'index'
/// (names as strings, positions as integers from 0)`), or lists the operations for an unknown
/// op. The operations that look names up (rename, remove_state, remove_state_machine) read
/// `index`, or index_config(loaded, registry) when it is null. The result is not checked().
OperationResult apply_operation(const Loaded& loaded, const std::string& request,
                                const Registry* registry, const ConfigIndex* index = nullptr);

/// Adds `entry` (`key: value`, as it is to be written) to the mapping `node` of `file`: before
/// a flow mapping's closing brace, else as a line of its own after the last line of the block
/// mapping, at its keys' indentation. Refused when the mapping's text is not where `node` says.
EditResult add_entry(const SourceFile& file, const Node& node, const std::string& entry);

/// The byte offset of a 1-based line and code-point column of `text` (clamped to the line).
std::size_t offset_of(const std::string& text, int line, int column);

/// A config loaded again with edits applied, before anything is written.
struct EditedConfig {
  /// The edited texts, which the load read through (declared first: destroyed after `loaded`).
  std::unique_ptr<Overlay> texts;
  Loaded loaded;
};

/// The config of `loaded` loaded again with `edits` applied to the texts it read (files it did
/// not read come from the disk): the diagnostics, model and program the edits would give.
/// `options.source` is replaced; the plugins are loaded into `registry` again.
EditedConfig load_edited(const Loaded& loaded, const std::vector<TextEdit>& edits,
                         Registry& registry, LoadOptions options = {});

/// `text` (of `file`) with the edits of `file` applied; they must not overlap.
std::string apply_edits(const std::string& text, const std::string& file,
                        const std::vector<TextEdit>& edits);

}  // namespace arbiter

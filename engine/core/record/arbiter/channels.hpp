#pragma once
// The channels a run publishes, the same in a recording (recording.hpp) and to a live viewer:
// each one's topic, and the JSON Schema of its messages, written for the program that runs so
// that a viewer (Foxglove, Lichtblick) knows every layer, behaviour, actuator and state machine
// by name. docs/replay.md and docs/foxglove.md describe them.
//
// Every schema here is one that Lichtblick's JSON Schema parser accepts as it is: an object at
// the top, and a `type` on every declared property, one type, never a list ("string" or "null"
// cannot be said). A field the parser cannot describe is left undeclared, and checked by
// `patternProperties`, which the parser does not read. tests/mcap/mcap_test.mjs applies its
// rules to every schema of a recording.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/manager.hpp"
#include "arbiter/scene.hpp"

namespace arbiter {

/// A channel of JSON messages described by a JSON Schema (MCAP's and the Foxglove WebSocket
/// protocol's encodings "json" and "jsonschema").
struct Channel {
  std::string topic;        ///< "/arbiter/step"
  std::string schema_name;  ///< "arbiter.Step"
  std::string schema;       ///< the JSON Schema, as text
};

inline constexpr std::string_view kMessageEncoding = "json";
inline constexpr std::string_view kSchemaEncoding = "jsonschema";

/// Where each channel is in what channels() returns.
enum ChannelIndex : std::size_t {
  kHeaderChannel,  ///< /arbiter/header: the trace header, at the start and at each hot reload
  kStepChannel,    ///< /arbiter/step: the trace's step record, one per step
  kInputsChannel,  ///< /arbiter/inputs: what interface layers read from the world, per step
  kLogChannel,     ///< /arbiter/log: foxglove.Log, what code reported and what went wrong
  kSceneChannel,   ///< /arbiter/scene: foxglove.SceneUpdate, what code drew (StepContext::scene)
  kChannelCount
};

/// The channels of a run of `program`, in ChannelIndex order. Allocates: call it when a run
/// starts or a program is staged, never in a step.
std::vector<Channel> channels(const Program& program);

/// foxglove.Log's levels.
enum class LogLevel : std::uint8_t {
  kUnknown = 0,
  kDebug = 1,
  kInfo = 2,
  kWarning = 3,
  kError = 4,
  kFatal = 5
};

/// A message of the `/arbiter/log` channel (Foxglove's foxglove.Log): `time_ns` since the epoch,
/// who it is from (`name`: a behaviour, a layer, "config"), and where in a file, if anywhere
/// (`file` empty and `line` 0 when nowhere). Appended to `out`, without a newline.
void append_log_message(std::uint64_t time_ns, LogLevel level, std::string_view name,
                        std::string_view message, std::string_view file, std::uint32_t line,
                        std::string& out);

/// A whole picture as a message of the `/arbiter/scene` channel (Foxglove's foxglove.SceneUpdate)
/// at `time_ns`: a deletion of all entities, then the primitives a step drew, in the entities
/// SceneUpdates gives them. The picture's `dropped` primitives (for want of room), and those
/// with a coordinate that is not a finite number, are told in the first entity's metadata
/// ("dropped"). Appended to `out`, without a newline. Allocates: off the stepping thread.
void append_scene_update(std::uint64_t time_ns, const ScenePicture& picture, std::string& out);

/// The `/arbiter/scene` messages of one recording, step after step. A frame's primitives are in
/// two entities, with lifetime 0 (a viewer keeps them until they are replaced or deleted): what
/// the step before a whole picture drew alike ("field/still") and the rest ("field/moving"). A
/// message between whole pictures carries only the moving entity (or deletes it when nothing
/// moves), so that what does not move (a field's lines) is not written every step. The whole
/// picture (a deletion of all, then every entity) comes first, at least once a second of log
/// time after (a viewer that seeks shows the last message before the time it seeks to), after
/// restart(), when a still primitive changes or goes, and while primitives are dropped.
class SceneUpdates {
 public:
  static constexpr std::uint64_t kWholeEveryNs = 1000000000;

  /// The message of a step at `time_ns`, as append_scene_update() takes it, appended to `out`.
  void append(std::uint64_t time_ns, const ScenePicture& picture, std::string& out);
  /// The next message gives the whole picture (a new program, a new file).
  void restart() { started_ = false; }

 private:
  struct Placed {
    std::string_view frame;  // cut to its room
    std::uint32_t rank = 0;  // among its frame's primitives
    std::size_t index = 0;   // in the step's primitives
    bool same = false;       // as the step before drew it
    bool still = false;      // in the entity of what does not move
  };
  static void place(const ScenePicture& picture, std::vector<Placed>& placed, std::size_t& dropped);

  bool started_ = false;
  std::uint64_t whole_at_ = 0;  // the last whole picture's time
  std::size_t dropped_ = 0;
  // The last message's step: what a viewer shows now. Reused: no allocation once grown.
  std::vector<ScenePrimitive> primitives_;
  std::vector<ScenePoint> points_;
  std::vector<char> strings_;
  std::vector<Placed> last_, now_;
};

}  // namespace arbiter

#pragma once
// The step record of the trace (docs/semantics.md, "The trace") and of recordings, in two halves:
// capture_step() copies a step's values out of the manager into a block laid out when the
// program was loaded (no allocation: a recorder does it on the stepping thread), and
// append_step_record() formats a snapshot, wherever and whenever it runs (a recorder's writer
// thread). Both the trace writer and the recorder go through them, so their records are the same
// bytes.

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/channels.hpp"
#include "arbiter/controller.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/step_ring.hpp"
#include "arbiter/trace.hpp"
#include "core/run/code_placement.hpp"

namespace arbiter::detail {

/// What formatting needs of a program besides a step's values: names, ranges and closed
/// inhibitions, copied, so that a snapshot can be formatted after a hot reload replaced the
/// program it was taken from. Not after that program is freed: a snapshot's state machines
/// point to their config params in it (Observer::on_retiring() keeps it until then).
struct StepLayout {
  explicit StepLayout(const Program& program);

  struct Layer {
    std::string name;
    std::uint32_t behaviour_begin = 0, behaviour_end = 0;
    std::uint32_t actuator_begin = 0, actuator_end = 0;
    bool interface = false;
  };
  struct Actuator {
    std::string name;
    const ValueType* type = nullptr;
    std::size_t offset = 0;
  };
  struct State {
    std::string name;
    const ClassInfo* cls = nullptr;
  };
  struct Machine {
    std::string name;
    std::vector<State> states;
    std::size_t capacity = 0;     // the longest queue
    std::size_t most_params = 0;  // of any of its states' classes
  };
  std::vector<Layer> layers;
  std::vector<std::string> behaviours;
  /// Behaviour b's closed inhibitors: inhibitors[inhibitor_begin[b] .. inhibitor_begin[b + 1]).
  std::vector<std::uint32_t> inhibitor_begin;
  std::vector<std::uint32_t> inhibitors;
  std::vector<Actuator> actuators;
  std::size_t value_bytes = 0;
  /// Every actuator's value is a built-in number, vector or flag: the values copy as bytes.
  bool plain_values = true;
  std::vector<Machine> machines;
  /// "machine/state" for each state of each machine in order: the names of the event sources
  /// after the behaviours and layers (a state's reports).
  std::vector<std::string> state_sources;
};

/// The scalars at the start of a snapshot's block: a cache line, which a streamed capture
/// writes whole.
struct alignas(64) SnapshotHeader {
  std::uint64_t step = 0;
  double t = 0.0;
  double duration = 0.0;
  std::uint32_t report_count = 0;
  std::uint32_t input_reports = 0;  ///< the first reports: made in the input pass
  std::uint32_t text_size = 0;
  /// False: the tracked parts hold only the chunks listed as changed (see SnapshotShape).
  bool full = true;
  bool safe = false;
  bool timed = false;
  std::uint32_t changed_count[TrackedLayout::kParts] = {};  // per tracked part
};

/// Where a step's values lie in a snapshot's block of bytes, laid out once for a layout. A
/// capture computes every address from it and only writes the block, never reads it: a
/// recorder's ring cycles through many blocks, each cold when its turn comes, and a store to a
/// cold line costs the stepping thread little, a load from one a wait.
///
/// The tracked parts (TrackedLayout: levels, flags, values), the bulk of a big graph's step, lie
/// in a block as in the manager, so that a small graph's are copied in one move; a chained
/// capture copies a part of more than kWhole bytes only by the 64-byte chunks that changed since
/// the capture before. What every step writes is packed at the start of the block, so that it
/// touches few lines; reports and state-machine events, seldom written, are in the block's
/// extras, apart.
struct SnapshotShape {
  SnapshotShape() = default;
  SnapshotShape(const StepLayout& layout, std::size_t text_bytes);

  static constexpr std::size_t kChunk = 64;
  /// A part this small is copied whole at every capture: comparing it with the capture before
  /// reads lines the stepping thread has not touched since, and at a robot's pace (a sleep
  /// between steps) those loads cost more than streaming the part whole. 256 bytes here made a
  /// served step of 100 behaviours 0.30x dearer than the plain one; 2 KiB, 0.10x.
  static constexpr std::size_t kWhole = 32 * kChunk;
  /// What a string value may hold in a block: a capture that may not allocate fails on a longer
  /// one (a recorder drops that step).
  static constexpr std::size_t kStringBytes = 256;

  struct Machine {
    std::uint64_t cycle = 0;
    ControllerStatus status = ControllerStatus::kRunning;
    std::uint32_t current = kNoState;  // state index
    const std::vector<Param>* planned = nullptr;
    std::uint32_t args_begin = 0, args_count = 0;  // into the args
    std::uint32_t queue_begin = 0, queue_count = 0;
    std::uint32_t events_begin = 0, events_count = 0;
  };
  struct Report {
    std::uint32_t source = 0;
    std::uint32_t text_begin = 0, text_size = 0;
  };
  using Arg = std::pair<std::uint32_t, ArgValue>;
  struct SceneCounts {
    std::uint32_t primitives = 0, points = 0, dropped = 0, string_bytes = 0;
  };
  /// A step's picture as the manager lays it out: the room for its primitives, for its points
  /// and for its strings (frames' names, texts). A capture copies only what was drawn, whole
  /// lines, into the blocks' picture ring (SnapshotBlock::scene), each step's after the step
  /// before's: a reader compares it with the picture before (SceneUpdates), not the stepping
  /// thread.
  static constexpr std::size_t kScenePrimitiveBytes =
      Manager::kScenePrimitivesPerStep * sizeof(ScenePrimitive);
  static constexpr std::size_t kScenePointBytes = Manager::kScenePointsPerStep * sizeof(ScenePoint);
  static constexpr std::size_t kSceneStringBytes = Manager::kSceneStringBytesPerStep;
  static constexpr std::size_t kSceneBytes =
      kScenePrimitiveBytes + kScenePointBytes + kSceneStringBytes;
  static_assert(kScenePrimitiveBytes % kChunk == 0 && kScenePointBytes % kChunk == 0 &&
                    kSceneStringBytes % kChunk == 0,
                "the picture's parts are whole chunks, copied as whole cache lines");
  /// The picture's counts and where it lies in the picture ring: one line of the block,
  /// written whole (streamed) at every capture.
  struct alignas(64) SceneLine {
    SceneCounts counts;
    std::uint64_t primitives_at = 0, points_at = 0, strings_at = 0;  ///< bytes into the ring
    std::uint64_t unused_rest[3] = {};  // no padding: the line is copied whole
  };
  static_assert(sizeof(SceneLine) == kChunk);

  std::size_t behaviours = 0, actuators = 0, machines = 0;
  std::size_t args = 0, queue = 0, events = 0, event_args = 0, text_bytes = 0;
  /// Every value is plain bytes: the values are tracked.
  bool plain_values = true;
  /// The tracked parts as the manager lays them out, and so a StepImage.
  TrackedLayout tracked;
  /// Per tracked part: where it starts in a block (the manager's layout, moved), and where the
  /// list of its changed chunks starts.
  std::size_t tracked_at[TrackedLayout::kParts] = {};
  std::size_t changed_at[TrackedLayout::kParts] = {};
  /// The parts a capture tracks: all of them, or all but the values when those are not plain
  /// bytes (then assigned value by value at every capture).
  std::size_t tracked_parts() const {
    return plain_values ? TrackedLayout::kParts : TrackedLayout::kValues;
  }
  /// Whether a chained capture copies `part` by the chunks that changed; if not, whole at every
  /// capture, without a list of changes.
  bool chunked(std::size_t part) const { return tracked.bytes[part] > kWhole; }
  std::size_t chunks(std::size_t part) const { return (tracked.bytes[part] + kChunk - 1) / kChunk; }
  /// Some tracked part is chunked: else a capture copies all of them in one move.
  bool any_chunked = false;
  /// A capture writes the header and the tracked parts, whole cache lines, with streaming stores,
  /// which bypass the caches: a ring's block is cold, and an ordinary store would first fetch
  /// each line for writing. When no part is chunked and the values are plain bytes (a small
  /// graph's); the tracked parts then take whole lines (`tracked.allocated` bytes). The slot
  /// must be published after fence_streamed_stores().
  bool streamed = false;
  /// Where the other parts start in a block (the header at 0).
  std::size_t machines_at = 0, args_at = 0, queue_at = 0;
  std::size_t bytes = 0;  ///< a block's: whole cache lines, so that blocks share none
  /// Where the seldom written parts start in a block's extras, and their bytes.
  std::size_t reports_at = 0, texts_at = 0, events_at = 0, event_args_at = 0;
  /// What code drew (StepContext::scene): its SceneLine, in the block.
  std::size_t scene_line_at = 0;
  std::size_t extra_bytes = 0;
};

/// Where one snapshot is: its block, the block's extras (SnapshotShape), and the picture ring
/// of the blocks it is one of.
struct SnapshotBlock {
  std::byte* main = nullptr;
  std::byte* extras = nullptr;
  /// Room for one more picture (SnapshotShape::kSceneBytes) than there are blocks: a capture
  /// writes its picture after the one before, and starts again at the beginning when the rest
  /// would not hold the most a step draws. So the pictures of the blocks a reader has not
  /// released yet (fewer than the blocks) are never written over, and the stepping thread never
  /// reads the reader's progress to know it.
  std::byte* scene = nullptr;
  std::size_t scene_bytes = 0;
};

/// The tracked parts of a step in full, laid out by a shape's `tracked`: the stepping side's, as
/// its last capture left them, or a reader's, brought up to date by the snapshots in order.
struct StepImage {
  std::vector<std::byte> bytes;
  /// The stepping side's: where in the picture ring (SnapshotBlock::scene) the next capture's
  /// picture goes.
  std::size_t scene_cursor = 0;
  /// Zeroed, sized for `shape`: the stepping side's, before its first capture.
  void reset(const SnapshotShape& shape);
};

/// Blocks of one shape, one after another: one for a trace writer, a ring of them for a
/// recorder. Each is ready to capture into; the values of types that own memory (strings) are
/// constructed in every block, with their reserve, and destroyed here.
class SnapshotBlocks {
 public:
  SnapshotBlocks() = default;
  ~SnapshotBlocks();
  SnapshotBlocks(const SnapshotBlocks&) = delete;
  SnapshotBlocks& operator=(const SnapshotBlocks&) = delete;

  /// `count` blocks for `layout`'s program, each with room for `text_bytes` of reported text.
  void reset(const StepLayout& layout, std::size_t text_bytes, std::size_t count);
  const SnapshotShape& shape() const { return shape_; }
  std::size_t size() const { return count_; }
  SnapshotBlock operator[](std::size_t index) const {
    return {data_ + index * shape_.bytes,
            data_ + count_ * shape_.bytes + index * shape_.extra_bytes,
            data_ + count_ * (shape_.bytes + shape_.extra_bytes), scene_bytes()};
  }
  /// The picture ring's (SnapshotBlock::scene).
  std::size_t scene_bytes() const { return (count_ + 1) * SnapshotShape::kSceneBytes; }

 private:
  void release();
  SnapshotShape shape_;
  std::size_t count_ = 0;
  std::byte* data_ = nullptr;
  std::size_t alignment_ = 0;  // data_'s
  // The values that are not plain bytes: constructed per type at these offsets of each block.
  std::vector<std::pair<const ValueType*, std::size_t>> constructed_;
};

/// A ring of snapshots laid out for one program, as a recorder and the live Foxglove server
/// keep them: made on the thread that stages the program where it can be, so that a hot reload
/// neither allocates on the stepping thread nor waits there for the reader.
struct SnapshotGeneration {
  /// Reported text a slot holds; a step that reported more is dropped.
  static constexpr std::size_t kReportTextBytes = 4096;

  SnapshotGeneration(const Program& program, std::uint64_t stage, std::size_t slots);
  std::uint64_t stage = 0;  ///< Manager::stage_number()
  StepLayout layout;
  SnapshotBlocks blocks;  ///< one per slot of the ring
  /// The stepping thread's: what its last capture left, for the next one to copy what changed.
  StepImage last;
  std::string header;             ///< the program's trace header, without a reload's number
  std::vector<Channel> channels;  ///< channels(program), in ChannelIndex order
  double rate_hz = 0.0;
  std::vector<std::pair<std::string, std::string>> files;  ///< a reloaded config's (path, text)
};

/// Copies the manager's last step (or safe pass) into `block`, of `shape`. False when something
/// does not fit (more reported text than the block holds; without `may_allocate`, a string value
/// longer than its reserve): the block is then incomplete and must not be read.
/// With `last` (the tracked parts as the capture before left them, kept up to date here) and
/// `chained` (that capture will be read just before this one), only the chunks that changed are
/// copied: a reader brings its own image up to date with StepSnapshot::apply(), in order.
bool capture_step(const Manager& manager, const StepLayout& layout, const SnapshotShape& shape,
                  SnapshotBlock block, bool may_allocate = false, StepImage* last = nullptr,
                  bool chained = false, CapturePicture picture = CapturePicture::kCopy);
/// capture_step() for the ring, which calls it at every observed step: bound within the library.
ARBITER_LIBRARY_LOCAL bool capture_step_in_library(const Manager& manager, const StepLayout& layout,
                                                   const SnapshotShape& shape, SnapshotBlock block,
                                                   bool may_allocate, StepImage* last, bool chained,
                                                   CapturePicture picture);

/// Makes the streaming stores of the captures before (SnapshotShape::streamed) visible to
/// other threads before the stores after it: a recorder calls it before it publishes a slot. Its
/// cost is waiting for those stores to leave the core, so a recorder publishes a step's slot
/// only at the next step, when they long have. Inline: no call at every step.
inline void fence_streamed_stores() {
#if defined(__SSE2__)
  _mm_sfence();
#endif
}

/// A contiguous run of T in a block, as a reader sees it.
template <typename T>
class Span {
 public:
  Span() = default;
  Span(const T* data, std::size_t size) : data_(data), size_(size) {}
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  const T& operator[](std::size_t i) const { return data_[i]; }

 private:
  const T* data_ = nullptr;
  std::size_t size_ = 0;
};

/// One step's values, as append_step_record() prints them: a reader's view of a captured block.
struct StepSnapshot {
  StepSnapshot(const SnapshotShape& shape, SnapshotBlock block);

  /// Brings `image` (a reader's, of the snapshots before this one) up to this one, and reads
  /// the tracked parts from it from now on: the block holds only those that changed when the
  /// capture was chained.
  void apply(StepImage& image);

  using Machine = SnapshotShape::Machine;
  using Report = SnapshotShape::Report;

  const SnapshotShape* shape = nullptr;
  const std::byte* block = nullptr;
  std::uint64_t step = 0;
  bool safe = false;
  bool timed = false;
  double t = 0.0;
  double duration = 0.0;
  Span<double> requested;
  Span<double> activation;
  Span<char> active;
  Span<bool> written;
  const std::byte* values = nullptr;
  Span<Machine> machines;
  Span<SnapshotShape::Arg> current_args;
  Span<std::uint32_t> queue;
  Span<Controller::Event> events;  // args_begin rebased into event_args
  Span<Controller::EventArg> event_args;
  Span<Report> reports;
  std::uint32_t input_reports = 0;  ///< how many of the reports the input pass made
  std::string_view texts;
  /// What code drew (StepContext::scene), and how many primitives it dropped for want of room.
  Span<ScenePrimitive> scene;
  Span<ScenePoint> scene_points;
  const char* scene_strings = nullptr;
  std::uint32_t scene_dropped = 0;
  ScenePicture picture() const {
    return {scene.data(), scene.size(), scene_points.data(), scene_strings, scene_dropped};
  }

  const void* value(const StepLayout& layout, std::uint32_t actuator) const {
    return values + layout.actuators[actuator].offset;
  }
};

/// A snapshot of the manager's last step in `storage` (one block, made over for `layout` when it
/// is not yet, and grown until the step's reported text fits): for those that may allocate.
StepSnapshot capture_growing(const Manager& manager, const StepLayout& layout,
                             SnapshotBlocks& storage);

/// The JSON Schemas of `/arbiter/step` and `/arbiter/inputs` for a program laid out as `layout`
/// (named `name`), and every channel (channels.hpp): on the thread that lays a program out.
std::string step_schema(const StepLayout& layout, const std::string& name);
std::string inputs_schema(const StepLayout& layout, const std::string& name);
std::vector<Channel> channels(const StepLayout& layout, const std::string& name);

/// Who made a report (StepSnapshot::Report::source): a behaviour, an interface layer, or
/// "state machines" for a standalone state machine.
const std::string& report_source(const StepLayout& layout, std::uint32_t source);

/// The step record of a snapshot, without the newline.
void append_step_record(const StepLayout& layout, const StepSnapshot& step, std::string& out);
/// The `/arbiter/inputs` message of a snapshot (see append_inputs_record in recording.hpp).
void append_inputs_record(const StepLayout& layout, const StepSnapshot& step, std::string& out);

/// Why a state ended, from a deactivation event and a function naming a state index.
template <typename Name>
StateEnd make_state_end(const Controller::Event& event, Name name) {
  const auto named = [&](std::uint32_t state) {
    return state == kNoState ? std::string() : std::string(name(state));
  };
  StateEnd end;
  end.state = named(event.state);
  end.cause = cause_name(event.cause);
  if (event.cause == Controller::EndCause::kTerminated) {
    end.by = named(event.other);
  } else {
    end.to = named(event.other);
  }
  if (event.preempt != kUnbound) end.preempt = event.preempt;
  end.proceeded = event.proceeded;
  return end;
}

/// "activate", "execute" or "deactivate".
const char* event_verb(Controller::Event::Kind kind);

/// A param's value as JSON; not `exact`: numbers to 4 significant digits (short_number()).
void append_param_json(const ParamValue& value, bool exact, std::string& out);

/// Per-instance params of a state of class `cls`: those `planned` in the config, then `args`
/// (param index, value) from Plan calls; see event_params() in trace.hpp.
template <typename Args, typename ValueOf>
ParamTexts merged_params(const ClassInfo& cls, const std::vector<Param>* planned, const Args& args,
                         ValueOf value_of, bool exact) {
  ParamTexts out;
  const auto set = [&](const std::string& name, const ParamValue& value) {
    std::string json;
    append_param_json(value, exact, json);
    for (auto& [known, text] : out) {
      if (known == name) {
        text = std::move(json);
        return;
      }
    }
    out.emplace_back(name, std::move(json));
  };
  if (planned != nullptr) {
    for (const auto& param : *planned) set(param.name, param.value);
  }
  for (const auto& arg : args) set(cls.params[arg.first].name, value_of(arg.second));
  return out;
}

}  // namespace arbiter::detail

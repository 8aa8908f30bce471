#include "core/record/step_record.hpp"
#include "core/run/code_placement.hpp"

#include <fmt/format.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <algorithm>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>
#include <typeinfo>

namespace arbiter::detail {

namespace {

bool plain_type(const ValueType& type) {
  const auto& t = *type.cpp_type;
  return t == typeid(bool) || t == typeid(std::int64_t) || t == typeid(double) ||
         t == typeid(Vec2) || t == typeid(Vec3);
}

void append_name(const std::string& name, std::string& out) {
  append_json_string(name, out);
}

// `, "params": {...}`, or nothing when there are none.
void append_params(const ParamTexts& params, std::string& out) {
  if (params.empty()) return;
  out += R"(, "params": {)";
  for (std::size_t i = 0; i < params.size(); ++i) {
    if (i > 0) out += ", ";
    append_name(params[i].first, out);
    out += ": " + params[i].second;
  }
  out += "}";
}

void append_end(const StateEnd& end, const ParamTexts& params, std::string& out) {
  out += R"({"state": )";
  append_name(end.state, out);
  append_params(params, out);
  out += R"(, "cause": )";
  append_name(end.cause, out);
  if (!end.to.empty()) {
    out += R"(, "to": )";
    append_name(end.to, out);
  }
  if (!end.by.empty()) {
    out += R"(, "by": )";
    append_name(end.by, out);
  }
  if (end.preempt >= 0) fmt::format_to(std::back_inserter(out), R"(, "preempt": {})", end.preempt);
  if (end.proceeded) out += R"(, "proceeded": true)";
  out += "}";
}

ParamValue param_value(const ArgValue& value) {
  return std::visit([](auto v) { return ParamValue(v); }, value);
}

}  // namespace

// Who reported: a behaviour, an interface layer, a state ("machine/state"), or a standalone state
// machine's code outside its states (kNoBehaviour).
const std::string& report_source(const StepLayout& layout, std::uint32_t source) {
  static const std::string kStandalone = "state machines";
  static const std::string kBreak = "break";
  if (source == kNoBehaviour) return kStandalone;
  if (source == Manager::kBreakSource) return kBreak;
  if (source < layout.behaviours.size()) return layout.behaviours[source];
  const std::size_t layer = source - layout.behaviours.size();
  if (layer < layout.layers.size()) return layout.layers[layer].name;
  const std::size_t state = layer - layout.layers.size();
  return state < layout.state_sources.size() ? layout.state_sources[state] : kStandalone;
}

const char* event_verb(Controller::Event::Kind kind) {
  return kind == Controller::Event::Kind::kActivate  ? "activate"
         : kind == Controller::Event::Kind::kExecute ? "execute"
                                                     : "deactivate";
}

void append_param_json(const ParamValue& value, bool exact, std::string& out) {
  struct Visitor {
    std::string& out;
    bool exact;
    void number(double v) const {
      if (exact) {
        append_json_number(v, out);
      } else {
        out += short_number(v);
      }
    }
    void operator()(bool v) const { out += v ? "true" : "false"; }
    void operator()(std::int64_t v) const { fmt::format_to(std::back_inserter(out), "{}", v); }
    void operator()(double v) const { number(v); }
    void operator()(const std::string& v) const { append_json_string(v, out); }
    void operator()(const Vec2& v) const { numbers({v.x, v.y}); }
    void operator()(const Vec3& v) const { numbers({v.x, v.y, v.z}); }
    void operator()(const std::vector<double>& v) const {
      out += '[';
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (i > 0) out += ", ";
        number(v[i]);
      }
      out += ']';
    }
    void operator()(const std::vector<std::string>& v) const {
      out += '[';
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (i > 0) out += ", ";
        append_json_string(v[i], out);
      }
      out += ']';
    }
    // A list of planned states (scripted's append:) is shown by what it says, not its structure.
    void operator()(const Node& v) const { append_json_string(v.describe(), out); }
    void numbers(std::initializer_list<double> values) const {
      out += '[';
      for (auto it = values.begin(); it != values.end(); ++it) {
        if (it != values.begin()) out += ", ";
        number(*it);
      }
      out += ']';
    }
  };
  std::visit(Visitor{out, exact}, value);
}

StepLayout::StepLayout(const Program& program) {
  for (const auto& layer : program.layers) {
    layers.push_back({layer.name, layer.behaviour_begin, layer.behaviour_end, layer.actuator_begin,
                      layer.actuator_end, layer.is_interface()});
  }
  std::vector<std::uint32_t> closed;
  inhibitor_begin.push_back(0);
  for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
    behaviours.push_back(program.behaviours[b].name);
    program.inhibitions.closed(b, closed);
    inhibitors.insert(inhibitors.end(), closed.begin(), closed.end());
    inhibitor_begin.push_back(static_cast<std::uint32_t>(inhibitors.size()));
  }
  for (std::uint32_t a = 0; a < program.actuators.size(); ++a) {
    actuators.push_back(
        {program.actuators[a].name, program.actuators[a].type, program.actuator_offsets[a]});
    plain_values = plain_values && plain_type(*program.actuators[a].type);
  }
  value_bytes = program.value_bytes;
  for (const auto& controller : program.controllers) {
    Machine machine;
    machine.name = controller->name();
    machine.capacity = controller->capacity();
    for (const auto& state : controller->states()) {
      machine.states.push_back({state.name, state.cls});
      state_sources.push_back(controller->name() + "/" + state.name);
      machine.most_params = std::max(machine.most_params, state.cls->params.size());
    }
    machines.push_back(std::move(machine));
  }
}

namespace {

std::size_t round_up(std::size_t n, std::size_t to) {
  return (n + to - 1) / to * to;
}

// Places `count` T at `at` or after, aligned for T: where they start; `at` moves past them.
template <typename T>
std::size_t place(std::size_t& at, std::size_t count) {
  const auto start = round_up(at, alignof(T));
  at = start + count * sizeof(T);
  return start;
}

template <typename T>
T* part_of(std::byte* block, std::size_t at) {
  return std::launder(reinterpret_cast<T*>(block + at));
}

template <typename T>
const T* part_of(const std::byte* block, std::size_t at) {
  return std::launder(reinterpret_cast<const T*>(block + at));
}

template <typename T>
void construct_part(std::byte* block, std::size_t at, std::size_t count) {
  std::uninitialized_value_construct_n(reinterpret_cast<T*>(block + at), count);
}

constexpr std::size_t kCacheLine = 64;
constexpr std::size_t kHugePage = std::size_t{2} << 20;

}  // namespace

SnapshotShape::SnapshotShape(const StepLayout& layout, std::size_t text_bytes_)
    : behaviours(layout.behaviours.size()),
      actuators(layout.actuators.size()),
      machines(layout.machines.size()),
      events(machines * Controller::kMaxEventsPerStep),
      text_bytes(text_bytes_),
      plain_values(layout.plain_values) {
  for (const auto& machine : layout.machines) {
    args += machine.most_params;
    queue += machine.capacity;
    event_args += Controller::kMaxEventsPerStep * machine.most_params;
  }
  // The chunked parts' lists of changes first, then the tracked parts as the manager has them.
  std::size_t at = sizeof(SnapshotHeader);
  tracked = TrackedLayout(behaviours, actuators, layout.value_bytes);
  for (std::size_t part = 0; part < tracked_parts(); ++part) {
    if (!chunked(part)) continue;
    any_chunked = true;
    changed_at[part] = place<std::uint32_t>(at, chunks(part));
  }
  streamed = !any_chunked && plain_values;
  const std::size_t tracked_begin = round_up(at, TrackedLayout::kAlignment);
  for (std::size_t part = 0; part < TrackedLayout::kParts; ++part) {
    tracked_at[part] = tracked_begin + tracked.at[part];
  }
  at = tracked_begin + (streamed ? tracked.allocated : tracked.total);
  machines_at = place<Machine>(at, machines);
  args_at = place<Arg>(at, args);
  queue_at = place<std::uint32_t>(at, queue);
  scene_line_at = place<SceneLine>(at, 1);  // a whole line, which a capture streams
  // Whole lines: the writer reads one block while the stepping thread fills the next.
  bytes = round_up(at, kCacheLine);
  // What a step seldom writes, or writes only the start of, apart: room for the most a step may
  // report would spread the blocks over many more pages than steps touch.
  std::size_t extra = 0;
  reports_at = place<Report>(extra, Manager::kEventsPerStep);
  texts_at = place<char>(extra, text_bytes);
  events_at = place<Controller::Event>(extra, events);
  event_args_at = place<Controller::EventArg>(extra, event_args);
  extra_bytes = round_up(extra, kCacheLine);
}

SnapshotBlocks::~SnapshotBlocks() {
  release();
}

void SnapshotBlocks::release() {
  if (data_ == nullptr) return;
  for (std::size_t i = 0; i < count_; ++i) {
    for (const auto& [type, offset] : constructed_) type->destroy((*this)[i].main + offset);
  }
  ::operator delete (data_, std::align_val_t{alignment_});
  data_ = nullptr;
  count_ = 0;
  constructed_.clear();
}

void SnapshotBlocks::reset(const StepLayout& layout, std::size_t text_bytes, std::size_t count) {
  release();
  shape_ = SnapshotShape(layout, text_bytes);
  const auto& s = shape_;
  count_ = count;
  std::size_t bytes = (s.bytes + s.extra_bytes) * count + scene_bytes();
  // A recorder's or a server's blocks and their picture ring span megabytes, which the stepping
  // thread walks through a few lines a step: on 4 KiB pages most captures met a page the TLB did
  // not hold, and under a virtual machine's nested paging that miss cost a served step more
  // than its copying. So whole 2 MiB pages, where the kernel gives them on request.
  alignment_ = kCacheLine;
  if (bytes >= kHugePage) {
    bytes = round_up(bytes, kHugePage);
    alignment_ = kHugePage;
  }
  data_ = static_cast<std::byte*>(::operator new (bytes, std::align_val_t{alignment_}));
#if defined(MADV_HUGEPAGE)
  // Before the pages are first written, below. Only advice: without it, or refused, 4 KiB pages.
  if (alignment_ == kHugePage) madvise(data_, bytes, MADV_HUGEPAGE);
#endif
  // Written here, so that the stepping thread's first pass through the picture ring finds its
  // pages mapped.
  construct_part<std::byte>((*this)[0].scene, 0, scene_bytes());
  for (std::size_t i = 0; i < count; ++i) {
    std::byte* block = (*this)[i].main;
    std::byte* extras = (*this)[i].extras;
    construct_part<SnapshotHeader>(block, 0, 1);
    for (std::size_t part = 0; part < s.tracked_parts(); ++part) {
      if (s.chunked(part)) construct_part<std::uint32_t>(block, s.changed_at[part], s.chunks(part));
    }
    // Bytes throughout, padding included: a capture may copy it all in one move.
    construct_part<std::byte>(block, s.tracked_at[0],
                              s.streamed ? s.tracked.allocated : s.tracked.total);
    construct_part<SnapshotShape::Machine>(block, s.machines_at, s.machines);
    construct_part<SnapshotShape::Arg>(block, s.args_at, s.args);
    construct_part<std::uint32_t>(block, s.queue_at, s.queue);
    construct_part<SnapshotShape::Report>(extras, s.reports_at, Manager::kEventsPerStep);
    construct_part<char>(extras, s.texts_at, s.text_bytes);
    construct_part<Controller::Event>(extras, s.events_at, s.events);
    construct_part<Controller::EventArg>(extras, s.event_args_at, s.event_args);
    construct_part<SnapshotShape::SceneLine>(block, s.scene_line_at, 1);
  }
  if (!s.plain_values) {
    for (const auto& actuator : layout.actuators) {
      const auto offset = s.tracked_at[TrackedLayout::kValues] + actuator.offset;
      constructed_.emplace_back(actuator.type, offset);
      for (std::size_t i = 0; i < count; ++i) {
        std::byte* value = (*this)[i].main + offset;
        actuator.type->construct(value);
        if (*actuator.type->cpp_type == typeid(std::string)) {
          static_cast<std::string*>(static_cast<void*>(value))
              ->reserve(SnapshotShape::kStringBytes);
        }
      }
    }
  }
}

namespace {

// Fixed-size moves the compiler inlines: a small graph's tracked parts are a few hundred bytes,
// and a call to memcpy would cost the step more than the copying. From 32 bytes on, 32-byte
// moves, the last overlapping the one before; below, two moves that may overlap.
void copy_bytes(std::byte* to, const std::byte* from, std::size_t bytes) {
  const auto two = [&](auto size) {
    std::memcpy(to, from, size);
    std::memcpy(to + bytes - size, from + bytes - size, size);
  };
  if (bytes > SnapshotShape::kWhole) {
    std::memcpy(to, from, bytes);
  } else if (bytes >= 32) {
    constexpr std::size_t kMove = 32;
    for (std::size_t at = 0; at + kMove < bytes; at += kMove)
      std::memcpy(to + at, from + at, kMove);
    std::memcpy(to + bytes - kMove, from + bytes - kMove, kMove);
  } else if (bytes >= 16) {
    two(std::integral_constant<std::size_t, 16>());
  } else if (bytes >= 8) {
    two(std::integral_constant<std::size_t, 8>());
  } else if (bytes >= 4) {
    two(std::integral_constant<std::size_t, 4>());
  } else {
    for (std::size_t at = 0; at < bytes; ++at) to[at] = from[at];
  }
}

// Whole cache lines from `from` to `to` (line-aligned), past the caches (SnapshotShape::streamed)
// where the CPU can; else an ordinary copy.
ARBITER_EVERY_STEP void stream_lines(std::byte* to, const std::byte* from, std::size_t bytes) {
#if defined(__SSE2__)
  for (std::size_t line = 0; line < bytes; line += 64) {
    const auto* in = reinterpret_cast<const __m128i*>(from + line);
    auto* out = reinterpret_cast<__m128i*>(to + line);
    const __m128i a = _mm_loadu_si128(in), b = _mm_loadu_si128(in + 1);
    const __m128i c = _mm_loadu_si128(in + 2), d = _mm_loadu_si128(in + 3);
    _mm_stream_si128(out, a);
    _mm_stream_si128(out + 1, b);
    _mm_stream_si128(out + 2, c);
    _mm_stream_si128(out + 3, d);
  }
#else
  std::memcpy(to, from, bytes);
#endif
}

bool same_chunk(const std::byte* a, const std::byte* b, std::size_t bytes) {
  if (bytes != SnapshotShape::kChunk) return std::memcmp(a, b, bytes) == 0;
  // Inline, whole words: a call to memcmp per line would cost more than the compare.
  std::uint64_t x[SnapshotShape::kChunk / 8];
  std::uint64_t y[SnapshotShape::kChunk / 8];
  std::memcpy(x, a, sizeof x);
  std::memcpy(y, b, sizeof y);
  std::uint64_t differ = 0;
  for (std::size_t i = 0; i < SnapshotShape::kChunk / 8; ++i) differ |= x[i] ^ y[i];
  return differ == 0;
}

// Copies the chunks of `now` that differ from `kept` to `to` and `kept`, listing them in
// `changed`: how many. Bytes, not values: -0.0 prints apart from 0.0.
std::uint32_t copy_changed(const std::byte* now, std::byte* kept, std::byte* to, std::size_t bytes,
                           std::uint32_t* changed) {
  if (std::memcmp(now, kept, bytes) == 0) return 0;  // most steps, most parts: one quick pass
  std::uint32_t count = 0;
  std::uint32_t chunk = 0;
  for (std::size_t at = 0; at < bytes; at += SnapshotShape::kChunk, ++chunk) {
    const auto size = std::min(SnapshotShape::kChunk, bytes - at);
    if (same_chunk(now + at, kept + at, size)) continue;
    std::memcpy(to + at, now + at, size);
    std::memcpy(kept + at, now + at, size);
    changed[count++] = chunk;
  }
  return count;
}

}  // namespace

SnapshotGeneration::SnapshotGeneration(const Program& program, std::uint64_t stage_,
                                       std::size_t slots)
    : stage(stage_),
      layout(program),
      header(trace_header(program)),
      channels(detail::channels(layout, program.name)),
      rate_hz(program.rate_hz) {
  blocks.reset(layout, kReportTextBytes, slots);
  last.reset(blocks.shape());
}

void StepImage::reset(const SnapshotShape& shape) {
  bytes.assign(shape.tracked.total, std::byte{0});
  scene_cursor = 0;
}

namespace {

/// The step's picture, as drawn, into the blocks' picture ring; where it lies, and its counts,
/// into `scene_line`.
ARBITER_EVERY_STEP void capture_picture(const Manager& manager, SnapshotBlock into, StepImage* last,
                                        SnapshotShape::SceneLine& scene_line) {
  const auto& scene = manager.scene();
  auto& scene_counts = scene_line.counts;
  scene_counts.primitives = static_cast<std::uint32_t>(manager.scene_primitive_count());
  scene_counts.points =
      static_cast<std::uint32_t>(std::min(scene.point_count, scene.point_capacity));
  scene_counts.dropped = static_cast<std::uint32_t>(scene.dropped);
  scene_counts.string_bytes = static_cast<std::uint32_t>(scene.string_size);
  // Copied as drawn, whole lines (the manager's buffers have room for them), streamed after the
  // picture before: comparing it with that one is the reader's work (SceneUpdates), and the
  // pictures of consecutive steps share pages, where each block's own room would put every step
  // on pages of its own.
  const auto primitive_bytes =
      round_up(scene_counts.primitives * sizeof(ScenePrimitive), SnapshotShape::kChunk);
  const auto point_bytes =
      round_up(scene_counts.points * sizeof(ScenePoint), SnapshotShape::kChunk);
  const auto string_bytes = round_up(scene_counts.string_bytes, SnapshotShape::kChunk);
  std::size_t scene_at = last != nullptr ? last->scene_cursor : 0;
  if (scene_at + primitive_bytes + point_bytes + string_bytes > into.scene_bytes) scene_at = 0;
  scene_line.primitives_at = scene_at;
  scene_line.points_at = scene_at + primitive_bytes;
  scene_line.strings_at = scene_line.points_at + point_bytes;
  stream_lines(into.scene + scene_at, reinterpret_cast<const std::byte*>(scene.primitives),
               primitive_bytes);
  stream_lines(into.scene + scene_line.points_at, reinterpret_cast<const std::byte*>(scene.points),
               point_bytes);
  stream_lines(into.scene + scene_line.strings_at,
               reinterpret_cast<const std::byte*>(scene.strings), string_bytes);
  if (last != nullptr) last->scene_cursor = scene_line.strings_at + string_bytes;
}

// The parts of a capture that a small graph's step does not need, each a function of its own,
// out of line: at a robot's pace the capture's code is cold, and each line of it the step runs
// through costs a miss. Those that few steps need (reports, values that are not plain bytes),
// apart from the rest of the code as well.

ARBITER_OUT_OF_LINE void capture_changed_parts(const std::byte* now, const SnapshotShape& shape,
                                               std::byte* block, StepImage& last,
                                               SnapshotHeader& header) {
  for (std::size_t part = 0; part < shape.tracked_parts(); ++part) {
    const auto bytes = shape.tracked.bytes[part];
    const std::byte* from = now + shape.tracked.at[part];
    std::byte* to = block + shape.tracked_at[part];
    if (!shape.chunked(part)) {
      copy_bytes(to, from, bytes);  // whole at every capture: `last` has no use for it
    } else {
      // Compared where they are hot (the manager's and `last`), written to the block, which
      // is cold, only by the chunk that changed.
      header.changed_count[part] =
          copy_changed(from, last.bytes.data() + shape.tracked.at[part], to, bytes,
                       part_of<std::uint32_t>(block, shape.changed_at[part]));
    }
  }
}

// False when a string is longer than the copy's reserve and `may_allocate` is not set.
ARBITER_SELDOM bool capture_values(const Manager& manager, const StepLayout& layout,
                                   const SnapshotShape& shape, std::byte* block,
                                   bool may_allocate) {
  std::byte* values = block + shape.tracked_at[TrackedLayout::kValues];
  for (std::uint32_t a = 0; a < shape.actuators; ++a) {
    const auto& actuator = layout.actuators[a];
    void* to = values + actuator.offset;
    const void* from = manager.actuator_value(a);
    // A string longer than the copy's reserve would allocate.
    if (!may_allocate && *actuator.type->cpp_type == typeid(std::string) &&
        static_cast<const std::string*>(from)->size() >
            static_cast<const std::string*>(to)->capacity()) {
      return false;
    }
    actuator.type->assign(to, from);
  }
  return true;
}

// False when the state machines hold more than the block has room for.
ARBITER_OUT_OF_LINE bool capture_machines(const Program& program, const SnapshotShape& shape,
                                          SnapshotBlock into) {
  std::byte* block = into.main;
  auto* machines = part_of<SnapshotShape::Machine>(block, shape.machines_at);
  auto* current_args = part_of<SnapshotShape::Arg>(block, shape.args_at);
  auto* queue = part_of<std::uint32_t>(block, shape.queue_at);
  auto* events = part_of<Controller::Event>(into.extras, shape.events_at);
  auto* event_args = part_of<Controller::EventArg>(into.extras, shape.event_args_at);
  std::uint32_t args = 0;
  std::uint32_t queued = 0;
  std::uint32_t event_index = 0;
  std::uint32_t event_arg = 0;
  for (std::size_t c = 0; c < shape.machines; ++c) {
    const Controller& controller = *program.controllers[c];
    SnapshotShape::Machine machine;
    machine.cycle = controller.cycle();
    machine.status = controller.status();
    machine.current = controller.current_state_index();
    machine.planned = controller.current_planned();
    machine.args_begin = args;
    for (const auto& [param, value] : controller.current_args()) {
      if (args == shape.args) return false;
      auto& to = current_args[args++];
      to.first = param;
      if (const auto* v = std::get_if<bool>(&value)) {
        to.second = *v;
      } else if (const auto* i = std::get_if<std::int64_t>(&value)) {
        to.second = *i;
      } else if (const auto* d = std::get_if<double>(&value)) {
        to.second = *d;
      } else if (const auto* v2 = std::get_if<Vec2>(&value)) {
        to.second = *v2;
      } else if (const auto* v3 = std::get_if<Vec3>(&value)) {
        to.second = *v3;
      } else {
        return false;  // Plan calls give only these; anything else would need a copy
      }
    }
    machine.args_count = args - machine.args_begin;
    machine.queue_begin = queued;
    if (queued + controller.queue_size() > shape.queue) return false;
    for (std::size_t i = 0; i < controller.queue_size(); ++i) {
      queue[queued++] = controller.queued_state(i);
    }
    machine.queue_count = queued - machine.queue_begin;
    machine.events_begin = event_index;
    for (std::size_t e = 0; e < controller.event_count(); ++e) {
      Controller::Event event = controller.events()[e];
      if (event_index == shape.events || event_arg + event.args_count > shape.event_args) {
        return false;
      }
      const auto* first = controller.event_args(event);
      event.args_begin = event_arg;
      for (std::uint32_t i = 0; i < event.args_count; ++i) event_args[event_arg++] = first[i];
      events[event_index++] = event;
    }
    machine.events_count = event_index - machine.events_begin;
    machines[c] = machine;
  }
  return true;
}

// False when the texts are more than the block has room for; else their size.
ARBITER_SELDOM bool capture_reports(const Manager& manager, const SnapshotShape& shape,
                                    std::byte* extras, std::size_t count,
                                    std::uint32_t& text_size) {
  auto* reports = part_of<SnapshotShape::Report>(extras, shape.reports_at);
  auto* texts = part_of<char>(extras, shape.texts_at);
  for (std::size_t e = 0; e < count; ++e) {
    const auto& event = manager.event(e);
    const auto size = std::strlen(event.text);
    if (text_size + size > shape.text_bytes) return false;
    reports[e] = {event.source, text_size, static_cast<std::uint32_t>(size)};
    std::memcpy(texts + text_size, event.text, size);
    text_size += static_cast<std::uint32_t>(size);
  }
  return true;
}

}  // namespace

ARBITER_EVERY_STEP bool capture_step_in_library(const Manager& manager, const StepLayout& layout,
                                                const SnapshotShape& shape, SnapshotBlock into,
                                                bool may_allocate, StepImage* last, bool chained,
                                                CapturePicture picture) {
  std::byte* block = into.main;
  // Written to the block last, whole: the block is cold, and never read here.
  SnapshotHeader header;
  header.step = manager.steps();
  header.safe = manager.in_safe_pass();
  header.timed = manager.timed();
  header.t = manager.step_time();
  header.duration = manager.step_duration();
  const std::byte* now = manager.tracked_parts();
  header.full = last == nullptr || !chained;
  if (header.full || !shape.any_chunked) {
    // Laid out as in the manager: a small graph's step is one move.
    const std::size_t bytes = shape.tracked.end_of(shape.tracked_parts());
    // Streamed at the end, once nothing can fail: a failed capture leaves no streaming store in
    // flight to a block the writer may free.
    if (!shape.streamed) copy_bytes(block + shape.tracked_at[0], now, bytes);
    if (last != nullptr && shape.any_chunked) std::memcpy(last->bytes.data(), now, bytes);
  } else {
    capture_changed_parts(now, shape, block, *last, header);
  }
  if (!shape.plain_values && !capture_values(manager, layout, shape, block, may_allocate)) {
    return false;
  }
  if (shape.machines > 0 && !capture_machines(manager.program(), shape, into)) return false;
  const auto report_count = std::min(manager.event_count(), Manager::kEventsPerStep);
  std::uint32_t text_size = 0;
  if (report_count > 0 && !capture_reports(manager, shape, into.extras, report_count, text_size)) {
    return false;
  }
  header.report_count = static_cast<std::uint32_t>(report_count);
  header.input_reports =
      static_cast<std::uint32_t>(std::min(manager.input_pass_events(), report_count));
  header.text_size = text_size;
  // Written whole at the end, streamed: the block's lines are cold. Left out, the picture reads
  // as none.
  SnapshotShape::SceneLine scene_line;
  if (picture == CapturePicture::kCopy) capture_picture(manager, into, last, scene_line);
  stream_lines(block + shape.scene_line_at, reinterpret_cast<const std::byte*>(&scene_line),
               sizeof scene_line);
  if (shape.streamed) {
    stream_lines(block + shape.tracked_at[0], now, shape.tracked.allocated);
    stream_lines(block, reinterpret_cast<const std::byte*>(&header), sizeof header);
  } else {
    std::memcpy(block, &header, sizeof header);
  }
  return true;
}

bool capture_step(const Manager& manager, const StepLayout& layout, const SnapshotShape& shape,
                  SnapshotBlock into, bool may_allocate, StepImage* last, bool chained,
                  CapturePicture picture) {
  return capture_step_in_library(manager, layout, shape, into, may_allocate, last, chained,
                                 picture);
}

StepSnapshot::StepSnapshot(const SnapshotShape& s, SnapshotBlock from)
    : shape(&s), block(from.main) {
  const std::byte* b = from.main;
  const std::byte* extras = from.extras;
  const auto& header = *part_of<SnapshotHeader>(b, 0);
  step = header.step;
  safe = header.safe;
  timed = header.timed;
  t = header.t;
  duration = header.duration;
  requested = {part_of<double>(b, s.tracked_at[TrackedLayout::kRequested]), s.behaviours};
  activation = {part_of<double>(b, s.tracked_at[TrackedLayout::kActivation]), s.behaviours};
  active = {part_of<char>(b, s.tracked_at[TrackedLayout::kActive]), s.behaviours};
  written = {part_of<bool>(b, s.tracked_at[TrackedLayout::kWritten]), s.actuators};
  values = b + s.tracked_at[TrackedLayout::kValues];
  machines = {part_of<Machine>(b, s.machines_at), s.machines};
  current_args = {part_of<SnapshotShape::Arg>(b, s.args_at), s.args};
  queue = {part_of<std::uint32_t>(b, s.queue_at), s.queue};
  events = {part_of<Controller::Event>(extras, s.events_at), s.events};
  event_args = {part_of<Controller::EventArg>(extras, s.event_args_at), s.event_args};
  reports = {part_of<Report>(extras, s.reports_at), header.report_count};
  input_reports = header.input_reports;
  texts = std::string_view(part_of<char>(extras, s.texts_at), header.text_size);
  const auto& line = *part_of<SnapshotShape::SceneLine>(b, s.scene_line_at);
  scene = {part_of<ScenePrimitive>(from.scene, line.primitives_at), line.counts.primitives};
  scene_points = {part_of<ScenePoint>(from.scene, line.points_at), line.counts.points};
  scene_strings = part_of<char>(from.scene, line.strings_at);
  scene_dropped = line.counts.dropped;
}

void StepSnapshot::apply(StepImage& image) {
  const auto& s = *shape;
  const auto& header = *part_of<SnapshotHeader>(block, 0);
  image.bytes.resize(s.tracked.total);
  for (std::size_t part = 0; part < s.tracked_parts(); ++part) {
    const std::byte* from = block + s.tracked_at[part];
    std::byte* to = image.bytes.data() + s.tracked.at[part];
    const auto bytes = s.tracked.bytes[part];
    if (header.full || !s.chunked(part)) {
      std::copy(from, from + bytes, to);
      continue;
    }
    const auto* changed = part_of<std::uint32_t>(block, s.changed_at[part]);
    for (std::uint32_t i = 0; i < header.changed_count[part]; ++i) {
      const auto at = changed[i] * SnapshotShape::kChunk;
      const auto size = std::min(SnapshotShape::kChunk, bytes - at);
      std::copy(from + at, from + at + size, to + at);
    }
  }
  const std::byte* from = image.bytes.data();
  requested = {part_of<double>(from, s.tracked.at[TrackedLayout::kRequested]), s.behaviours};
  activation = {part_of<double>(from, s.tracked.at[TrackedLayout::kActivation]), s.behaviours};
  active = {part_of<char>(from, s.tracked.at[TrackedLayout::kActive]), s.behaviours};
  written = {part_of<bool>(from, s.tracked.at[TrackedLayout::kWritten]), s.actuators};
  if (s.plain_values) values = from + s.tracked.at[TrackedLayout::kValues];
}

StepSnapshot capture_growing(const Manager& manager, const StepLayout& layout,
                             SnapshotBlocks& storage) {
  constexpr std::size_t kTextBytes = 1024;
  std::size_t text = 0;
  for (std::size_t e = 0; e < manager.event_count(); ++e)
    text += std::strlen(manager.event(e).text);
  if (storage.size() == 0 || storage.shape().text_bytes < text) {
    storage.reset(layout, std::max({kTextBytes, text, 2 * storage.shape().text_bytes}), 1);
  }
  if (!capture_step(manager, layout, storage.shape(), storage[0], true)) {
    // Every part is sized for the program and the text for this step: only a state-machine
    // argument of a kind Plan cannot give gets here.
    throw std::logic_error(
        fmt::format("step {}: a value the step record cannot hold", manager.steps()));
  }
  return StepSnapshot(storage.shape(), storage[0]);
}

void append_step_record(const StepLayout& layout, const StepSnapshot& step, std::string& out) {
  fmt::format_to(std::back_inserter(out), R"({{"step": {}, )", step.step);
  if (step.safe) out += R"("safe": true, )";
  if (step.timed) {
    out += R"("t": )";
    append_json_number(step.t, out);
    out += R"(, "duration": )";
    append_json_number(step.duration, out);
    out += ", ";
  }
  out += R"("layers": {)";
  for (std::size_t l = 0; l < layout.layers.size(); ++l) {
    const auto& layer = layout.layers[l];
    if (l > 0) out += ", ";
    append_name(layer.name, out);
    out += ": {";
    for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
      if (b > layer.behaviour_begin) out += ", ";
      append_name(layout.behaviours[b], out);
      out += R"(: {"requested": )";
      append_json_number(step.requested[b], out);
      out += R"(, "activation": )";
      append_json_number(step.activation[b], out);
      out += step.active[b] != 0 ? R"(, "active": true)" : R"(, "active": false)";
      out += R"(, "inhibited_by": [)";
      bool first = true;
      for (auto i = layout.inhibitor_begin[b]; i < layout.inhibitor_begin[b + 1]; ++i) {
        const auto inhibitor = layout.inhibitors[i];
        if (step.activation[inhibitor] <= 0.0) continue;
        if (!first) out += ", ";
        first = false;
        append_name(layout.behaviours[inhibitor], out);
      }
      out += "]}";
    }
    out += "}";
  }
  out += R"(}, "actuators": {)";
  for (std::uint32_t a = 0; a < layout.actuators.size(); ++a) {
    if (a > 0) out += ", ";
    append_name(layout.actuators[a].name, out);
    out += R"(: {"value": )";
    layout.actuators[a].type->append_json(step.value(layout, a), out);
    out += step.written[a] ? R"(, "written": true})" : R"(, "written": false})";
  }
  out += R"(}, "controllers": {)";
  std::vector<std::pair<std::uint32_t, ArgValue>> args;
  for (std::size_t c = 0; c < layout.machines.size(); ++c) {
    const auto& machine = layout.machines[c];
    const auto& taken = step.machines[c];
    const auto name = [&](std::uint32_t state) -> const std::string& {
      return machine.states[state].name;
    };
    if (c > 0) out += ", ";
    append_name(machine.name, out);
    fmt::format_to(std::back_inserter(out), R"(: {{"cycle": {}, "state": )", taken.cycle);
    if (taken.current == kNoState) {
      out += "null";
    } else {
      append_name(name(taken.current), out);
    }
    out += R"(, "queue": [)";
    for (std::uint32_t i = 0; i < taken.queue_count; ++i) {
      if (i > 0) out += ", ";
      append_name(name(step.queue[taken.queue_begin + i]), out);
    }
    out += "]";
    if (taken.current != kNoState) {
      const auto* first = step.current_args.data() + taken.args_begin;
      append_params(merged_params(*machine.states[taken.current].cls, taken.planned,
                                  std::vector<std::pair<std::uint32_t, ArgValue>>(
                                      first, first + taken.args_count),
                                  param_value, true),
                    out);
    }
    out += R"(, "events": [)";
    bool ended = false;
    for (std::uint32_t e = 0; e < taken.events_count; ++e) {
      const auto& event = step.events[taken.events_begin + e];
      if (e > 0) out += ", ";
      append_name(std::string(event_verb(event.kind)) + " " + name(event.state), out);
      ended = ended || event.kind == Controller::Event::Kind::kDeactivate;
    }
    out += "]";
    if (ended) {
      out += R"(, "ended": [)";
      bool first = true;
      for (std::uint32_t e = 0; e < taken.events_count; ++e) {
        const auto& event = step.events[taken.events_begin + e];
        if (event.kind != Controller::Event::Kind::kDeactivate) continue;
        if (!first) out += ", ";
        first = false;
        args.clear();
        for (std::uint32_t i = 0; i < event.args_count; ++i) {
          const auto& arg = step.event_args[event.args_begin + i];
          args.emplace_back(arg.param, arg.value);
        }
        append_end(
            make_state_end(event, name),
            merged_params(*machine.states[event.state].cls, event.planned, args, param_value, true),
            out);
      }
      out += "]";
    }
    out += R"(, "status": ")";
    out += to_string(taken.status);
    out += "\"}";
  }
  out += "}";
  // What behaviour and interface code reported (StepContext::report): only in steps that have
  // some, so that traces of graphs that report nothing keep the exact shape of docs/semantics.md,
  // "The trace".
  if (step.reports.size() > 0) {
    out += R"(, "reported": [)";
    for (std::size_t e = 0; e < step.reports.size(); ++e) {
      const auto& report = step.reports[e];
      if (e > 0) out += ", ";
      out += R"({"by": )";
      append_name(report_source(layout, report.source), out);
      out += R"(, "text": )";
      append_json_string(std::string(step.texts.substr(report.text_begin, report.text_size)), out);
      out += "}";
    }
    out += "]";
  }
  out += "}";
}

void append_inputs_record(const StepLayout& layout, const StepSnapshot& step, std::string& out) {
  fmt::format_to(std::back_inserter(out), R"({{"step": {}, "inputs": {{)", step.step);
  bool first = true;
  for (const auto& layer : layout.layers) {
    if (!layer.interface) continue;
    for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
      if (!first) out += ", ";
      first = false;
      append_name(layout.actuators[a].name, out);
      out += R"(: {"value": )";
      layout.actuators[a].type->append_json(step.value(layout, a), out);
      out += step.written[a] ? R"(, "written": true})" : R"(, "written": false})";
    }
  }
  out += "}";
  // What interface code reported is an input too: replay reports it again, from the layer that
  // reported it, in the pass it was reported in.
  bool reported = false;
  const auto behaviours = layout.behaviours.size();
  for (std::size_t e = 0; e < step.reports.size(); ++e) {
    const auto& report = step.reports[e];
    if (report.source < behaviours || report.source - behaviours >= layout.layers.size() ||
        !layout.layers[report.source - behaviours].interface) {
      continue;
    }
    out += reported ? ", " : R"(, "reported": [)";
    reported = true;
    out += R"({"by": )";
    append_name(layout.layers[report.source - behaviours].name, out);
    out += R"(, "text": )";
    append_json_string(std::string(step.texts.substr(report.text_begin, report.text_size)), out);
    out += e < step.input_reports ? R"(, "pass": "input"})" : R"(, "pass": "output"})";
  }
  if (reported) out += "]";
  out += "}";
}

}  // namespace arbiter::detail

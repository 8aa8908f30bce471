#include "arbiter/channels.hpp"

#include <fmt/compile.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <typeinfo>
#include <utility>

#include "arbiter/trace.hpp"
#include "core/record/scene_update_schema.hpp"
#include "core/record/step_record.hpp"

namespace arbiter {

namespace {

constexpr std::string_view kDraft = R"("$schema": "https://json-schema.org/draft/2020-12/schema")";

void append_name(std::string_view name, std::string& out) {
  detail::append_json_string(std::string(name), out);
}

// `{"type": "object", "properties": {NAME: SCHEMA, ...}, "required": [...], "additionalProperties":
// false}` for fields all present in every message, each schema given by `field(i, out)`.
template <typename Names, typename Field>
void append_closed_object(const Names& names, Field field, std::string& out) {
  out += R"({"type": "object", "properties": {)";
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += ", ";
    append_name(names[i], out);
    out += ": ";
    field(i, out);
  }
  out += R"(}, "required": [)";
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += ", ";
    append_name(names[i], out);
  }
  out += R"(], "additionalProperties": false})";
}

// The schema of a value as ValueType::append_json writes it, for the built-in types; empty for
// a plugin's own type, whose JSON this cannot know.
std::string value_schema(const ValueType& type) {
  const auto& t = *type.cpp_type;
  if (t == typeid(bool)) return R"({"type": "boolean"})";
  if (t == typeid(std::int64_t)) return R"({"type": "integer"})";
  if (t == typeid(double)) return R"({"type": "number"})";
  if (t == typeid(std::string)) return R"({"type": "string"})";
  if (t == typeid(Vec2)) {
    return R"({"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2})";
  }
  if (t == typeid(Vec3)) {
    return R"({"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3})";
  }
  return {};
}

// An actuator's or an input's `{"value": V, "written": B}`.
void append_value_entry(const ValueType& type, std::string& out) {
  const auto value = value_schema(type);
  out += R"({"type": "object", "properties": {)";
  if (!value.empty()) out += R"("value": )" + value + ", ";
  out += R"("written": {"type": "boolean"}})";
  if (value.empty()) {
    // Checked all the same, out of the parser's sight (see channels.hpp).
    out += fmt::format(R"(, "patternProperties": {{"^value$": {{"description": "a value of the )"
                       R"(plugin type {}, as the plugin writes it"}}}})",
                       type.name);
  }
  out += R"(, "required": ["value", "written"], "additionalProperties": false})";
}

// The schema of a param's value as append_param_json() writes it; empty for kAny, whose value
// is the class's own.
std::string param_schema(ParamKind kind) {
  switch (kind) {
    case ParamKind::kBool:
      return R"({"type": "boolean"})";
    case ParamKind::kInt:
      return R"({"type": "integer"})";
    case ParamKind::kDouble:
      return R"({"type": "number"})";
    case ParamKind::kString:
      return R"({"type": "string"})";
    case ParamKind::kVec2:
    case ParamKind::kVec3:
    case ParamKind::kDoubleList:
      return R"({"type": "array", "items": {"type": "number"}})";
    case ParamKind::kStringList:
      return R"({"type": "array", "items": {"type": "string"}})";
    case ParamKind::kAny:
      break;
  }
  return {};
}

// The per-instance params of a machine's states: every param any of its states' classes has,
// typed where they all agree on its kind. Open: a param left out is still allowed.
std::string machine_params_schema(const detail::StepLayout::Machine& machine) {
  std::vector<std::pair<std::string, std::string>> params;  // name, schema ("": no one type)
  for (const auto& state : machine.states) {
    for (const auto& param : state.cls->params) {
      auto schema = param_schema(param.kind);
      bool known = false;
      for (auto& [name, kept] : params) {
        if (name != param.name) continue;
        known = true;
        if (kept != schema) kept.clear();
      }
      if (!known) params.emplace_back(param.name, std::move(schema));
    }
  }
  std::string out = R"({"type": "object", "description": "the state's per-instance params", )"
                    R"("properties": {)";
  bool first = true;
  for (const auto& [name, schema] : params) {
    if (schema.empty()) continue;
    if (!first) out += ", ";
    first = false;
    append_name(name, out);
    out += ": " + schema;
  }
  out += "}}";
  return out;
}

void append_state_names(const detail::StepLayout::Machine& machine, std::string& out) {
  for (std::size_t s = 0; s < machine.states.size(); ++s) {
    if (s > 0) out += ", ";
    append_name(machine.states[s].name, out);
  }
}

void append_machine_schema(const detail::StepLayout::Machine& machine, std::string& out) {
  const auto params = machine_params_schema(machine);
  std::string names;
  append_state_names(machine, names);
  out += R"({"type": "object", "properties": {"cycle": {"type": "integer", "minimum": 0}, )";
  out += R"("queue": {"type": "array", "items": {"type": "string", "enum": [)" + names + "]}}, ";
  out += R"("params": )" + params + ", ";
  out += R"("events": {"type": "array", "items": {"type": "string"}}, )";
  out += R"("ended": {"type": "array", "description": "why each state deactivated in the step )"
         R"(ended, in order", "items": {"type": "object", "properties": {)";
  out += R"("state": {"type": "string", "enum": [)" + names + "]}, ";
  out += R"("params": )" + params + ", ";
  out += R"("cause": {"type": "string", "enum": [)";
  using Cause = Controller::EndCause;
  for (auto c = static_cast<int>(Cause::kProceeded); c <= static_cast<int>(Cause::kDropped); ++c) {
    if (c > static_cast<int>(Cause::kProceeded)) out += ", ";
    append_name(cause_name(static_cast<Cause>(c)), out);
  }
  out += R"(]}, "to": {"type": "string"}, "by": {"type": "string"}, )";
  out += R"("preempt": {"type": "integer", "minimum": 0}, "proceeded": {"type": "boolean"}}, )";
  out += R"("required": ["state", "cause"], "additionalProperties": false}}, )";
  out += R"("status": {"type": "string", "enum": [)";
  for (auto status :
       {ControllerStatus::kRunning, ControllerStatus::kFinished, ControllerStatus::kError}) {
    if (status != ControllerStatus::kRunning) out += ", ";
    append_name(to_string(status), out);
  }
  // `state` is null before the first state and after the last: a type the parser cannot say,
  // so checked out of its sight (see channels.hpp).
  out += R"(]}}, "patternProperties": {"^state$": {"description": "the current state, null )"
         R"(before the first and after the last", "enum": [)" +
         names + (names.empty() ? "" : ", ") + "null]}}, ";
  out += R"("required": ["cycle", "state", "queue", "events", "status"], )";
  out += R"("additionalProperties": false})";
}

constexpr std::string_view kReportedSchema =
    R"({"type": "array", "description": "what behaviour and interface code reported in the step", )"
    R"("items": {"type": "object", "properties": {"by": {"type": "string"}, )"
    R"("text": {"type": "string"}}, "required": ["by", "text"], "additionalProperties": false}})";

constexpr std::string_view kHeaderSchema =
    R"({"$schema": "https://json-schema.org/draft/2020-12/schema",
 "title": "arbiter trace header",
 "type": "object",
 "properties": {
  "arbiter_trace": {"type": "integer", "const": 1},
  "reload": {"type": "integer", "minimum": 1, "description": "which hot reload swapped the program in"},
  "after_step": {"type": "integer", "minimum": 0, "description": "the last step of the program it replaced"},
  "name": {"type": "string"},
  "layers": {"type": "array", "items": {"type": "object", "properties": {
    "name": {"type": "string"},
    "order": {"type": "array", "items": {"type": "string"}, "description": "the layer's behaviours, in execution order"}},
   "required": ["name", "order"], "additionalProperties": false}}},
 "required": ["arbiter_trace", "name", "layers"],
 "additionalProperties": false})";

// Foxglove's documented foxglove.Log
// (https://docs.foxglove.dev/docs/visualization/message-schemas/log), whose `level` the parser
// reads as constants.
constexpr std::string_view kLogSchema =
    R"({"$schema": "https://json-schema.org/draft/2020-12/schema",
 "title": "foxglove.Log",
 "description": "A log message",
 "type": "object",
 "properties": {
  "timestamp": {"type": "object", "title": "time", "description": "Timestamp of log message",
   "properties": {"sec": {"type": "integer", "minimum": 0},
                  "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}},
   "required": ["sec", "nsec"]},
  "level": {"title": "foxglove.LogLevel", "description": "Log level",
   "oneOf": [{"title": "UNKNOWN", "const": 0}, {"title": "DEBUG", "const": 1},
             {"title": "INFO", "const": 2}, {"title": "WARNING", "const": 3},
             {"title": "ERROR", "const": 4}, {"title": "FATAL", "const": 5}]},
  "message": {"type": "string", "description": "Log message"},
  "name": {"type": "string", "description": "Process or node name"},
  "file": {"type": "string", "description": "Filename"},
  "line": {"type": "integer", "minimum": 0, "maximum": 4294967295, "description": "Line number in the file"}},
 "required": ["timestamp", "level", "message", "name", "file", "line"]})";

}  // namespace

namespace detail {

std::string step_schema(const StepLayout& layout, const std::string& name) {
  std::string out = "{";
  out += kDraft;
  out += R"(, "title": )";
  append_name("arbiter step record of " + name, out);
  out += R"(, "type": "object", "properties": {)";
  out += R"("step": {"type": "integer", "minimum": 0}, )";
  out += R"("safe": {"type": "boolean", "description": "the safe-value pass of a stopping or )"
         R"(pausing engine"}, )";
  out += R"("t": {"type": "number", "description": "seconds since the run began, at the step's )"
         R"(start"}, )";
  out += R"("duration": {"type": "number", "description": "seconds the step took"}, )";
  out += R"("layers": )";
  std::vector<std::string> names;
  for (const auto& layer : layout.layers) names.push_back(layer.name);
  append_closed_object(
      names,
      [&](std::size_t l, std::string& o) {
        const auto& layer = layout.layers[l];
        std::vector<std::string> behaviours(layout.behaviours.begin() + layer.behaviour_begin,
                                            layout.behaviours.begin() + layer.behaviour_end);
        append_closed_object(
            behaviours,
            [](std::size_t, std::string& b) {
              b += R"({"type": "object", "properties": {"requested": {"type": "number"}, )"
                   R"("activation": {"type": "number"}, "active": {"type": "boolean"}, )"
                   R"("inhibited_by": {"type": "array", "items": {"type": "string"}}}, )"
                   R"("required": ["requested", "activation", "active", "inhibited_by"], )"
                   R"("additionalProperties": false})";
            },
            o);
      },
      out);
  out += R"(, "actuators": )";
  names.clear();
  for (const auto& actuator : layout.actuators) names.push_back(actuator.name);
  append_closed_object(
      names,
      [&](std::size_t a, std::string& o) { append_value_entry(*layout.actuators[a].type, o); },
      out);
  out += R"(, "controllers": )";
  names.clear();
  for (const auto& machine : layout.machines) names.push_back(machine.name);
  append_closed_object(
      names, [&](std::size_t c, std::string& o) { append_machine_schema(layout.machines[c], o); },
      out);
  out += R"(, "reported": )";
  out += kReportedSchema;
  out += R"(}, "required": ["step", "layers", "actuators", "controllers"], )";
  out += R"("additionalProperties": false})";
  return out;
}

std::string inputs_schema(const StepLayout& layout, const std::string& name) {
  std::string out = "{";
  out += kDraft;
  out += R"(, "title": )";
  append_name("arbiter interface inputs of " + name, out);
  out += R"(, "type": "object", "properties": {"step": {"type": "integer", "minimum": 0}, )";
  out += R"("inputs": )";
  std::vector<std::string> names;
  std::vector<std::uint32_t> inputs;
  for (const auto& layer : layout.layers) {
    if (!layer.interface) continue;
    for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
      names.push_back(layout.actuators[a].name);
      inputs.push_back(a);
    }
  }
  append_closed_object(
      names,
      [&](std::size_t i, std::string& o) {
        append_value_entry(*layout.actuators[inputs[i]].type, o);
      },
      out);
  out += R"(, "reported": {"type": "array", "description": "what interface code reported, and )"
         R"(in which pass", "items": {"type": "object", "properties": {"by": {"type": "string"}, )"
         R"("text": {"type": "string"}, "pass": {"type": "string", "enum": ["input", "output"]}}, )"
         R"("required": ["by", "text", "pass"], "additionalProperties": false}}}, )";
  out += R"("required": ["step", "inputs"], "additionalProperties": false})";
  return out;
}

std::vector<Channel> channels(const StepLayout& layout, const std::string& name) {
  std::vector<Channel> out(kChannelCount);
  out[kHeaderChannel] = {"/arbiter/header", "arbiter.Header", std::string(kHeaderSchema)};
  out[kStepChannel] = {"/arbiter/step", "arbiter.Step", step_schema(layout, name)};
  out[kInputsChannel] = {"/arbiter/inputs", "arbiter.Inputs", inputs_schema(layout, name)};
  out[kLogChannel] = {"/arbiter/log", "foxglove.Log", std::string(kLogSchema)};
  out[kSceneChannel] = {"/arbiter/scene", "foxglove.SceneUpdate", std::string(kSceneUpdateSchema)};
  return out;
}

}  // namespace detail

std::vector<Channel> channels(const Program& program) {
  return detail::channels(detail::StepLayout(program), program.name);
}

void append_log_message(std::uint64_t time_ns, LogLevel level, std::string_view name,
                        std::string_view message, std::string_view file, std::uint32_t line,
                        std::string& out) {
  fmt::format_to(std::back_inserter(out),
                 R"({{"timestamp": {{"sec": {}, "nsec": {}}}, "level": {}, "message": )",
                 time_ns / 1000000000u, time_ns % 1000000000u, static_cast<int>(level));
  append_name(message, out);
  out += R"(, "name": )";
  append_name(name, out);
  out += R"(, "file": )";
  append_name(file, out);
  fmt::format_to(std::back_inserter(out), R"(, "line": {}}})", line);
}

namespace {

bool has_points(const ScenePrimitive& p) {
  return p.shape == SceneShape::kLine || p.shape == SceneShape::kPolygon;
}

bool finite_primitive(const ScenePrimitive& p, const ScenePoint* points) {
  bool ok = std::isfinite(p.x0) && std::isfinite(p.y0) && std::isfinite(p.x1) &&
            std::isfinite(p.y1) && std::isfinite(p.size) && std::isfinite(p.color.r) &&
            std::isfinite(p.color.g) && std::isfinite(p.color.b) && std::isfinite(p.color.a);
  for (std::uint32_t i = 0; ok && has_points(p) && i < p.point_count; ++i) {
    ok = std::isfinite(points[p.point_begin + i].x) && std::isfinite(points[p.point_begin + i].y);
  }
  return ok;
}

// Scene messages are formatted into a reused buffer: appending to it is a copy, where each
// format_to() into a std::string resizes (and zeroes) it first.
using Buffer = fmt::memory_buffer;
using Out = fmt::appender;

void put(Buffer& out, std::string_view text) {
  out.append(text.data(), text.data() + text.size());
}

// A JSON string: a name as it is unless it holds a character JSON escapes.
void put_name(Buffer& out, std::string_view name) {
  const bool plain = std::all_of(name.begin(), name.end(), [](char c) {
    return c != '"' && c != '\\' && static_cast<unsigned char>(c) >= 0x20;
  });
  if (plain) {
    out.push_back('"');
    put(out, name);
    out.push_back('"');
  } else {
    std::string quoted;
    detail::append_json_string(std::string(name), quoted);
    put(out, quoted);
  }
}

// A length or a coordinate to the micrometre, a rotation's component to 1e-6: finer is noise
// (a cosine's last bits), which would make each number twice as long in every message.
double fine(double value) {
  return std::round(value * 1e6) / 1e6 + 0.0;  // + 0.0: no "-0"
}

// foxglove.Pose: at (x, y) on the ground, turned by `yaw` about the vertical.
void append_pose(double x, double y, double yaw, Buffer& out) {
  fmt::format_to(Out(out),
                 FMT_COMPILE(R"("pose":{{"position":{{"x":{},"y":{},"z":0}},"orientation":)"
                             R"({{"x":0,"y":0,"z":{},"w":{}}}}})"),
                 fine(x), fine(y), fine(std::sin(yaw / 2)), fine(std::cos(yaw / 2)));
}

void append_color(const SceneColor& c, Buffer& out) {
  fmt::format_to(Out(out), FMT_COMPILE(R"("color":{{"r":{},"g":{},"b":{},"a":{}}})"), c.r, c.g, c.b,
                 c.a);
}

// foxglove.LinePrimitive: a strip (0) or a loop (1) through `count` points given by `point(i)`.
template <typename Point>
void append_line(int type, double width, const SceneColor& color, std::size_t count, Point point,
                 Buffer& out) {
  fmt::format_to(Out(out), FMT_COMPILE(R"({{"type":{},)"), type);
  append_pose(0, 0, 0, out);
  fmt::format_to(Out(out), FMT_COMPILE(R"(,"thickness":{},"scale_invariant":false,"points":[)"),
                 fine(width));
  for (std::size_t i = 0; i < count; ++i) {
    const ScenePoint at = point(i);
    fmt::format_to(Out(out), FMT_COMPILE(R"({}{{"x":{},"y":{},"z":0}})"), i > 0 ? "," : "",
                   fine(at.x), fine(at.y));
  }
  put(out, "],");
  append_color(color, out);
  put(out, R"(,"colors":[],"indices":[]})");
}

// A circle's outline, as Foxglove has no circle: a loop of this many points.
constexpr int kCirclePoints = 32;
constexpr double kPi = 3.14159265358979323846;

// A frame's or a text's `size` bytes, as Scene copied them: cut to their room of `bytes` (its
// NUL included), perhaps inside a UTF-8 character, whose start is then left out too, so that the
// JSON stays valid UTF-8.
std::string_view cut(const char* text, std::size_t size, std::size_t bytes) {
  if (size + 1 < bytes) return {text, size};
  std::size_t start = size;  // of the last character
  while (start > 0 && (static_cast<unsigned char>(text[start - 1]) & 0xC0) == 0x80) --start;
  if (start == 0) return {text, size};
  const auto lead = static_cast<unsigned char>(text[start - 1]);
  const std::size_t length = lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : lead >= 0xC0 ? 2 : 1;
  return {text, start - 1 + length <= size ? size : start - 1};
}

std::string_view frame_of(const ScenePicture& picture, const ScenePrimitive& p) {
  const char* frame = picture.frame(p);
  return cut(frame, strnlen(frame, ScenePrimitive::kFrameBytes), ScenePrimitive::kFrameBytes);
}

std::string_view text_of(const ScenePicture& picture, const ScenePrimitive& p) {
  return cut(picture.text(p), picture.text_size(p), ScenePrimitive::kTextBytes);
}

void append_entity_id(std::string_view frame, bool still, Buffer& out);

// The entity of a frame's primitives that are `still` (unchanged since the step before the last
// whole picture) or not: its id is the frame's name and "still" or "moving", "field/moving".
template <typename Primitives>
void append_entity(std::uint64_t sec, std::uint64_t nsec, std::string_view frame, bool still,
                   Primitives each, const ScenePicture& picture, std::size_t dropped, Buffer& out) {
  fmt::format_to(Out(out), FMT_COMPILE(R"({{"timestamp":{{"sec":{},"nsec":{}}},"frame_id":)"), sec,
                 nsec);
  put_name(out, frame);
  put(out, R"(,"id":)");
  append_entity_id(frame, still, out);
  put(out, R"(,"lifetime":{"sec":0,"nsec":0},"frame_locked":false,"metadata":[)");
  if (dropped > 0) {
    fmt::format_to(Out(out), FMT_COMPILE(R"({{"key":"dropped","value":"{}"}})"), dropped);
  }
  // The primitives `wanted`, separated by commas.
  const auto list = [&](auto wanted, auto append) {
    bool first = true;
    each([&](const ScenePrimitive& p) {
      if (!wanted(p)) return;
      if (!first) put(out, ",");
      first = false;
      append(p);
    });
  };
  const auto is = [](SceneShape shape) {
    return [shape](const ScenePrimitive& p) { return p.shape == shape; };
  };
  put(out, R"(],"arrows":[)");
  list(is(SceneShape::kArrow), [&](const ScenePrimitive& p) {
    const double length = std::hypot(p.x1 - p.x0, p.y1 - p.y0);
    const double head = std::min(0.4 * length, 3 * p.size);
    put(out, "{");
    append_pose(p.x0, p.y0, std::atan2(p.y1 - p.y0, p.x1 - p.x0), out);
    fmt::format_to(Out(out),
                   FMT_COMPILE(R"(,"shaft_length":{},"shaft_diameter":{},"head_length":{},)"
                               R"("head_diameter":{},)"),
                   fine(length - head), fine(p.size), fine(head), fine(2.5 * p.size));
    append_color(p.color, out);
    put(out, "}");
  });
  put(out, R"(],"cubes":[],"spheres":[],"cylinders":[)");
  list([](const ScenePrimitive& p) { return p.shape == SceneShape::kCircle && p.filled; },
       [&](const ScenePrimitive& p) {
         put(out, "{");
         append_pose(p.x0, p.y0, 0, out);
         fmt::format_to(Out(out),
                        FMT_COMPILE(R"(,"size":{{"x":{},"y":{},"z":0.01}},"bottom_scale":1,)"
                                    R"("top_scale":1,)"),
                        fine(2 * p.size), fine(2 * p.size));
         append_color(p.color, out);
         put(out, "}");
       });
  put(out, R"(],"lines":[)");
  list(
      [](const ScenePrimitive& p) {
        return p.shape == SceneShape::kLine || p.shape == SceneShape::kPolygon ||
               (p.shape == SceneShape::kCircle && !p.filled);
      },
      [&](const ScenePrimitive& p) {
        if (p.shape == SceneShape::kCircle) {
          append_line(
              1, p.x1, p.color, kCirclePoints,
              [&](std::size_t i) {
                const double angle = 2 * kPi * static_cast<double>(i) / kCirclePoints;
                return ScenePoint{p.x0 + p.size * std::cos(angle), p.y0 + p.size * std::sin(angle)};
              },
              out);
        } else {
          append_line(
              p.shape == SceneShape::kPolygon ? 1 : 0, p.size, p.color, p.point_count,
              [&](std::size_t i) { return picture.points[p.point_begin + i]; }, out);
        }
      });
  put(out, R"(],"triangles":[],"texts":[)");
  list(is(SceneShape::kText), [&](const ScenePrimitive& p) {
    put(out, "{");
    append_pose(p.x0, p.y0, 0, out);
    fmt::format_to(Out(out),
                   FMT_COMPILE(R"(,"billboard":true,"font_size":{},"scale_invariant":false,)"),
                   fine(p.size));
    append_color(p.color, out);
    put(out, R"(,"text":)");
    put_name(out, text_of(picture, p));
    put(out, "}");
  });
  put(out, R"(],"models":[]})");
}

// Whether two primitives draw alike (their points and texts compared by value, not by place).
bool same(const ScenePrimitive& a, const ScenePicture& a_picture, const ScenePrimitive& b,
          const ScenePicture& b_picture) {
  if (a.shape != b.shape || a.filled != b.filled || a.point_count != b.point_count ||
      a.x0 != b.x0 || a.y0 != b.y0 || a.x1 != b.x1 || a.y1 != b.y1 || a.size != b.size ||
      a.color.r != b.color.r || a.color.g != b.color.g || a.color.b != b.color.b ||
      a.color.a != b.color.a) {
    return false;
  }
  if (a.shape == SceneShape::kText) return text_of(a_picture, a) == text_of(b_picture, b);
  if (!has_points(a)) return true;
  for (std::uint32_t i = 0; i < a.point_count; ++i) {
    const ScenePoint& pa = a_picture.points[a.point_begin + i];
    const ScenePoint& pb = b_picture.points[b.point_begin + i];
    if (pa.x != pb.x || pa.y != pb.y) return false;
  }
  return true;
}

void append_entity_id(std::string_view frame, bool still, Buffer& out) {
  char id[ScenePrimitive::kFrameBytes + 8];  // the frame is cut to its room
  const char* end = fmt::format_to(id, FMT_COMPILE("{}/{}"), frame, still ? "still" : "moving");
  put_name(out, {id, static_cast<std::size_t>(end - id)});
}

}  // namespace

void SceneUpdates::place(const ScenePicture& picture, std::vector<Placed>& placed,
                         std::size_t& dropped) {
  placed.clear();
  for (std::size_t i = 0; i < picture.count; ++i) {
    if (!finite_primitive(picture.primitives[i], picture.points)) {
      ++dropped;
      continue;
    }
    const auto frame = frame_of(picture, picture.primitives[i]);
    std::uint32_t rank = 0;
    for (auto it = placed.rbegin(); it != placed.rend(); ++it) {
      if (it->frame == frame) {
        rank = it->rank + 1;
        break;
      }
    }
    placed.push_back({frame, rank, i});
  }
}

void SceneUpdates::append(std::uint64_t time_ns, const ScenePicture& picture, std::string& text) {
  thread_local Buffer out;  // reused: no allocation once grown
  out.clear();
  const auto sec = time_ns / 1000000000u, nsec = time_ns % 1000000000u;
  std::size_t dropped = picture.dropped;
  const ScenePrimitive* primitives = picture.primitives;
  place(picture, now_, dropped);
  const ScenePicture before{primitives_.data(), primitives_.size(), points_.data(), strings_.data(),
                            dropped_};
  const auto find = [&](const Placed& at) -> const Placed* {
    for (const Placed& p : last_) {
      if (p.rank == at.rank && p.frame == at.frame) return &p;
    }
    return nullptr;
  };
  // The whole picture now and then, so that a viewer that seeks (and shows the last message
  // before the time it seeks to) soon has all of it; whenever something was dropped, so that
  // the count told in the first entity is never left on another one; and when a still
  // primitive changed or went.
  bool whole = !started_ || time_ns < whole_at_ || time_ns - whole_at_ >= kWholeEveryNs ||
               dropped > 0 || dropped_ > 0;
  std::size_t still_now = 0;
  for (Placed& at : now_) {
    const Placed* before_at = find(at);
    at.same = before_at != nullptr &&
              same(primitives[at.index], picture, primitives_[before_at->index], before);
    at.still = before_at != nullptr && before_at->still;
    if (at.still) ++still_now;
    if (at.still && !at.same) whole = true;
  }
  std::size_t still_before = 0;
  for (const Placed& p : last_) still_before += p.still ? 1 : 0;
  if (still_now != still_before) whole = true;
  if (whole) {
    // Still: what the step before drew alike; at the start, all (the next step sorts it out).
    const bool first = last_.empty();
    for (Placed& at : now_) at.still = first || at.same;
  }

  // The frames, in the order first drawn in; whether each has a moving part now or had one.
  const auto each_frame = [&](const std::vector<Placed>& placed, auto visit) {
    for (std::size_t i = 0; i < placed.size(); ++i) {
      bool seen = false;
      for (std::size_t j = 0; j < i && !seen; ++j) seen = placed[j].frame == placed[i].frame;
      if (!seen) visit(placed[i].frame);
    }
  };
  const auto has = [](const std::vector<Placed>& placed, std::string_view frame, bool still) {
    return std::any_of(placed.begin(), placed.end(),
                       [&](const Placed& p) { return p.frame == frame && p.still == still; });
  };
  const auto part = [&](std::string_view frame, bool still) {
    return [&, frame, still](auto visit) {
      for (const Placed& p : now_) {
        if (p.frame == frame && p.still == still) visit(primitives[p.index]);
      }
    };
  };

  put(out, R"({"deletions":[)");
  if (whole) {
    fmt::format_to(Out(out),
                   FMT_COMPILE(R"({{"timestamp":{{"sec":{},"nsec":{}}},"type":1,"id":""}})"), sec,
                   nsec);
    started_ = true;
    whole_at_ = time_ns;
  } else {
    bool first = true;
    each_frame(last_, [&](std::string_view frame) {
      if (!has(last_, frame, false) || has(now_, frame, false)) return;
      fmt::format_to(Out(out),
                     FMT_COMPILE(R"({}{{"timestamp":{{"sec":{},"nsec":{}}},"type":0,"id":)"),
                     first ? "" : ",", sec, nsec);
      append_entity_id(frame, false, out);
      put(out, "}");
      first = false;
    });
  }
  put(out, R"(],"entities":[)");
  bool first = true;
  each_frame(now_, [&](std::string_view frame) {
    for (const bool still : {true, false}) {
      if ((still && !whole) || !has(now_, frame, still)) continue;
      if (!first) put(out, ",");
      append_entity(sec, nsec, frame, still, part(frame, still), picture, first ? dropped : 0, out);
      first = false;
    }
  });
  put(out, "]}");
  text.append(out.data(), out.size());

  // What the viewer now shows, to compare the next step's drawing with.
  primitives_.assign(primitives, primitives + picture.count);
  points_.assign(picture.points, picture.points + picture.point_end());
  strings_.assign(picture.strings, picture.strings + picture.string_end());
  last_.swap(now_);
  for (Placed& p : last_) {
    p.frame = std::string_view(strings_.data() + primitives_[p.index].frame, p.frame.size());
  }
  dropped_ = dropped;
}

void append_scene_update(std::uint64_t time_ns, const ScenePicture& picture, std::string& out) {
  SceneUpdates fresh;
  fresh.append(time_ns, picture, out);
}

}  // namespace arbiter

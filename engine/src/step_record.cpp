#include "step_record.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
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

// Who reported: a behaviour, an interface layer, or a standalone state machine (kNoBehaviour).
const std::string& source_name(const StepLayout& layout, std::uint32_t source) {
  static const std::string kStandalone = "state machines";
  if (source == kNoBehaviour) return kStandalone;
  if (source < layout.behaviours.size()) return layout.behaviours[source];
  return layout.layers[source - layout.behaviours.size()].name;
}

}  // namespace

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
      machine.most_params = std::max(machine.most_params, state.cls->params.size());
    }
    machines.push_back(std::move(machine));
  }
}

StepSnapshot::~StepSnapshot() {
  release();
}

void StepSnapshot::release() {
  for (const auto& [type, offset] : constructed_) type->destroy(values_.get() + offset);
  constructed_.clear();
  values_.reset();
}

void StepSnapshot::size_for(const StepLayout& layout, std::size_t text_bytes) {
  release();
  const auto behaviours = layout.behaviours.size();
  requested.assign(behaviours, 0.0);
  activation.assign(behaviours, 0.0);
  active.assign(behaviours, 0);
  levels_full = true;
  changed_blocks.assign((behaviours + kLevelBlock - 1) / kLevelBlock, 0);
  changed_count = 0;
  written.assign(layout.actuators.size(), 0);
  values_ = std::make_unique<std::byte[]>(std::max<std::size_t>(layout.value_bytes, 1));
  if (!layout.plain_values) {
    for (const auto& actuator : layout.actuators) {
      actuator.type->construct(values_.get() + actuator.offset);
      constructed_.emplace_back(actuator.type, actuator.offset);
    }
  }
  machines.assign(layout.machines.size(), Machine{});
  std::size_t args = 0;
  std::size_t queue_entries = 0;
  std::size_t event_args_size = 0;
  for (const auto& machine : layout.machines) {
    args += machine.most_params;
    queue_entries += machine.capacity;
    event_args_size += Controller::kMaxEventsPerStep * machine.most_params;
  }
  current_args.assign(args, {});
  queue.assign(queue_entries, 0);
  events.assign(layout.machines.size() * Controller::kMaxEventsPerStep, {});
  event_args.assign(event_args_size, {});
  report_count = 0;
  reports.assign(Manager::kEventsPerStep, {});
  texts.clear();
  texts.reserve(text_bytes);
}

void StepSnapshot::apply_levels(Levels& current) const {
  if (levels_full) {
    current.requested = requested;
    current.activation = activation;
    current.active = active;
    return;
  }
  const auto behaviours = requested.size();
  for (std::size_t i = 0; i < changed_count; ++i) {
    const std::size_t begin = changed_blocks[i] * kLevelBlock;
    const std::size_t end = std::min(begin + kLevelBlock, behaviours);
    std::copy(requested.begin() + begin, requested.begin() + end,
              current.requested.begin() + begin);
    std::copy(activation.begin() + begin, activation.begin() + end,
              current.activation.begin() + begin);
    std::copy(active.begin() + begin, active.begin() + end, current.active.begin() + begin);
  }
}

bool StepSnapshot::capture(const Manager& manager, const StepLayout& layout, bool grow,
                           Levels* last, bool chained) {
  const Program& program = manager.program();
  step = manager.steps();
  safe = manager.in_safe_pass();
  timed = manager.timed();
  t = manager.step_time();
  duration = manager.step_duration();
  const std::size_t behaviours = layout.behaviours.size();
  const double* requested_now = manager.requested_levels();
  const double* activation_now = manager.activation_levels();
  const char* active_now = manager.active_flags();
  if (last != nullptr && chained) {
    // Compared where they are hot (the manager's levels and `last`), written to the slot, which
    // is cold, only by the block that changed. Bytes, not values: -0.0 prints apart from 0.0.
    levels_full = false;
    changed_count = 0;
    const auto same = [&](std::size_t begin, std::size_t count) {
      return std::memcmp(requested_now + begin, last->requested.data() + begin,
                         count * sizeof(double)) == 0 &&
             std::memcmp(activation_now + begin, last->activation.data() + begin,
                         count * sizeof(double)) == 0 &&
             std::memcmp(active_now + begin, last->active.data() + begin, count) == 0;
    };
    if (behaviours > 0 && !same(0, behaviours)) {
      for (std::size_t begin = 0; begin < behaviours; begin += kLevelBlock) {
        const auto count = std::min(kLevelBlock, behaviours - begin);
        if (same(begin, count)) continue;
        changed_blocks[changed_count++] = static_cast<std::uint32_t>(begin / kLevelBlock);
        const auto copy = [&](const auto* from, auto& to, auto& kept) {
          std::copy(from + begin, from + begin + count, to.begin() + begin);
          std::copy(from + begin, from + begin + count, kept.begin() + begin);
        };
        copy(requested_now, requested, last->requested);
        copy(activation_now, activation, last->activation);
        copy(active_now, active, last->active);
      }
    }
  } else {
    levels_full = true;
    std::copy(requested_now, requested_now + behaviours, requested.begin());
    std::copy(activation_now, activation_now + behaviours, activation.begin());
    std::copy(active_now, active_now + behaviours, active.begin());
    if (last != nullptr) {
      std::copy(requested_now, requested_now + behaviours, last->requested.begin());
      std::copy(activation_now, activation_now + behaviours, last->activation.begin());
      std::copy(active_now, active_now + behaviours, last->active.begin());
    }
  }
  const auto actuators = static_cast<std::uint32_t>(layout.actuators.size());
  if (actuators > 0 && layout.plain_values) {
    const auto* values =
        static_cast<const std::byte*>(manager.actuator_value(0)) - layout.actuators[0].offset;
    std::memcpy(values_.get(), values, layout.value_bytes);
  }
  for (std::uint32_t a = 0; a < actuators; ++a) {
    written[a] = manager.actuator_written(a) ? 1 : 0;
    if (layout.plain_values) continue;
    const auto& actuator = layout.actuators[a];
    void* to = values_.get() + actuator.offset;
    const void* from = manager.actuator_value(a);
    // A string longer than the copy's reserve would allocate.
    if (!grow && *actuator.type->cpp_type == typeid(std::string) &&
        static_cast<const std::string*>(from)->size() >
            static_cast<const std::string*>(to)->capacity()) {
      return false;
    }
    actuator.type->assign(to, from);
  }
  std::uint32_t args = 0;
  std::uint32_t queued = 0;
  std::uint32_t event_index = 0;
  std::uint32_t event_arg = 0;
  for (std::size_t c = 0; c < machines.size(); ++c) {
    const Controller& controller = *program.controllers[c];
    Machine& machine = machines[c];
    machine.cycle = controller.cycle();
    machine.status = controller.status();
    machine.current = controller.current_state_index();
    machine.planned = controller.current_planned();
    machine.args_begin = args;
    for (const auto& [param, value] : controller.current_args()) {
      if (args == current_args.size()) {
        if (!grow) return false;
        current_args.emplace_back();
      }
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
    for (std::size_t i = 0; i < controller.queue_size(); ++i) {
      queue[queued++] = controller.queued_state(i);
    }
    machine.queue_count = queued - machine.queue_begin;
    machine.events_begin = event_index;
    for (std::size_t e = 0; e < controller.event_count(); ++e) {
      Controller::Event event = controller.events()[e];
      const auto* first = controller.event_args(event);
      event.args_begin = event_arg;
      for (std::uint32_t i = 0; i < event.args_count; ++i) event_args[event_arg++] = first[i];
      events[event_index++] = event;
    }
    machine.events_count = event_index - machine.events_begin;
  }
  report_count = manager.event_count();
  texts.clear();
  for (std::size_t e = 0; e < report_count; ++e) {
    const auto& event = manager.event(e);
    const auto size = std::strlen(event.text);
    if (!grow && texts.size() + size > texts.capacity()) return false;
    reports[e] = {event.source, static_cast<std::uint32_t>(texts.size()),
                  static_cast<std::uint32_t>(size)};
    texts.append(event.text, size);
  }
  return true;
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
    out += step.written[a] != 0 ? R"(, "written": true})" : R"(, "written": false})";
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
  if (step.report_count > 0) {
    out += R"(, "reported": [)";
    for (std::size_t e = 0; e < step.report_count; ++e) {
      const auto& report = step.reports[e];
      if (e > 0) out += ", ";
      out += R"({"by": )";
      append_name(source_name(layout, report.source), out);
      out += R"(, "text": )";
      append_json_string(step.texts.substr(report.text_begin, report.text_size), out);
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
      out += step.written[a] != 0 ? R"(, "written": true})" : R"(, "written": false})";
    }
  }
  out += "}";
  // What interface code reported is an input too: replay reports it again, in the output pass,
  // from the layer that reported it.
  bool reported = false;
  const auto behaviours = layout.behaviours.size();
  for (std::size_t e = 0; e < step.report_count; ++e) {
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
    append_json_string(step.texts.substr(report.text_begin, report.text_size), out);
    out += "}";
  }
  if (reported) out += "]";
  out += "}";
}

}  // namespace arbiter::detail

#include "arbiter/trace.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>

namespace arbiter {

namespace {

void append_name(const std::string& name, std::string& out) {
  detail::append_json_string(name, out);
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

}  // namespace

std::string event_text(const Controller& controller, const Controller::Event& event) {
  const char* verb = event.kind == Controller::Event::Kind::kActivate  ? "activate"
                     : event.kind == Controller::Event::Kind::kExecute ? "execute"
                                                                       : "deactivate";
  return fmt::format("{} {}", verb, controller.states()[event.state].name);
}

const char* cause_name(Controller::EndCause cause) {
  switch (cause) {
    case Controller::EndCause::kNone:
      return "";
    case Controller::EndCause::kProceeded:
      return "proceeded";
    case Controller::EndCause::kQueueEmpty:
      return "queue_empty";
    case Controller::EndCause::kPreempted:
      return "preempted";
    case Controller::EndCause::kGoTo:
      return "go_to";
    case Controller::EndCause::kTerminated:
      return "terminated";
    case Controller::EndCause::kError:
      return "error";
    case Controller::EndCause::kRestarted:
      return "restarted";
    case Controller::EndCause::kDropped:
      return "reloaded";
  }
  return "";
}

StateEnd state_end(const Controller& controller, const Controller::Event& event) {
  const auto name = [&](std::uint32_t state) {
    return state == kUnbound ? std::string() : controller.states()[state].name;
  };
  StateEnd end;
  end.state = name(event.state);
  end.cause = cause_name(event.cause);
  if (event.cause == Controller::EndCause::kTerminated) {
    end.by = name(event.other);
  } else {
    end.to = name(event.other);
  }
  if (event.preempt != kUnbound) end.preempt = event.preempt;
  end.proceeded = event.proceeded;
  return end;
}

std::string end_text(const StateEnd& end, std::uint64_t cycle) {
  if (end.cause == "proceeded") return "proceeded";
  if (end.cause == "queue_empty") return "proceeded, queue empty";
  if (end.cause == "go_to") return "go_to " + end.to;
  if (end.cause == "preempted") {
    std::string text = end.to.empty() ? "pre-empted, nothing planned" : "pre-empted by " + end.to;
    if (end.preempt >= 0) text += fmt::format(" (preempt: at cycle {})", cycle);
    if (end.proceeded) text += "; it had asked to proceed";
    return text;
  }
  if (end.cause == "terminated") {
    if (end.by.empty()) return "terminated by its owner";
    return end.by == end.state ? "terminated" : "terminated by " + end.by;
  }
  if (end.cause == "error") return "the machine stopped with an error";
  if (end.cause == "restarted") return "the machine restarted";
  if (end.cause == "reloaded") return "dropped by a reload";
  return end.cause;
}

namespace {

void append_param_json(const ParamValue& value, bool exact, std::string& out) {
  struct Visitor {
    std::string& out;
    bool exact;
    void number(double v) const {
      if (exact) {
        detail::append_json_number(v, out);
      } else {
        out += short_number(v);
      }
    }
    void operator()(bool v) const { out += v ? "true" : "false"; }
    void operator()(std::int64_t v) const { fmt::format_to(std::back_inserter(out), "{}", v); }
    void operator()(double v) const { number(v); }
    void operator()(const std::string& v) const { detail::append_json_string(v, out); }
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
        detail::append_json_string(v[i], out);
      }
      out += ']';
    }
    // A list of planned states (scripted's append:) is shown by what it says, not its structure.
    void operator()(const Node& v) const { detail::append_json_string(v.describe(), out); }
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

template <typename Args, typename ValueOf>
ParamTexts merged_params(const CompiledState& state, const std::vector<Param>* planned,
                         const Args& args, ValueOf value_of, bool exact) {
  ParamTexts out;
  const auto& specs = state.cls->params;
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
  for (const auto& arg : args) set(specs[arg.first].name, value_of(arg.second));
  return out;
}

}  // namespace

std::string param_value_text(const ParamValue& value) {
  std::string out;
  append_param_json(value, true, out);
  return out;
}

std::string short_number(double value) {
  std::string out;
  if (std::isfinite(value)) value = std::strtod(fmt::format("{:.4g}", value).c_str(), nullptr);
  detail::append_json_number(value, out);
  return out;
}

ParamTexts event_params(const Controller& controller, const Controller::Event& event, bool exact) {
  if (event.kind == Controller::Event::Kind::kExecute) return {};
  std::vector<std::pair<std::uint32_t, Arg::Value>> args;
  const auto* first = controller.event_args(event);
  for (std::uint32_t i = 0; i < event.args_count; ++i) {
    args.emplace_back(first[i].param, first[i].value);
  }
  return merged_params(
      controller.states()[event.state], event.planned, args,
      [](const Arg::Value& value) {
        return std::visit([](auto v) { return ParamValue(v); }, value);
      },
      exact);
}

ParamTexts current_params(const Controller& controller) {
  const auto state = controller.current_state_index();
  if (state == kUnbound) return {};
  return merged_params(
      controller.states()[state], controller.current_planned(), controller.current_args(),
      [](const ParamValue& value) { return value; }, true);
}

std::string params_text(const ParamTexts& params) {
  if (params.empty()) return {};
  std::string out = "{";
  for (const auto& [name, value] : params) {
    if (out.size() > 1) out += ", ";
    out += name + ": " + value;
  }
  return out + "}";
}

std::string trace_header(const Program& program) {
  std::string out = R"({"arbiter_trace": 1, "name": )";
  append_name(program.name, out);
  out += R"(, "layers": [)";
  for (std::size_t l = 0; l < program.layers.size(); ++l) {
    const auto& layer = program.layers[l];
    if (l > 0) out += ", ";
    out += R"({"name": )";
    append_name(layer.name, out);
    out += R"(, "order": [)";
    for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
      if (b > layer.behaviour_begin) out += ", ";
      append_name(program.behaviours[b].name, out);
    }
    out += "]}";
  }
  out += "]}";
  return out;
}

void append_step_record(const Manager& manager, std::string& out) {
  const Program& program = manager.program();
  fmt::format_to(std::back_inserter(out), R"({{"step": {}, )", manager.steps());
  if (manager.in_safe_pass()) out += R"("safe": true, )";
  if (manager.timed()) {
    out += R"("t": )";
    detail::append_json_number(manager.step_time(), out);
    out += R"(, "duration": )";
    detail::append_json_number(manager.step_duration(), out);
    out += ", ";
  }
  out += R"("layers": {)";
  std::vector<std::uint32_t> inhibitors;
  for (std::size_t l = 0; l < program.layers.size(); ++l) {
    const auto& layer = program.layers[l];
    if (l > 0) out += ", ";
    append_name(layer.name, out);
    out += ": {";
    for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
      if (b > layer.behaviour_begin) out += ", ";
      append_name(program.behaviours[b].name, out);
      out += R"(: {"requested": )";
      detail::append_json_number(manager.requested(b), out);
      out += R"(, "activation": )";
      detail::append_json_number(manager.activation(b), out);
      out += manager.active(b) ? R"(, "active": true)" : R"(, "active": false)";
      out += R"(, "inhibited_by": [)";
      bool first = true;
      program.inhibitions.closed(b, inhibitors);
      for (const auto inhibitor : inhibitors) {
        if (manager.activation(inhibitor) <= 0.0) continue;
        if (!first) out += ", ";
        first = false;
        append_name(program.behaviours[inhibitor].name, out);
      }
      out += "]}";
    }
    out += "}";
  }
  out += R"(}, "actuators": {)";
  for (std::uint32_t a = 0; a < program.actuators.size(); ++a) {
    if (a > 0) out += ", ";
    append_name(program.actuators[a].name, out);
    out += R"(: {"value": )";
    program.actuators[a].type->append_json(manager.actuator_value(a), out);
    out += manager.actuator_written(a) ? R"(, "written": true})" : R"(, "written": false})";
  }
  out += R"(}, "controllers": {)";
  for (std::size_t c = 0; c < program.controllers.size(); ++c) {
    const Controller& controller = *program.controllers[c];
    if (c > 0) out += ", ";
    append_name(controller.name(), out);
    fmt::format_to(std::back_inserter(out), R"(: {{"cycle": {}, "state": )", controller.cycle());
    const auto current = controller.current_state();
    if (current.empty()) {
      out += "null";
    } else {
      append_name(std::string(current), out);
    }
    out += R"(, "queue": [)";
    for (std::size_t i = 0; i < controller.queue_size(); ++i) {
      if (i > 0) out += ", ";
      append_name(std::string(controller.queued(i)), out);
    }
    out += "]";
    append_params(current_params(controller), out);
    out += R"(, "events": [)";
    bool ended = false;
    for (std::size_t e = 0; e < controller.event_count(); ++e) {
      const auto& event = controller.events()[e];
      if (e > 0) out += ", ";
      append_name(event_text(controller, event), out);
      ended = ended || event.kind == Controller::Event::Kind::kDeactivate;
    }
    out += "]";
    if (ended) {
      out += R"(, "ended": [)";
      bool first = true;
      for (std::size_t e = 0; e < controller.event_count(); ++e) {
        const auto& event = controller.events()[e];
        if (event.kind != Controller::Event::Kind::kDeactivate) continue;
        if (!first) out += ", ";
        first = false;
        append_end(state_end(controller, event), event_params(controller, event), out);
      }
      out += "]";
    }
    out += R"(, "status": ")";
    out += to_string(controller.status());
    out += "\"}";
  }
  out += "}";
  // What behaviour and interface code reported (StepContext::report): only in steps that have
  // some, so that traces of graphs that report nothing keep the exact shape of docs/semantics.md,
  // "The trace".
  if (manager.event_count() > 0) {
    out += R"(, "reported": [)";
    for (std::size_t e = 0; e < manager.event_count(); ++e) {
      const auto& event = manager.event(e);
      if (e > 0) out += ", ";
      out += R"({"by": )";
      append_name(manager.event_source(event), out);
      out += R"(, "text": )";
      detail::append_json_string(event.text, out);
      out += "}";
    }
    out += "]";
  }
  out += "}";
}

void TraceWriter::on_start(const Manager& manager) {
  out_ << trace_header(manager.program()) << '\n';
}

void TraceWriter::on_safe(const Manager& manager) {
  on_step(manager);
}

void TraceWriter::on_step(const Manager& manager) {
  line_.clear();
  append_step_record(manager, line_);
  line_ += '\n';
  out_ << line_;
}

std::string reload_header(const Manager& manager) {
  std::string out = trace_header(manager.program());
  constexpr std::string_view kVersion = R"({"arbiter_trace": 1)";
  out.insert(kVersion.size(), fmt::format(R"(, "reload": {}, "after_step": {})", manager.reloads(),
                                          manager.steps()));
  return out;
}

void TraceWriter::on_reload(const Manager& manager) {
  out_ << reload_header(manager) << '\n';
}

void TraceWriter::on_finish(const Manager&) {
  out_.flush();
}

}  // namespace arbiter

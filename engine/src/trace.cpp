#include "arbiter/trace.hpp"

#include <fmt/format.h>

namespace arbiter {

namespace {

void append_name(const std::string& name, std::string& out) {
  detail::append_json_string(name, out);
}

}  // namespace

std::string event_text(const Controller& controller, const Controller::Event& event) {
  const char* verb = event.kind == Controller::Event::Kind::kActivate  ? "activate"
                     : event.kind == Controller::Event::Kind::kExecute ? "execute"
                                                                       : "deactivate";
  return fmt::format("{} {}", verb, controller.states()[event.state].name);
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
    out += R"(], "events": [)";
    for (std::size_t e = 0; e < controller.event_count(); ++e) {
      const auto& event = controller.events()[e];
      if (e > 0) out += ", ";
      append_name(event_text(controller, event), out);
    }
    out += R"(], "status": ")";
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

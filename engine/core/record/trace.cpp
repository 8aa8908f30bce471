#include "arbiter/trace.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>

#include "core/record/step_record.hpp"

namespace arbiter {

namespace {

void append_name(const std::string& name, std::string& out) {
  detail::append_json_string(name, out);
}

}  // namespace

std::string event_text(const Controller& controller, const Controller::Event& event) {
  return fmt::format("{} {}", detail::event_verb(event.kind),
                     controller.states()[event.state].name);
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
  return detail::make_state_end(event, [&](std::uint32_t state) -> const std::string& {
    return controller.states()[state].name;
  });
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

std::string param_value_text(const ParamValue& value) {
  std::string out;
  detail::append_param_json(value, true, out);
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
  std::vector<std::pair<std::uint32_t, ArgValue>> args;
  const auto* first = controller.event_args(event);
  for (std::uint32_t i = 0; i < event.args_count; ++i) {
    args.emplace_back(first[i].param, first[i].value);
  }
  return detail::merged_params(
      *controller.states()[event.state].cls, event.planned, args,
      [](const ArgValue& value) { return std::visit([](auto v) { return ParamValue(v); }, value); },
      exact);
}

ParamTexts current_params(const Controller& controller) {
  const auto state = controller.current_state_index();
  if (state == kNoState) return {};
  return detail::merged_params(
      *controller.states()[state].cls, controller.current_planned(), controller.current_args(),
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
  const detail::StepLayout layout(manager.program());
  detail::SnapshotBlocks storage;
  detail::append_step_record(layout, detail::capture_growing(manager, layout, storage), out);
}

struct StepRecordFormatter::State {
  explicit State(const Program& program) : layout(program) {}
  detail::StepLayout layout;
  detail::SnapshotBlocks storage;
};

StepRecordFormatter::StepRecordFormatter() = default;
StepRecordFormatter::~StepRecordFormatter() = default;

void StepRecordFormatter::reset(const Program& program) {
  state_ = std::make_unique<State>(program);
}

void StepRecordFormatter::append(const Manager& manager, std::string& out) {
  if (!state_) reset(manager.program());
  detail::append_step_record(
      state_->layout, detail::capture_growing(manager, state_->layout, state_->storage), out);
}

void TraceWriter::on_start(const Manager& manager) {
  records_.reset(manager.program());
  out_ << trace_header(manager.program()) << '\n';
}

void TraceWriter::on_safe(const Manager& manager) {
  on_step(manager);
}

void TraceWriter::on_step(const Manager& manager) {
  line_.clear();
  records_.append(manager, line_);
  line_ += '\n';
  out_ << line_;
}

std::string reload_header(const Manager& manager) {
  return reload_header(trace_header(manager.program()), manager.reloads(), manager.steps());
}

std::string reload_header(std::string trace_header, std::uint64_t reload,
                          std::uint64_t after_step) {
  constexpr std::string_view kVersion = R"({"arbiter_trace": 1)";
  trace_header.insert(kVersion.size(),
                      fmt::format(R"(, "reload": {}, "after_step": {})", reload, after_step));
  return trace_header;
}

void TraceWriter::on_reload(const Manager& manager) {
  records_.reset(manager.program());
  out_ << reload_header(manager) << '\n';
}

void TraceWriter::on_finish(const Manager&) {
  out_.flush();
}

}  // namespace arbiter

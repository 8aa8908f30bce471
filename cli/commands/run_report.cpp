#include "commands/run_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "arbiter/trace.hpp"

namespace arbiter::cli {

namespace {

std::string inhibitors_of(const Manager& manager, std::uint32_t behaviour) {
  const Program& program = manager.program();
  std::string names;
  for (const auto inhibitor : program.inhibitions.closed(behaviour)) {
    if (manager.activation(inhibitor) <= 0.0) continue;
    names += (names.empty() ? "" : ", ") + program.behaviours[inhibitor].name;
  }
  return names;
}

}  // namespace

void RunReport::key_by_index(const Program& program) {
  keys_.clear();
  for (const auto& behaviour : program.behaviours) {
    keys_.push_back(program.layers[behaviour.layer].name + "/" + behaviour.name);
  }
}

void RunReport::on_start(const Manager& manager) {
  const Program& program = manager.program();
  was_active_.assign(program.behaviours.size(), 0);
  active_steps_.assign(program.behaviours.size(), 0);
  controller_status_.assign(program.controllers.size(), ControllerStatus::kRunning);
  key_by_index(program);
  if (quiet_) return;
  print(fmt::format("running {}: {} layers, {} behaviours, {} state machines\n", program.name,
                    program.layers.size(), program.behaviours.size(), program.controllers.size()));
}

void RunReport::on_step(const Manager& manager) {
  const Program& program = manager.program();
  for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
    const bool active = manager.active(b);
    if (active) ++active_steps_[b];
    if (active == (was_active_[b] != 0)) continue;
    was_active_[b] = active ? 1 : 0;
    if (quiet_) continue;
    const auto& behaviour = program.behaviours[b];
    const auto& layer = program.layers[behaviour.layer].name;
    if (active) {
      print(fmt::format("step {:>4}  {}/{} activated (activation {:.3g})\n", manager.steps(), layer,
                        behaviour.name, manager.activation(b)));
    } else if (manager.requested(b) > 0.0) {
      print(fmt::format("step {:>4}  {}/{} inhibited by {}\n", manager.steps(), layer,
                        behaviour.name, inhibitors_of(manager, b)));
    } else {
      print(fmt::format("step {:>4}  {}/{} deactivated (requests 0)\n", manager.steps(), layer,
                        behaviour.name));
    }
  }
  report_story(manager);
  // Each step's lines go out at once, also into a pipe or a file (`--watch` is watched live);
  // a step that printed nothing has nothing to flush.
  if (!quiet_) out_.flush();
}

void RunReport::on_reload(const Manager& manager) {
  const Program& program = manager.program();
  std::map<std::string, std::uint64_t> counted;
  for (std::size_t b = 0; b < keys_.size(); ++b) counted[keys_[b]] = active_steps_[b];
  key_by_index(program);
  active_steps_.assign(program.behaviours.size(), 0);
  was_active_.assign(program.behaviours.size(), 0);
  for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
    if (const auto found = counted.find(keys_[b]); found != counted.end()) {
      active_steps_[b] = found->second;
      counted.erase(found);
    } else if (const auto removed = removed_steps_.find(keys_[b]);
               removed != removed_steps_.end()) {
      // Added back after a reload removed it: one behaviour to the summary, its steps before
      // counted with those to come, not listed again as removed.
      active_steps_[b] = removed->second;
      removed_steps_.erase(removed);
    }
    // The manager carries activity over for what it keeps: a change shows from the next step.
    was_active_[b] = manager.active(b) ? 1 : 0;
  }
  for (const auto& [key, steps] : counted) removed_steps_[key] += steps;
  controller_status_.clear();
  for (const auto& controller : program.controllers) {
    controller_status_.push_back(controller->status());
  }
  if (quiet_) return;
  print(fmt::format("step {:>4}  reloaded {}: {} layers, {} behaviours, {} state machines\n",
                    manager.steps(), program.name, program.layers.size(), program.behaviours.size(),
                    program.controllers.size()));
}

void RunReport::report_story(const Manager& manager) {
  const Program& program = manager.program();
  // What the state machines did and what code reported, in the order it happened: an interface
  // layer's report in the input pass comes before the state a behaviour then planned.
  struct Line {
    std::uint64_t order;  // sequence × 2, + 1 for a status change after the last event
    std::string text;
    bool reported;
  };
  std::vector<Line> lines;
  const auto step = manager.steps();
  for (std::size_t c = 0; c < program.controllers.size(); ++c) {
    const Controller& controller = *program.controllers[c];
    const bool status_changed = controller.status() != controller_status_[c];
    controller_status_[c] = controller.status();
    if (quiet_) continue;
    std::uint64_t last = std::numeric_limits<std::uint32_t>::max();
    for (std::size_t e = 0; e < controller.event_count(); ++e) {
      const auto& event = controller.events()[e];
      last = event.sequence;
      if (event.kind == Controller::Event::Kind::kExecute) continue;
      const std::string& state = controller.states()[event.state].name;
      std::string params = params_text(event_params(controller, event, false));
      if (!params.empty()) params.insert(0, " ");
      if (event.kind == Controller::Event::Kind::kDeactivate) {
        lines.push_back(
            {2 * std::uint64_t{event.sequence},
             fmt::format("step {:>4}  {}: {}{} ended ({})\n", step, controller.name(), state,
                         params, end_text(state_end(controller, event), controller.cycle())),
             false});
        continue;
      }
      std::string queue;
      for (std::size_t i = 0; i < controller.queue_size(); ++i) {
        queue += fmt::format("{}{}", i == 0 ? "" : ", ", controller.queued(i));
      }
      lines.push_back(
          {2 * std::uint64_t{event.sequence},
           fmt::format("step {:>4}  {}: {}{} (cycle {}; queued: {})\n", step, controller.name(),
                       state, params, controller.cycle(), queue.empty() ? "nothing" : queue),
           false});
    }
    if (!status_changed) continue;
    const std::string text = controller.status() == ControllerStatus::kError
                                 ? fmt::format("step {:>4}  {}: error: {}\n", step,
                                               controller.name(), controller.error())
                                 : fmt::format("step {:>4}  {}: {}\n", step, controller.name(),
                                               to_string(controller.status()));
    lines.push_back({2 * last + 1, text, false});
  }
  for (std::size_t e = 0; e < manager.event_count(); ++e) {
    const auto& event = manager.event(e);
    std::string text = fmt::format("{}: {}", manager.event_source(event), event.text);
    ++event_counts_[text];
    if (quiet_) continue;
    lines.push_back({2 * std::uint64_t{event.sequence}, std::move(text), true});
  }
  std::stable_sort(lines.begin(), lines.end(),
                   [](const Line& a, const Line& b) { return a.order < b.order; });
  for (const auto& line : lines) {
    if (line.reported) {
      print_event(step, line.text);
    } else {
      print(line.text);
    }
  }
}

void RunReport::print(const std::string& line) {
  flush_repeats();
  last_event_.clear();
  out_ << line;
}

void RunReport::print_event(std::uint64_t step, const std::string& event) {
  if (event == last_event_) {
    if (repeats_++ == 0) first_repeat_ = step;
    last_repeat_ = step;
    return;
  }
  print(fmt::format("step {:>4}  {}\n", step, event));
  last_event_ = event;
}

void RunReport::flush_repeats() {
  if (repeats_ == 0) return;
  out_ << fmt::format("step {:>4}  {} again ", last_repeat_, last_event_)
       << (repeats_ == 1
               ? std::string("(x1)\n")
               : fmt::format("(x{}, steps {}-{})\n", repeats_, first_repeat_, last_repeat_));
  repeats_ = 0;
}

void RunReport::on_safe(const Manager& manager) {
  if (quiet_) return;
  const Program& program = manager.program();
  std::string values;
  for (std::uint32_t a = 0; a < program.actuators.size(); ++a) {
    if (!manager.actuator_written(a)) continue;
    std::string value;
    program.actuators[a].type->append_json(manager.actuator_value(a), value);
    values +=
        fmt::format("{}{} = {}", values.empty() ? "" : ", ", program.actuators[a].name, value);
  }
  const bool single_step = manager.steps() == last_safe_step_ + 1 && last_safe_step_ > 0;
  last_safe_step_ = manager.steps();
  if (single_step && values == last_safe_) return;
  print(fmt::format("step {:>4}  safe values output: {}\n", manager.steps(), values));
  out_ << std::flush;
  last_safe_ = std::move(values);
}

void RunReport::on_finish(const Manager& manager) {
  if (quiet_) return;
  const Program& program = manager.program();
  print(fmt::format("\n{} steps.\n", manager.steps()));
  if (manager.safe_passes() > 0) {
    print(fmt::format("Safe values output {} time{} (the last after step {}).\n",
                      manager.safe_passes(), manager.safe_passes() == 1 ? "" : "s",
                      manager.steps()));
  }
  for (const auto& controller : program.controllers) {
    print(fmt::format("State machine {}: {} after {} cycles.\n", controller->name(),
                      to_string(controller->status()), controller->cycle()));
  }
  for (const auto& [event, count] : event_counts_) {
    print(fmt::format("{} ({} time{})\n", event, count, count == 1 ? "" : "s"));
  }
  // Those a reload removed are listed too when it removed them all.
  if (program.behaviours.empty() && removed_steps_.empty()) return;
  print("Active steps per behaviour:\n");
  for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
    print(fmt::format(
        "  {:<32} {:>6}  (final activation {:.3g})\n",
        program.layers[program.behaviours[b].layer].name + "/" + program.behaviours[b].name,
        active_steps_[b], manager.activation(b)));
  }
  for (const auto& [key, steps] : removed_steps_) {
    print(fmt::format("  {:<32} {:>6}  (removed by a reload)\n", key, steps));
  }
}

}  // namespace arbiter::cli

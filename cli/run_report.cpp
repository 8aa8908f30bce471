#include "run_report.hpp"

#include <fmt/format.h>

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
  report_controllers(manager);
  for (std::size_t e = 0; e < manager.event_count(); ++e) {
    const auto& event = manager.event(e);
    ++event_counts_[fmt::format("{}: {}", manager.event_source(event), event.text)];
    if (quiet_) continue;
    print_event(manager.steps(), fmt::format("{}: {}", manager.event_source(event), event.text));
  }
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
    const auto found = counted.find(keys_[b]);
    if (found != counted.end()) {
      active_steps_[b] = found->second;
      counted.erase(found);
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

void RunReport::report_controllers(const Manager& manager) {
  const Program& program = manager.program();
  for (std::size_t c = 0; c < program.controllers.size(); ++c) {
    const Controller& controller = *program.controllers[c];
    const bool status_changed = controller.status() != controller_status_[c];
    controller_status_[c] = controller.status();
    if (quiet_) continue;
    for (std::size_t e = 0; e < controller.event_count(); ++e) {
      const auto& event = controller.events()[e];
      if (event.kind != Controller::Event::Kind::kActivate) continue;
      std::string queue;
      for (std::size_t i = 0; i < controller.queue_size(); ++i) {
        queue += fmt::format("{}{}", i == 0 ? "" : ", ", controller.queued(i));
      }
      print(fmt::format("step {:>4}  {}: {} (cycle {}; queued: {})\n", manager.steps(),
                        controller.name(), controller.states()[event.state].name,
                        controller.cycle(), queue.empty() ? "nothing" : queue));
    }
    if (!status_changed) continue;
    if (controller.status() == ControllerStatus::kError) {
      print(fmt::format("step {:>4}  {}: error: {}\n", manager.steps(), controller.name(),
                        controller.error()));
    } else {
      print(fmt::format("step {:>4}  {}: {}\n", manager.steps(), controller.name(),
                        to_string(controller.status())));
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
  print(fmt::format("step {:>4}  safe values output: {}\n", manager.steps(), values));
  out_ << std::flush;
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
  if (program.behaviours.empty()) return;
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

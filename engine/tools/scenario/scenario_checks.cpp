#include "tools/scenario/scenario_checks.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "arbiter/controller.hpp"
#include "arbiter/trace.hpp"
#include "core/compile/controller_builder.hpp"

namespace arbiter {
namespace {

std::string qualified(const Program& program, std::uint32_t behaviour) {
  const auto& compiled = program.behaviours[behaviour];
  return fmt::format("{}/{}", program.layers[compiled.layer].name, compiled.name);
}

// Whether two JSON texts say the same, numbers compared within `tolerance`.
bool same_json(std::string_view a, std::string_view b, double tolerance) {
  const auto number_start = [](char c) { return (c >= '0' && c <= '9') || c == '-'; };
  std::size_t i = 0;
  std::size_t j = 0;
  while (i < a.size() && j < b.size()) {
    if (number_start(a[i]) && number_start(b[j])) {
      const std::string x(a.substr(i, a.find_first_of(",] }", i) - i));
      const std::string y(b.substr(j, b.find_first_of(",] }", j) - j));
      char* x_end = nullptr;
      char* y_end = nullptr;
      const double u = std::strtod(x.c_str(), &x_end);
      const double v = std::strtod(y.c_str(), &y_end);
      if (!(std::fabs(u - v) <= tolerance)) return false;
      i += static_cast<std::size_t>(x_end - x.c_str());
      j += static_cast<std::size_t>(y_end - y.c_str());
      continue;
    }
    if (a[i] != b[j]) return false;
    ++i;
    ++j;
  }
  return i == a.size() && j == b.size();
}

std::string level_text(double level) {
  return fmt::format("{:.6g}", level);
}

}  // namespace

bool ExpectationChecks::resolve(const Scenario& scenario, const Program& program,
                                Diagnostics& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  std::vector<std::string> behaviour_names;
  for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
    behaviour_names.push_back(qualified(program, b));
  }
  const auto find_behaviour = [&](const ScenarioName& name) -> std::optional<std::uint32_t> {
    const auto slash = name.text.find('/');
    std::vector<std::uint32_t> matches;
    for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
      const bool same = slash == std::string::npos ? program.behaviours[b].name == name.text
                                                   : behaviour_names[b] == name.text;
      if (same) matches.push_back(b);
    }
    if (matches.size() == 1) return matches.front();
    if (matches.empty()) {
      // Each behaviour once, by the name that is enough to name it.
      std::vector<std::string> known;
      for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
        const auto& name = program.behaviours[b].name;
        const bool shared =
            std::count_if(program.behaviours.begin(), program.behaviours.end(),
                          [&](const auto& other) { return other.name == name; }) > 1;
        known.push_back(shared ? behaviour_names[b] : name);
      }
      diagnostics
          .error(name.location, "unknown-behaviour",
                 fmt::format("'{}' is not a behaviour of config '{}'", name.text, program.name))
          .unknown_name(name.text, known);
      return std::nullopt;
    }
    std::vector<std::string> choices;
    for (const auto b : matches) choices.push_back(behaviour_names[b]);
    diagnostics
        .error(name.location, "ambiguous-name",
               fmt::format("'{}' is ambiguous: {} layers have a behaviour of that name", name.text,
                           matches.size()))
        .notes.push_back(fmt::format("write one of: {}", fmt::join(choices, ", ")));
    return std::nullopt;
  };
  for (const auto& expectation : scenario.expectations) {
    Resolved resolved;
    resolved.expectation = &expectation;
    switch (expectation.kind) {
      case Expectation::Kind::kActive:
      case Expectation::Kind::kInactive:
      case Expectation::Kind::kActivation:
      case Expectation::Kind::kRequested:
      case Expectation::Kind::kInhibitedBy: {
        const auto behaviour = find_behaviour(expectation.target);
        if (!behaviour) continue;
        resolved.index = *behaviour;
        for (const auto& inhibitor : expectation.names) {
          if (!find_behaviour({inhibitor, expectation.target.location})) resolved.index = kNoIndex;
        }
        if (resolved.index == kNoIndex) continue;
        break;
      }
      case Expectation::Kind::kActuator: {
        const auto actuator = program.find_actuator(expectation.target.text);
        if (!actuator) {
          std::vector<std::string> known;
          for (const auto& compiled : program.actuators) known.push_back(compiled.name);
          diagnostics
              .error(expectation.target.location, "unknown-actuator",
                     fmt::format("'{}' is not an actuator of config '{}'", expectation.target.text,
                                 program.name))
              .unknown_name(expectation.target.text, known);
          continue;
        }
        const ValueType& type = *program.actuators[*actuator].type;
        ValueBox expected(type);
        std::string shape;
        if (!type.from_node(expectation.value, expected.data(), shape)) {
          diagnostics.error(
              expectation.value.location(), "wrong-type",
              fmt::format("actuator '{}' has type {}: the expected value must be "
                          "{}, found {}",
                          expectation.target.text, type.name, shape, expectation.value.describe()));
          continue;
        }
        resolved.index = *actuator;
        type.append_json(expected.data(), resolved.expected_json);
        break;
      }
      case Expectation::Kind::kState:
      case Expectation::Kind::kQueue: {
        std::vector<std::string> known;
        resolved.index = kNoIndex;
        for (std::uint32_t c = 0; c < program.controllers.size(); ++c) {
          known.push_back(program.controllers[c]->name());
          if (program.controllers[c]->name() == expectation.target.text) resolved.index = c;
        }
        if (resolved.index == kNoIndex) {
          diagnostics
              .error(expectation.target.location, "unknown-machine",
                     fmt::format("'{}' is not a state machine of config '{}'",
                                 expectation.target.text, program.name))
              .unknown_name(expectation.target.text, known, "the config has no state machines");
          continue;
        }
        const Controller& controller = *program.controllers[resolved.index];
        std::vector<std::string> states;
        for (const auto& state : controller.states()) states.push_back(state.name);
        std::vector<std::string> named = expectation.names;
        if (expectation.kind == Expectation::Kind::kState) named = {expectation.state};
        bool ok = true;
        for (const auto& state : named) {
          if (auto found = find_state(controller, state)) {
            resolved.state = *found;
            continue;
          }
          diagnostics
              .error(expectation.target.location, "unknown-state",
                     fmt::format("state machine '{}' has no state '{}'", controller.name(), state))
              .unknown_name(state, states);
          ok = false;
        }
        if (!ok) continue;
        break;
      }
    }
    resolved_.push_back(std::move(resolved));
  }
  return diagnostics.error_count() == errors;
}

void ExpectationChecks::follow_state(Resolved& resolved, const Manager& manager) {
  const Controller& controller = *manager.program().controllers[resolved.index];
  for (std::size_t i = 0; i < controller.event_count(); ++i) {
    const Controller::Event& event = controller.events()[i];
    if (event.state != resolved.state) continue;
    if (event.kind == Controller::Event::Kind::kActivate) {
      resolved.started = manager.steps();
      resolved.ended = 0;
    } else if (event.kind == Controller::Event::Kind::kDeactivate) {
      resolved.ended = manager.steps();
      resolved.ended_cycle = controller.cycle();
      resolved.ending = event;
    }
  }
}

// How the expected state's last run went: "; 'dive' ran from step 201 and ended at step 230:
// proceeded", or "; 'dive' has not run yet (2nd in the queue)".
std::string ExpectationChecks::state_history(const Resolved& resolved,
                                             const Manager& manager) const {
  const Controller& controller = *manager.program().controllers[resolved.index];
  const std::string& name = controller.states()[resolved.state].name;
  if (resolved.ended != 0) {
    return fmt::format("; '{}' ran from step {} and ended at step {}: {}", name, resolved.started,
                       resolved.ended,
                       end_text(state_end(controller, resolved.ending), resolved.ended_cycle));
  }
  if (resolved.started != 0) return {};
  for (std::size_t i = 0; i < controller.queue_size(); ++i) {
    if (controller.queued_state(i) == resolved.state) {
      return fmt::format("; '{}' has not run yet (it is number {} in the queue)", name, i + 1);
    }
  }
  return fmt::format("; '{}' has not run yet, and is not in the queue", name);
}

void ExpectationChecks::check(const Manager& manager, double tolerance) {
  const std::uint64_t step = manager.steps();
  for (auto& resolved : resolved_) {
    if (!resolved.failed && resolved.expectation->kind == Expectation::Kind::kState) {
      follow_state(resolved, manager);
    }
  }
  for (std::size_t e = 0; e < resolved_.size(); ++e) {
    Resolved& resolved = resolved_[e];
    const Expectation& expectation = *resolved.expectation;
    if (resolved.failed || step < expectation.first_step || step > expectation.last_step) continue;
    std::string got = check_one(resolved, manager, tolerance);
    if (got.empty()) continue;
    resolved.failed = true;
    Failure failure;
    failure.expectation = e;
    failure.step = step;
    failure.message = std::move(got);
    const Program& program = manager.program();
    switch (expectation.kind) {
      case Expectation::Kind::kActuator:
        for (std::uint32_t s = program.actuator_slot_begin[resolved.index];
             s < program.actuator_slot_begin[resolved.index + 1]; ++s) {
          const auto owner = program.slots[program.actuator_slots[s]].owner;
          // The writers whose value could have counted: the active ones.
          if (owner != kNoBehaviour && manager.active(owner)) {
            failure.explain.push_back(qualified(program, owner));
          }
        }
        break;
      case Expectation::Kind::kState:
      case Expectation::Kind::kQueue:
        failure.explain.push_back("state_machines/" + expectation.target.text);
        break;
      default:
        failure.explain.push_back(qualified(program, resolved.index));
    }
    failures_.push_back(std::move(failure));
  }
}

// What was found instead, as "expected ..., got ..."; empty when the expectation holds.
std::string ExpectationChecks::check_one(const Resolved& resolved, const Manager& manager,
                                         double tolerance) {
  const Expectation& expectation = *resolved.expectation;
  const Program& program = manager.program();
  const std::string& name = expectation.target.text;
  const std::uint64_t step = manager.steps();
  // Formatted only for a failure: a check that holds allocates nothing.
  const auto at = [&] {
    return expectation.first_step == expectation.last_step
               ? fmt::format("at step {}", step)
               : fmt::format("at step {} (of steps {}-{})", step, expectation.first_step,
                             expectation.last_step);
  };
  const std::uint32_t b = resolved.index;
  switch (expectation.kind) {
    case Expectation::Kind::kActive:
      if (manager.active(b)) return {};
      return fmt::format(
          "expected '{}' to be active {}, got inactive (activation {}, requested {})", name, at(),
          level_text(manager.activation(b)), level_text(manager.requested(b)));
    case Expectation::Kind::kInactive:
      if (!manager.active(b)) return {};
      return fmt::format("expected '{}' to be inactive {}, got active (activation {})", name, at(),
                         level_text(manager.activation(b)));
    case Expectation::Kind::kActivation:
    case Expectation::Kind::kRequested: {
      const bool activation = expectation.kind == Expectation::Kind::kActivation;
      const double level = activation ? manager.activation(b) : manager.requested(b);
      const double slack = expectation.within_tolerance ? tolerance : 0.0;
      if (level >= expectation.low - slack && level <= expectation.high + slack) return {};
      const std::string wanted =
          expectation.within_tolerance
              ? fmt::format("{} (within {})", level_text(expectation.low), tolerance)
              : fmt::format("in [{}, {}]", level_text(expectation.low),
                            level_text(expectation.high));
      return fmt::format("expected the {} of '{}' {} to be {}, got {}",
                         activation ? "activation" : "requested level", name, at(), wanted,
                         level_text(level));
    }
    case Expectation::Kind::kInhibitedBy: {
      program.inhibitions.closed(b, inhibitors_);
      std::vector<std::string> got;
      for (const auto inhibitor : inhibitors_) {
        if (manager.activation(inhibitor) > 0.0) got.push_back(program.behaviours[inhibitor].name);
      }
      std::vector<std::string> expected;
      for (const auto& inhibitor : expectation.names) {
        expected.push_back(inhibitor.substr(inhibitor.find('/') + 1));
      }
      auto sorted_got = got;
      std::sort(sorted_got.begin(), sorted_got.end());
      std::sort(expected.begin(), expected.end());
      if (sorted_got == expected) return {};
      return fmt::format("expected '{}' {} to be inhibited by [{}], got [{}]", name, at(),
                         fmt::join(expectation.names, ", "), fmt::join(got, ", "));
    }
    case Expectation::Kind::kActuator: {
      const ValueType& type = *program.actuators[resolved.index].type;
      json_.clear();
      type.append_json(manager.actuator_value(resolved.index), json_);
      if (same_json(json_, resolved.expected_json, tolerance)) return {};
      return fmt::format(
          "expected actuator '{}' {} to be {}, got {}{}", name, at(), resolved.expected_json, json_,
          manager.actuator_written(resolved.index) ? "" : " (not written this step)");
    }
    case Expectation::Kind::kState: {
      const Controller& controller = *program.controllers[resolved.index];
      if (controller.current_state() == expectation.state) return {};
      const std::string got = controller.current_state().empty()
                                  ? fmt::format("no state ({})", to_string(controller.status()))
                                  : fmt::format("'{}'", controller.current_state());
      return fmt::format("expected state machine '{}' {} to be in state '{}', got {}{}", name, at(),
                         expectation.state, got, state_history(resolved, manager));
    }
    case Expectation::Kind::kQueue: {
      const Controller& controller = *program.controllers[resolved.index];
      bool same = controller.queue_size() == expectation.names.size();
      std::vector<std::string> got;
      for (std::size_t i = 0; i < controller.queue_size(); ++i) {
        got.emplace_back(controller.queued(i));
        same = same && expectation.names[i] == controller.queued(i);
      }
      if (same) return {};
      return fmt::format("expected the queue of state machine '{}' {} to be [{}], got [{}]", name,
                         at(), fmt::join(expectation.names, ", "), fmt::join(got, ", "));
    }
  }
  return {};
}

bool TraceChecks::resolve(const Scenario& scenario, const Trace* recorded, std::uint64_t steps,
                          Diagnostics& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  for (std::size_t i = 0; i < scenario.trace_expectations.size(); ++i) {
    const auto& expectation = scenario.trace_expectations[i];
    Compared compared;
    compared.expectation = &expectation;
    compared.index = i;
    if (expectation.kind == TraceExpectation::Kind::kIdentical) {
      if (recorded == nullptr) continue;  // reported by the reader
      compared.trace = *recorded;
      compared.name = scenario.replay.text;
    } else {
      Diagnostic error;
      auto trace = read_trace(expectation.path, error);
      if (!trace) {
        auto& reported = diagnostics.error(expectation.file.location, "unreadable-trace",
                                           fmt::format("cannot compare with trace '{}': {}",
                                                       expectation.file.text, error.message));
        if (error.location.line > 0) {
          reported.notes.push_back(
              {"in the trace at " + to_string(error.location), error.location});
        }
        continue;
      }
      if (!trace->truncated.empty()) {
        diagnostics.error(expectation.file.location, "unreadable-trace",
                          fmt::format("trace '{}' was cut off while it was written: {}",
                                      expectation.file.text, trace->truncated));
        continue;
      }
      compared.trace = std::move(*trace);
      compared.name = expectation.file.text;
    }
    // The steps after a hot reload ran another config: a test compares one.
    auto& kept = compared.trace.steps;
    std::size_t end = kept.size();
    if (!compared.trace.reloads.empty()) end = std::min(end, compared.trace.reloads.front().before);
    while (end > 0 && kept[end - 1].step > steps) --end;
    kept.resize(end);
    compared_.push_back(std::move(compared));
  }
  return diagnostics.error_count() == errors;
}

void TraceChecks::check(const Manager& manager) {
  if (compared_.empty()) return;
  record_.clear();
  append_step_record(manager, record_);
  const std::uint64_t step = manager.steps();
  for (auto& compared : compared_) {
    const auto& steps = compared.trace.steps;
    while (compared.next < steps.size() && steps[compared.next].step < step) {
      compared.differ.unmatched(steps[compared.next++].step);
    }
    if (compared.next < steps.size() && steps[compared.next].step == step) {
      compared.differ.compare(step, steps[compared.next++].text, record_);
    } else if (compared.next < steps.size()) {
      compared.differ.unmatched(step);  // a step the trace lacks (dropped while recorded)
    } else if (compared.first_extra == 0) {
      compared.first_extra = step;
    }
  }
}

void TraceChecks::finish(std::uint64_t steps) {
  for (auto& compared : compared_) {
    const auto& trace = compared.trace.steps;
    const std::uint64_t first_extra =
        compared.next < trace.size() ? trace[compared.next].step : compared.first_extra;
    const TraceDiff diff = compared.differ.finish(trace.size(), steps, first_extra);
    if (diff.identical) continue;
    const auto& expectation = *compared.expectation;
    const bool identical = expectation.kind == TraceExpectation::Kind::kIdentical;
    const auto& first = *diff.first_divergence;
    std::string what = fmt::format("{}", fmt::join(first.what, ", "));
    if (what.empty()) {
      what = diff.steps_a == diff.steps_b
                 ? "a step only one of them has"
                 : fmt::format("the run has {} steps, the {} {}", diff.steps_b,
                               identical ? "recording" : "trace", diff.steps_a);
    }
    Failure failure;
    failure.expectation = compared.index;
    failure.step = first.step;
    failure.message = fmt::format(
        "expected the run to be identical to {} (every step record but its timing), got a "
        "difference at step {}: {}",
        fmt::format("{} '{}'", identical ? "the recording" : "trace", compared.name), first.step,
        what);
    failure.summary = format_text(diff, compared.name, "the run");
    failures_.push_back(std::move(failure));
  }
}

}  // namespace arbiter

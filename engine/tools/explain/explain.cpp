#include "arbiter/explain.hpp"

#include "arbiter/dump.hpp"
#include "arbiter/trace.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <optional>

namespace arbiter {

namespace {

// Ordered: params are shown in the order the trace gives them.
using Json = nlohmann::ordered_json;
using Status = Explanation::Status;

std::string number(double value) {
  return fmt::format("{:.6g}", value);
}

/// The member `key` of `object`, or null (nlohmann's const operator[] asserts on a missing key).
const Json& at(const Json& object, const std::string& key) {
  static const Json kNull;
  if (!object.is_object()) return kNull;
  const auto found = object.find(key);
  return found == object.end() ? kNull : *found;
}

Explanation failure(Status status, std::string text, std::vector<Note> notes = {}) {
  Explanation out;
  out.status = status;
  out.text = std::move(text);
  out.notes = std::move(notes);
  return out;
}

std::string join(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += separator;
    out += items[i];
  }
  return out;
}

/// "a", "a and b", "a, b and c".
std::string listing(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == items.size() ? " and " : ", ") + items[i];
  }
  return out;
}

using Target = ExplainTarget;

/// How explain() names `target` in a list of candidates: enough to name it alone.
std::string full_name(const Program& program, const Target& target) {
  switch (target.kind) {
    case Target::Kind::kController:
      return "state_machines/" + program.controllers[target.index]->name();
    case Target::Kind::kActuator:
      return "actuators/" + program.actuators[target.index].name;
    case Target::Kind::kState:
      return program.controllers[target.index]->name() + "/" +
             program.controllers[target.index]->states()[target.state].name;
    case Target::Kind::kBehaviour:
      break;
  }
  return program.layers[program.behaviours[target.index].layer].name + "/" +
         program.behaviours[target.index].name;
}

std::optional<Target> resolve(const Program& program, std::string_view target, Explanation& error) {
  // Each behaviour once, by the name that is enough to name it.
  std::vector<std::string> known;
  for (const auto& behaviour : program.behaviours) {
    const bool shared =
        std::count_if(program.behaviours.begin(), program.behaviours.end(),
                      [&](const auto& other) { return other.name == behaviour.name; }) > 1;
    known.push_back(shared ? program.layers[behaviour.layer].name + "/" + behaviour.name
                           : behaviour.name);
  }
  for (const auto& controller : program.controllers) {
    known.push_back(controller->name());
    for (const auto& state : controller->states()) {
      known.push_back(controller->name() + "/" + state.name);
    }
  }
  for (const auto& actuator : program.actuators) known.push_back(actuator.name);
  const auto not_found = [&](std::string text) {
    std::vector<Note> notes;
    // `machine/stat` is meant within its machine (else `machine` itself, a prefix, would be
    // suggested).
    std::vector<std::string> scoped;
    if (const auto slash = target.find('/'); slash != std::string_view::npos) {
      const std::string scope(target.substr(0, slash + 1));
      for (const auto& name : known) {
        if (name.rfind(scope, 0) == 0) scoped.push_back(name);
      }
    }
    if (auto hint = suggest(target, scoped.empty() ? known : scoped); !hint.empty()) {
      notes.push_back(std::move(hint));
    }
    error = failure(Status::kNotFound, std::move(text), std::move(notes));
    return std::nullopt;
  };
  std::vector<Target> found;
  const auto slash = target.find('/');
  if (slash != std::string_view::npos) {
    const auto scope = target.substr(0, slash);
    const auto name = target.substr(slash + 1);
    if (scope == "state_machines") {
      for (std::uint32_t c = 0; c < program.controllers.size(); ++c) {
        if (program.controllers[c]->name() == name) found.push_back({Target::Kind::kController, c});
      }
    } else if (scope == "actuators") {
      if (const auto a = program.find_actuator(name)) {
        found.push_back({Target::Kind::kActuator, *a});
      }
    } else if (const auto b = program.find_behaviour(scope, name)) {
      found.push_back({Target::Kind::kBehaviour, *b});
    }
    // A state is named `machine/state`, as its reports name their source.
    for (std::uint32_t c = 0; c < program.controllers.size(); ++c) {
      if (program.controllers[c]->name() != scope) continue;
      const auto& states = program.controllers[c]->states();
      for (std::uint32_t s = 0; s < states.size(); ++s) {
        if (states[s].name == name) found.push_back({Target::Kind::kState, c, s});
      }
    }
  } else {
    for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
      if (program.behaviours[b].name == target) found.push_back({Target::Kind::kBehaviour, b});
    }
    for (std::uint32_t c = 0; c < program.controllers.size(); ++c) {
      if (program.controllers[c]->name() == target) found.push_back({Target::Kind::kController, c});
    }
    for (std::uint32_t a = 0; a < program.actuators.size(); ++a) {
      if (program.actuators[a].name == target) found.push_back({Target::Kind::kActuator, a});
    }
  }
  if (found.empty()) {
    return not_found(fmt::format(
        "'{}' names no behaviour, state machine, state (machine/state) or actuator of '{}'", target,
        program.name));
  }
  if (found.size() > 1) {
    std::vector<std::string> candidates;
    for (const auto& candidate : found) candidates.push_back(full_name(program, candidate));
    error = failure(Status::kNotFound, fmt::format("'{}' is ambiguous", target),
                    {"write one of: " + join(candidates, ", ")});
    return std::nullopt;
  }
  return found.front();
}

/// The records around the step asked for (null where the trace has none).
struct Records {
  Json previous;
  Json current;
  Json next;
  std::uint64_t last_step = 0;
  /// The first step record read, and those just before and after the step asked for (0: none):
  /// a trace need not start at step 1 (a run's own trace does), nor have every step (one edited
  /// by hand).
  std::uint64_t first_step = 0;
  std::uint64_t step_before = 0;
  std::uint64_t step_after = 0;
  /// When `history_of` is set (a member of every step record, e.g. {"actuators", "kick"}): that
  /// member of each step, from the first step to the step asked for, or to the end of the run
  /// with `history_to_end`. An actuator's and a state's story is told from the steps around it.
  std::optional<std::pair<std::string, std::string>> history_of;
  bool history_to_end = false;
  std::vector<std::pair<std::uint64_t, Json>> history;
};

std::optional<Explanation> check_header(const Program& program, const Json& header) {
  const auto bad = [](std::string text, std::vector<Note> notes = {}) {
    return failure(Status::kBadTrace, std::move(text), std::move(notes));
  };
  if (!header.is_object() || header.value("arbiter_trace", 0) != 1) {
    return bad("the trace does not start with an 'arbiter_trace: 1' header",
               {"write one with 'arbiter run CONFIG --trace FILE.jsonl'"});
  }
  const std::string name = header.value("name", "");
  if (name != program.name) {
    return bad(fmt::format("the trace was written for '{}', not for '{}'", name, program.name));
  }
  const Json& layers = at(header, "layers");
  std::vector<Note> differences;
  if (!layers.is_array() || layers.size() != program.layers.size()) {
    differences.push_back(fmt::format("the config has {} layers, the trace {}",
                                      program.layers.size(),
                                      layers.is_array() ? layers.size() : 0));
  } else {
    for (std::size_t l = 0; l < layers.size(); ++l) {
      const auto& layer = program.layers[l];
      std::vector<std::string> order;
      for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
        order.push_back(program.behaviours[b].name);
      }
      const Json& recorded = layers[l];
      if (recorded.value("name", "") != layer.name ||
          recorded.value("order", std::vector<std::string>{}) != order) {
        differences.push_back(fmt::format("layer {} is '{}' [{}] in the config", l + 1, layer.name,
                                          join(order, ", ")));
      }
    }
  }
  if (!differences.empty()) {
    return bad("the trace was written for another version of this config", differences);
  }
  return std::nullopt;
}

std::optional<Explanation> read_trace(TraceSource& source, std::uint64_t step, Records& records,
                                      Json& header) {
  TraceRecord record;
  while (source.next(record)) {
    if (record.kind == TraceRecord::Kind::kHeader) {
      header = Json::parse(record.text);
      continue;
    }
    if (record.kind == TraceRecord::Kind::kReload) {
      // A run reloaded with --watch has a header per program: a step is explained against the
      // program that ran it.
      if (step <= record.step) break;
      header = Json::parse(record.text);
      records.previous = Json();  // written by the program before, with its own indices
      records.history.clear();    // its actuators and states may not be this program's
      continue;
    }
    if (record.kind == TraceRecord::Kind::kSafe) continue;  // outputs values, steps nothing
    records.last_step = record.step;
    if (records.first_step == 0) records.first_step = record.step;
    if (record.step < step) records.step_before = record.step;
    if (record.step > step && records.step_after == 0) records.step_after = record.step;
    Json* slot = record.step + 1 == step   ? &records.previous
                 : record.step == step     ? &records.current
                 : record.step == step + 1 ? &records.next
                                           : nullptr;
    if (records.history_of) {
      Json parsed = Json::parse(record.text);
      records.history.emplace_back(
          record.step, at(at(parsed, records.history_of->first), records.history_of->second));
      if (slot != nullptr) *slot = std::move(parsed);
      if (record.step > step && !records.history_to_end) break;
      continue;
    }
    if (slot != nullptr) *slot = Json::parse(record.text);
    if (record.step > step) break;
  }
  if (const auto& error = source.error()) {
    Explanation out = failure(Status::kBadTrace, error->message, error->notes);
    out.where = error->location;
    return out;
  }
  return std::nullopt;
}

std::optional<Explanation> read_trace(const Program& program, TraceSource& source,
                                      std::uint64_t step, Records& records) {
  Json header;
  if (auto error = read_trace(source, step, records, header)) return error;
  if (auto error = check_header(program, header)) return error;
  if (records.current.is_null()) {
    std::string why;
    if (records.last_step == 0) {
      why = fmt::format("the trace has no step records, so no step {}", step);
    } else if (step < records.first_step) {
      why = fmt::format("the trace starts at step {}, after step {}", records.first_step, step);
    } else if (step < records.last_step) {
      // The step after the gap, not the last read: a state's story reads to the end of the run.
      why = fmt::format("the trace has no step {}: it goes from step {} to step {}", step,
                        records.step_before, records.step_after);
    } else {
      why = fmt::format("the trace has steps {} to {}, not step {}", records.first_step,
                        records.last_step, step);
    }
    return failure(Status::kNotFound, std::move(why));
  }
  return std::nullopt;
}

/// The closed inhibitors of `behaviour`, in execution order.
std::vector<CompiledInhibition> inhibitors_of(const Program& program, std::uint32_t behaviour) {
  std::vector<CompiledInhibition> out;
  for (const auto inhibitor : program.inhibitions.closed(behaviour)) {
    if (const auto declared = program.declared(inhibitor, behaviour)) {
      out.push_back(*declared);
    } else {
      CompiledInhibition implicit;
      implicit.inhibitor = inhibitor;
      implicit.inhibited = behaviour;
      implicit.chaining = true;
      implicit.implicit = true;
      out.push_back(std::move(implicit));
    }
  }
  return out;
}

Explanation explain_behaviour(const Program& program, std::uint32_t target, std::uint64_t step,
                              const Json& record) {
  const auto& behaviour = program.behaviours[target];
  const auto& layer = program.layers[behaviour.layer];
  const Json& levels = at(at(record, "layers"), layer.name);
  // Refinement over the whole layer, from the recorded requested levels (docs/semantics.md,
  // "Refinement").
  const std::size_t n = layer.behaviour_end - layer.behaviour_begin;
  std::vector<double> refined(n, 0.0);
  double sum = 0.0;
  for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
    const Json& requested = at(at(levels, program.behaviours[b].name), "requested");
    if (!requested.is_number()) {
      return failure(Status::kBadTrace,
                     fmt::format("step {} of the trace has no requested level of {}/{}", step,
                                 layer.name, program.behaviours[b].name));
    }
    double level = requested.get<double>();
    for (const auto inhibitor : program.inhibitions.closed(b)) {
      level *= 1.0 - refined[inhibitor - layer.behaviour_begin];
    }
    refined[b - layer.behaviour_begin] = level;
    sum += level;
  }
  const auto level_of = [&](std::uint32_t b) { return refined[b - layer.behaviour_begin]; };
  const Json& own = at(levels, behaviour.name);
  const double requested = at(own, "requested").get<double>();
  const double raw = level_of(target);
  const double activation = layer.normalise && sum > 0.0 ? raw / sum : raw;
  const bool active = activation > 0.0;

  Explanation out;
  std::string& text = out.text;
  text = fmt::format("behaviour {} (layer {}) at step {}: {}, activation {}\n", behaviour.name,
                     layer.name, step, active ? "active" : "inactive", number(activation));
  text += fmt::format("  requested: {}\n", number(requested));
  const auto inhibitors = inhibitors_of(program, target);
  std::string product = number(requested);
  std::vector<std::string> blockers;
  if (inhibitors.empty()) {
    text += "  no inhibitors\n";
  } else {
    text += fmt::format(
        "  inhibitors after closure, in execution order; each multiplies the level by "
        "1 - its {}activation:\n",
        layer.normalise ? "refined (not yet normalised) " : "");
    std::size_t width = 0;
    std::size_t level_width = 0;
    std::size_t factor_width = 0;
    for (const auto& inhibition : inhibitors) {
      width = std::max(width, program.behaviours[inhibition.inhibitor].name.size());
      const double level = level_of(inhibition.inhibitor);
      level_width = std::max(level_width, number(level).size());
      factor_width = std::max(factor_width, number(1.0 - level).size());
    }
    for (const auto& inhibition : inhibitors) {
      const auto& name = program.behaviours[inhibition.inhibitor].name;
      const double level = level_of(inhibition.inhibitor);
      const double factor = 1.0 - level;
      product += " × " + number(factor);
      if (factor <= 0.0) blockers.push_back(name);
      std::string how;
      if (inhibition.implicit) {
        std::vector<std::string> chain;
        std::vector<std::string> declared;
        const auto links = program.chain(inhibition.inhibitor, target);
        for (std::size_t i = 0; i < links.size(); ++i) {
          chain.push_back(program.behaviours[links[i]].name);
          if (i == 0) continue;
          if (const auto edge = program.declared(links[i - 1], links[i])) {
            declared.push_back(to_string(edge->location));
          }
        }
        how = fmt::format("implicit, from chaining {} (declared at {})", join(chain, " => "),
                          join(declared, ", "));
      } else {
        how = fmt::format("declared {} {} {} at {}", name, inhibition.chaining ? "=>" : "->",
                          behaviour.name, to_string(inhibition.location));
      }
      text += fmt::format("    {:<{}}  activation {:<{}}  factor {:<{}}  {}\n", name, width,
                          number(level), level_width, number(factor), factor_width, how);
    }
  }
  if (layer.normalise) {
    text += fmt::format("  refined = {} = {}\n", product, number(raw));
    text += sum > 0.0 ? fmt::format(
                            "  normalised (layer {} normalises): {} / {} (the sum of the layer's "
                            "refined levels) = {}\n",
                            layer.name, number(raw), number(sum), number(activation))
                      : fmt::format(
                            "  normalised (layer {} normalises): every refined level is 0, "
                            "so nothing is divided\n",
                            layer.name);
  } else {
    text += fmt::format("  activation = {} = {}\n", product, number(activation));
  }
  if (active) {
    text += "  active: its activation is above 0\n";
  } else if (requested <= 0.0) {
    text += "  inactive: it requested 0\n";
  } else if (!blockers.empty()) {
    text += fmt::format("  inactive: {} {} fully active (factor 0)\n", listing(blockers),
                        blockers.size() == 1 ? "is" : "are");
  } else {
    text += "  inactive: its activation is 0\n";
  }
  if (const Json& recorded_json = at(own, "activation"); recorded_json.is_number()) {
    const double recorded = recorded_json.get<double>();
    if (std::abs(recorded - activation) > 1e-9 * std::max(1.0, std::abs(recorded))) {
      text += fmt::format(
          "  note: the trace records activation {}, not {}: was it written with another version "
          "of the config?\n",
          number(recorded), number(activation));
    }
  } else {
    // A trace edited by hand, or damaged: the recomputation stands, unchecked, and says so.
    text += fmt::format(
        "  note: the trace records no activation level here (its 'activation' is {}): the "
        "recomputation above is not checked against it\n",
        recorded_json.is_null() ? "missing or null"
                                : std::string("a ") + recorded_json.type_name());
  }
  return out;
}

std::vector<std::string> strings(const Json& list) {
  std::vector<std::string> out;
  if (!list.is_array()) return out;
  for (const auto& item : list) {
    if (item.is_string()) out.push_back(item.get<std::string>());
  }
  return out;
}

std::string state_of(const Json& record) {
  const Json& state = at(record, "state");
  return state.is_string() ? state.get<std::string>() : std::string();
}

/// ` {x: 0.0, y: -4.2}` for a trace's `params` object; "" without one.
std::string params_of(const Json& params) {
  if (!params.is_object()) return {};
  ParamTexts texts;
  const auto shown = [](const Json& value) {
    return value.is_number_float() ? short_number(value.get<double>()) : value.dump();
  };
  for (const auto& [name, value] : params.items()) {
    if (!value.is_array()) {
      texts.emplace_back(name, shown(value));
      continue;
    }
    std::vector<std::string> items;
    for (const auto& item : value) items.push_back(shown(item));
    texts.emplace_back(name, "[" + join(items, ", ") + "]");
  }
  const std::string text = params_text(texts);
  return text.empty() ? text : " " + text;
}

std::string describe_state(const Json& record) {
  const std::string state = state_of(record);
  const auto queue = strings(at(record, "queue"));
  return fmt::format("state {}; queue: {}",
                     state.empty() ? "(none)" : state + params_of(at(record, "params")),
                     queue.empty() ? "(empty)" : join(queue, ", "));
}

/// The trace's `ended` entries of a controller's record, in the order of its deactivations.
struct Ended {
  StateEnd end;
  std::string params;  ///< params_of()
};
std::vector<Ended> ended_of(const Json& record) {
  std::vector<Ended> out;
  const Json& list = at(record, "ended");
  if (!list.is_array()) return out;
  const auto text = [](const Json& value) {
    return value.is_string() ? value.get<std::string>() : std::string();
  };
  for (const auto& item : list) {
    Ended ended;
    ended.end.state = text(at(item, "state"));
    ended.end.cause = text(at(item, "cause"));
    ended.end.to = text(at(item, "to"));
    ended.end.by = text(at(item, "by"));
    if (const Json& preempt = at(item, "preempt"); preempt.is_number_integer()) {
      ended.end.preempt = preempt.get<std::int64_t>();
    }
    ended.end.proceeded = at(item, "proceeded").is_boolean() && at(item, "proceeded").get<bool>();
    ended.params = params_of(at(item, "params"));
    out.push_back(std::move(ended));
  }
  return out;
}

Explanation explain_controller(const Program& program, std::uint32_t target, std::uint64_t step,
                               const Records& records) {
  const Controller& controller = *program.controllers[target];
  const auto entry = [&](const Json& record) -> const Json* {
    const Json& found = at(at(record, "controllers"), controller.name());
    return found.is_object() ? &found : nullptr;
  };
  const Json* now = entry(records.current);
  if (now == nullptr) {
    return failure(Status::kBadTrace, fmt::format("step {} of the trace has no record of state "
                                                  "machine {}",
                                                  step, controller.name()));
  }
  const Json* before = entry(records.previous);
  const Json* after = entry(records.next);
  const std::string status = now->value("status", "");
  const auto events = strings(at(*now, "events"));

  Explanation out;
  std::string& text = out.text;
  text = fmt::format("state machine {} at step {}: cycle {}, {}\n", controller.name(), step,
                     now->value("cycle", 0), status);
  const std::string owner = owner_of(program, controller);
  text += fmt::format("  stepped by: {}\n",
                      !controller.owned() ? "the manager, after the output pass (it is standalone)"
                      : owner.empty() ? "its owner (a state_machine behaviour, or a parent state)"
                      : controller.owner_behaviour() != kNoBehaviour
                          ? fmt::format("behaviour {}, while it is active", owner)
                          : fmt::format("state {} of its parent machine, while it runs", owner));
  if (before != nullptr) {
    text += "  before the step: " + describe_state(*before) + "\n";
  } else if (step == 1) {
    text += "  before the step: (none; the initial queue)\n";
  }
  text +=
      "  events, in order: " + (events.empty() ? std::string("(none)") : join(events, ", ")) + "\n";
  text += "  after the step: " + describe_state(*now) + "\n";

  std::vector<std::string> meaning;
  if (events.empty()) {
    if (status == "finished") {
      meaning.push_back("it has finished: no state runs");
    } else if (status == "error") {
      meaning.push_back("it stopped with an error (see the run's log)");
    } else if (controller.owned()) {
      meaning.push_back(fmt::format(
          "it was not stepped: {} did not step it in this step (a state_machine behaviour "
          "steps its controller only while it is active)",
          owner.empty() ? std::string("its owner") : owner));
    } else {
      meaning.push_back("it was not stepped in this step");
    }
  }
  std::string popped;
  const std::uint64_t cycle = now->value("cycle", std::uint64_t{0});
  const auto ended = ended_of(*now);
  std::size_t deactivations = 0;
  for (std::size_t e = 0; e < events.size(); ++e) {
    const auto& event = events[e];
    const auto space = event.find(' ');
    const std::string verb = event.substr(0, space);
    const std::string state = space == std::string::npos ? "" : event.substr(space + 1);
    if (verb == "deactivate") {
      const std::size_t index = deactivations++;
      if (index < ended.size()) {
        meaning.push_back(fmt::format("{}{} was deactivated: {}", state, ended[index].params,
                                      end_text(ended[index].end, cycle)));
      } else {  // a trace without `ended` (written before it was recorded)
        meaning.push_back(fmt::format(
            "{} was deactivated: it had asked to proceed, the plan was pre-empted, or the "
            "controller was terminated",
            state));
      }
    } else if (verb == "activate") {
      popped = state;
      // Its params: those of the current state, or, when it ended in this very step, those its
      // `ended` entry gives.
      std::string params;
      std::size_t ends_before = 0;
      for (std::size_t i = 0; i < e; ++i) {
        if (events[i].rfind("deactivate ", 0) == 0) ++ends_before;
      }
      const bool ends_here = std::find(events.begin() + static_cast<std::ptrdiff_t>(e),
                                       events.end(), "deactivate " + state) != events.end();
      if (ends_here && ends_before < ended.size()) {
        params = ended[ends_before].params;
      } else if (!ends_here) {
        params = params_of(at(*now, "params"));
      }
      meaning.push_back(
          fmt::format("{}{} became the current state (the head of the queue) and was activated",
                      state, params));
    } else if (verb == "execute") {
      std::string outcome;
      if (after != nullptr) {
        const auto next_events = strings(at(*after, "events"));
        const auto next_ended = ended_of(*after);
        if (!next_events.empty() && next_events.front() == "deactivate " + state) {
          outcome = next_ended.empty()
                        ? fmt::format(
                              " and is deactivated at step {}: it asked to proceed (or the plan "
                              "was pre-empted)",
                              step + 1)
                        : fmt::format(" and is deactivated at step {}: {}", step + 1,
                                      end_text(next_ended.front().end,
                                               after->value("cycle", std::uint64_t{0})));
        } else if (std::find(next_events.begin(), next_events.end(), "execute " + state) !=
                   next_events.end()) {
          outcome = fmt::format(" and held: it runs again at step {}", step + 1);
        } else if (next_events.empty()) {
          outcome = fmt::format(" (the controller is not stepped at step {})", step + 1);
        }
      }
      meaning.push_back(fmt::format("{} executed{}", state, outcome));
    }
  }
  if (before != nullptr) {
    auto expected = strings(at(*before, "queue"));
    if (!popped.empty() && !expected.empty() && expected.front() == popped) {
      expected.erase(expected.begin());
    }
    const auto queue = strings(at(*now, "queue"));
    if (queue != expected) {
      meaning.push_back(
          fmt::format("the plan was edited in this step: the queue would have been "
                      "[{}], it is [{}]",
                      join(expected, ", "), join(queue, ", ")));
    }
    const std::string was = before->value("status", "");
    if (was != status && status == "finished") meaning.push_back("the controller finished");
    if (was != status && status == "error")
      meaning.push_back("the controller stopped with an error");
  }
  text += "  so:\n";
  for (const auto& line : meaning) text += "    - " + line + "\n";
  return out;
}

/// A trace's value as `run` shows values: `[0.3, 0.1, 0]`, `true`, `-0.3`.
std::string value_text(const Json& value) {
  if (value.is_number_float()) return short_number(value.get<double>());
  if (!value.is_array()) return value.dump();
  std::vector<std::string> items;
  for (const auto& item : value) items.push_back(value_text(item));
  return "[" + join(items, ", ") + "]";
}

bool written_in(const Json& entry) {
  return at(entry, "written").is_boolean() && at(entry, "written").get<bool>();
}

Explanation explain_actuator(const Program& program, std::uint32_t target, std::uint64_t step,
                             const Records& records) {
  const CompiledActuator& actuator = program.actuators[target];
  const CompiledLayer& layer = program.layers[actuator.layer];
  const Json& now = at(at(records.current, "actuators"), actuator.name);
  if (!now.is_object()) {
    return failure(
        Status::kBadTrace,
        fmt::format("step {} of the trace has no value of actuator {}", step, actuator.name));
  }
  const bool written = written_in(now);
  Explanation out;
  std::string& text = out.text;
  text = fmt::format("actuator {} (layer {}, {}) at step {}: {}, {}\n", actuator.name, layer.name,
                     actuator.aggregate ? "aggregated" : "the most active writer wins", step,
                     value_text(at(now, "value")), written ? "written" : "held");
  // The writers, each once, in execution order (the order ties are broken in).
  struct Writer {
    std::string name;
    double activation = 0.0;
    bool interface = false;
  };
  std::vector<Writer> writers;
  std::vector<std::uint32_t> seen;
  for (auto i = program.actuator_slot_begin[target]; i < program.actuator_slot_begin[target + 1];
       ++i) {
    const std::uint32_t owner = program.slots[program.actuator_slots[i]].owner;
    if (std::find(seen.begin(), seen.end(), owner) != seen.end()) continue;
    seen.push_back(owner);
    if (owner == kNoBehaviour) {
      writers.push_back({"the interface of layer " + layer.name, 1.0, true});
      continue;
    }
    const auto& behaviour = program.behaviours[owner];
    const Json& level = at(
        at(at(at(records.current, "layers"), program.layers[behaviour.layer].name), behaviour.name),
        "activation");
    writers.push_back({behaviour.name, level.is_number() ? level.get<double>() : 0.0, false});
  }
  std::vector<const Writer*> active;
  std::vector<std::string> inactive;
  double sum = 0.0;
  for (const auto& writer : writers) {
    if (writer.interface || writer.activation > 0.0) {
      active.push_back(&writer);
      sum += writer.activation;
    } else {
      inactive.push_back(writer.name);
    }
  }
  if (writers.empty()) text += "  no behaviour writes it\n";
  if (written) {
    if (actuator.aggregate && !active.empty() && !active.front()->interface) {
      text += "  written by the active writers, weighted by activation (Σ aᵢ·vᵢ / Σ aᵢ):\n";
      std::size_t width = 0;
      std::size_t level_width = 0;
      for (const auto* writer : active) {
        width = std::max(width, writer->name.size());
        level_width = std::max(level_width, number(writer->activation).size());
      }
      for (const auto* writer : active) {
        text +=
            fmt::format("    {:<{}}  activation {:<{}}  weight {} / {} = {}\n", writer->name, width,
                        number(writer->activation), level_width, number(writer->activation),
                        number(sum), number(writer->activation / sum));
      }
      text +=
          "  (the trace records the mean, not each writer's value; an active writer that did not "
          "write in this step is left out of it)\n";
    } else if (!active.empty()) {
      const Writer* winner = active.front();
      for (const auto* writer : active) {
        if (writer->activation > winner->activation) winner = writer;
      }
      text += winner->interface ? fmt::format("  written by {}\n", winner->name)
                                : fmt::format(
                                      "  written by {} (activation {}): the most active writer, "
                                      "the earlier in "
                                      "execution order on a tie\n",
                                      winner->name, number(winner->activation));
    }
  } else {
    std::uint64_t last = 0;
    Json last_value;
    for (const auto& [at_step, entry] : records.history) {
      if (at_step >= step) break;
      if (written_in(entry)) {
        last = at_step;
        last_value = at(entry, "value");
      }
    }
    // A trace given in part (the views give the steps around the one asked for) cannot tell
    // which step older than its first wrote the value.
    const std::uint64_t first = records.history.empty() ? step : records.history.front().first;
    if (last == 0 && first > 1) {
      text += first < step ? fmt::format(
                                 "  held: nobody wrote it in steps {} to {}; the trace given "
                                 "starts at step {}, so the step it was written in is not known\n",
                                 first, step, first)
                           : fmt::format(
                                 "  held: nobody wrote it in this step; the trace given starts "
                                 "here, so the step it was written in is not known\n");
    } else {
      text += last > 0 ? fmt::format(
                             "  held: nobody wrote it in this step; it keeps the value written at "
                             "step {} ({})\n",
                             last, value_text(last_value))
                       : "  held: nothing has written it yet; it holds its default (or its type's "
                         "zero)\n";
    }
    if (!active.empty()) {
      std::vector<std::string> names;
      for (const auto* writer : active) names.push_back(writer->name);
      text += fmt::format("  {} {} active but did not write it\n", listing(names),
                          names.size() == 1 ? "was" : "were");
    }
  }
  if (!inactive.empty()) {
    text += fmt::format("  inactive writers (activation 0, their writes are ignored): {}\n",
                        listing(inactive));
  }
  return out;
}

bool has_event(const Json& entry, const std::string& event) {
  const auto events = strings(at(entry, "events"));
  return std::find(events.begin(), events.end(), event) != events.end();
}

bool queued(const Json& entry, const std::string& state) {
  const auto queue = strings(at(entry, "queue"));
  return std::find(queue.begin(), queue.end(), state) != queue.end();
}

/// Why `state` ended in the step of `entry`: the `ended` entry of its deactivation.
std::string why_ended(const Json& entry, const std::string& state) {
  const auto events = strings(at(entry, "events"));
  const auto ended = ended_of(entry);
  std::size_t index = 0;
  for (const auto& event : events) {
    if (event == "deactivate " + state) {
      return index < ended.size()
                 ? end_text(ended[index].end, entry.value("cycle", std::uint64_t{0}))
                 : "(the trace does not say why)";
    }
    if (event.rfind("deactivate ", 0) == 0) ++index;
  }
  return "(the trace does not say why)";
}

Explanation explain_state(const Program& program, std::uint32_t machine, std::uint32_t target,
                          std::uint64_t step, const Records& records) {
  const Controller& controller = *program.controllers[machine];
  const std::string& state = controller.states()[target].name;
  const auto& history = records.history;
  std::size_t here = history.size();
  for (std::size_t i = 0; i < history.size(); ++i) {
    if (history[i].first == step) here = i;
  }
  if (here == history.size() || !history[here].second.is_object()) {
    return failure(Status::kBadTrace, fmt::format("step {} of the trace has no record of state "
                                                  "machine {}",
                                                  step, controller.name()));
  }
  const auto step_of = [&](std::size_t i) { return history[i].first; };
  const auto entry = [&](std::size_t i) -> const Json& { return history[i].second; };
  // The run of `state` that covers the step: its last activation up to here, and its end.
  std::optional<std::size_t> start;
  for (std::size_t i = here + 1; i-- > 0;) {
    if (has_event(entry(i), "activate " + state)) {
      start = i;
      break;
    }
  }
  // A trace given in part (the views give the steps around the one asked for) may begin while
  // the state runs: then its run started before the first step given.
  const Json& at_step = entry(here);
  const bool started_before =
      !start && (state_of(at_step) == state || has_event(at_step, "execute " + state) ||
                 has_event(at_step, "deactivate " + state));
  std::optional<std::size_t> end;
  if (start || started_before) {
    for (std::size_t i = start ? *start : 0; i < history.size(); ++i) {
      const auto events = strings(at(entry(i), "events"));
      const auto activated = std::find(events.begin(), events.end(), "activate " + state);
      // In the step it started, only a deactivation after its activation ends it.
      const auto from = start && i == *start ? activated : events.begin();
      if (std::find(from, events.end(), "deactivate " + state) != events.end()) {
        end = i;
        break;
      }
    }
  }
  const bool running = (start || started_before) && (!end || *end >= here);
  const std::string name = controller.name() + "/" + state;
  const Json& now = entry(here);
  // Where it was planned: the first step of the stretch, just before `before`, in which it was
  // queued without a break.
  const auto planned = [&](std::size_t before) {
    std::size_t first = before;
    while (first > 0 && queued(entry(first - 1), state)) --first;
    if (first == before) return std::string();
    if (first == 0) {
      return fmt::format(
          "queued since step {}, the first of the trace (the config's queue:, or "
          "planned in that step)",
          step_of(0));
    }
    const std::string was = state_of(entry(first - 1));
    const std::string by = state_of(entry(first));
    return fmt::format("entered the queue at step {}, while {} ran", step_of(first),
                       by.empty() ? (was.empty() ? std::string("no state") : was) : by);
  };

  Explanation out;
  std::string& text = out.text;
  if (running) {
    text =
        fmt::format("state {} at step {}: running (cycle {})\n", name, step, now.value("cycle", 0));
    if (started_before) {
      text += fmt::format("  started before step {}, the first of the trace given\n", step_of(0));
    } else {
      const Json& first = entry(*start);
      std::string how;
      const auto events = strings(at(first, "events"));
      for (const auto& event : events) {
        if (event == "activate " + state) break;
        if (event.rfind("deactivate ", 0) == 0) {
          const std::string previous = event.substr(std::string("deactivate ").size());
          how = fmt::format("activated when {} ended: {}", previous, why_ended(first, previous));
        }
      }
      if (how.empty()) how = "activated as the head of the queue";
      text += fmt::format("  started at step {}: {}\n", step_of(*start), how);
      const std::string plan = planned(*start);
      text += "  planned: " +
              (plan.empty()
                   ? fmt::format("in step {} itself, as the state before it ended", step_of(*start))
                   : plan) +
              "\n";
    }
    text +=
        end ? fmt::format("  ended at step {}: {}\n", step_of(*end), why_ended(entry(*end), state))
            : fmt::format("  still running at step {}, the last of the trace\n",
                          step_of(history.size() - 1));
    return out;
  }
  const auto queue = strings(at(now, "queue"));
  const auto position = std::find(queue.begin(), queue.end(), state);
  if (position != queue.end()) {
    text = fmt::format("state {} at step {}: queued, position {} of [{}] (behind {})\n", name, step,
                       position - queue.begin() + 1, join(queue, ", "),
                       state_of(now).empty() ? std::string("no state") : state_of(now));
    const std::string plan = planned(here + 1);
    if (!plan.empty()) text += "  planned: " + plan + "\n";
  } else {
    text = fmt::format("state {} at step {}: not running and not queued\n", name, step);
    if (start && end) {
      text += fmt::format("  it last ran from step {} to step {}, and ended: {}\n", step_of(*start),
                          step_of(*end), why_ended(entry(*end), state));
    } else {
      text += step_of(0) > 1
                  ? fmt::format("  it has not run in the trace given (from step {})\n", step_of(0))
                  : std::string("  it has not run yet\n");
    }
  }
  std::optional<std::size_t> next;
  for (std::size_t i = here + 1; i < history.size() && !next; ++i) {
    if (has_event(entry(i), "activate " + state)) next = i;
  }
  text += next ? fmt::format("  it runs next from step {}\n", step_of(*next))
               : "  it does not run again before the trace ends\n";
  return out;
}

}  // namespace

Explanation check_trace_header(const Program& program, const std::string& header_line) {
  Json header;
  try {
    header = Json::parse(header_line);
  } catch (const Json::exception& error) {
    return failure(Status::kBadTrace,
                   fmt::format("line 1 of the trace is not JSON: {}", error.what()));
  }
  if (auto error = check_header(program, header)) return *error;
  return {};
}

Explanation explain(const Program& program, std::istream& trace, std::uint64_t step,
                    std::string_view target) {
  const auto source = jsonl_trace_source(trace, "trace");
  return explain(program, *source, step, target);
}

Explanation explain(const Program& program, TraceSource& trace, std::uint64_t step,
                    std::string_view target) {
  Explanation error;
  const auto resolved = resolve(program, target, error);
  if (!resolved) return error;
  if (step == 0) return failure(Status::kNotFound, "steps count from 1");
  try {
    Records records;
    if (resolved->kind == Target::Kind::kActuator) {
      records.history_of.emplace("actuators", program.actuators[resolved->index].name);
    } else if (resolved->kind == Target::Kind::kState) {
      records.history_of.emplace("controllers", program.controllers[resolved->index]->name());
      records.history_to_end = true;
    }
    if (auto failed = read_trace(program, trace, step, records)) return *failed;
    switch (resolved->kind) {
      case Target::Kind::kController:
        return explain_controller(program, resolved->index, step, records);
      case Target::Kind::kActuator:
        return explain_actuator(program, resolved->index, step, records);
      case Target::Kind::kState:
        return explain_state(program, resolved->index, resolved->state, step, records);
      case Target::Kind::kBehaviour:
        break;
    }
    return explain_behaviour(program, resolved->index, step, records.current);
  } catch (const Json::exception& malformed) {  // a member of the wrong JSON type
    return failure(Status::kBadTrace, fmt::format("the trace is malformed: {}", malformed.what()));
  }
}

std::optional<ExplainTarget> resolve_target(const Program& program, std::string_view name,
                                            Explanation& error) {
  return resolve(program, name, error);
}

std::string target_name(const Program& program, const ExplainTarget& target) {
  return full_name(program, target);
}

}  // namespace arbiter

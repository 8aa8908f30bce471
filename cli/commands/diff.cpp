// `arbiter diff A B`: where two runs part (engine/tools/diff), and why: the values at the first
// divergence, whether the inputs parted first, what differs between the configs the recordings
// hold, and the explanation of what first differs in each run against its own config.

#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "arbiter/explain.hpp"
#include "arbiter/recorded_inputs.hpp"
#include "arbiter/reload.hpp"
#include "arbiter/trace_diff.hpp"
#include "arbiter/trace_reader.hpp"
#include "commands/command.hpp"
#include "commands/record.hpp"

namespace arbiter::cli {

namespace {

using Json = nlohmann::ordered_json;

const Json& member(const Json& object, const std::string& key) {
  static const Json kNull;
  if (!object.is_object()) return kNull;
  const auto found = object.find(key);
  return found == object.end() ? kNull : *found;
}

std::string join(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    out += (i > 0 ? std::string(separator) : std::string()) + items[i];
  }
  return out;
}

std::string shown(const Json& value) {
  if (value.is_number_float()) return fmt::format("{:.6g}", value.get<double>());
  if (value.is_array()) {
    std::vector<std::string> items;
    for (const auto& item : value) items.push_back(shown(item));
    return "[" + join(items, ", ") + "]";
  }
  return value.dump();
}

/// One run as the why of a diff reads it: its first header, its record of one step, and the
/// program of the config it holds, if a recording holds one that loads.
struct Run {
  std::string label;  ///< "A" or "B"
  std::string path;
  bool recording = false;
  Json header;
  Json record;  ///< of the first divergence's step; null when the run has no such step
  RecordedProgram config;
  /// Why there is no program, for a person: "A is a trace", "B's config does not load: ...".
  std::string no_program;
};

void read_step(Run& run, std::uint64_t step) {
  if (!readable_again(run.path)) return;  // read once already, by the diff
  const auto source = open_trace(run.path);
  TraceRecord record;
  while (source->next(record)) {
    if (record.kind == TraceRecord::Kind::kHeader) {
      run.header = Json::parse(record.text);
    } else if (record.kind == TraceRecord::Kind::kStep) {
      if (record.step == step) run.record = Json::parse(record.text);
      if (record.step >= step) break;
    }
  }
}

void load_run_config(Run& run, Registry& registry, const LoadOptions& load) {
  if (!readable_again(run.path)) {
    run.no_program =
        fmt::format("{} is not a file (a pipe?), read once already by the diff", run.label);
    return;
  }
  run.recording = is_recording(run.path);
  if (!run.recording) {
    run.no_program = fmt::format("{} is a trace: only a recording holds its config", run.label);
    return;
  }
  run.config = load_recorded_program(run.path, registry, load);
  if (!run.config.error.empty()) {
    std::string error = run.config.error;
    while (!error.empty() && error.back() == '\n') error.pop_back();
    run.no_program = fmt::format("{}'s config cannot be read: {}", run.label, error);
  } else if (!run.config.program) {
    const auto& items = run.config.diagnostics.items();
    const auto error = std::find_if(items.begin(), items.end(), [](const Diagnostic& item) {
      return item.severity == Severity::kError;
    });
    run.no_program = fmt::format(
        "{}'s config ({}) does not load here{}", run.label, run.config.config,
        error == items.end() ? std::string()
                             : ": " + to_string(error->location) + ": " + error->message);
  }
}

/// The behaviours of a run's header, "layer/name", in order.
std::vector<std::string> behaviours_of(const Json& header) {
  std::vector<std::string> out;
  const Json& layers = member(header, "layers");
  if (!layers.is_array()) return out;
  for (const auto& layer : layers) {
    const Json& order = member(layer, "order");
    const Json& layer_name = member(layer, "name");
    if (!order.is_array() || !layer_name.is_string()) continue;
    for (const auto& name : order) {
      if (name.is_string()) {
        out.push_back(layer_name.get<std::string>() + "/" + name.get<std::string>());
      }
    }
  }
  return out;
}

/// What `what` (a name of TraceDiff::Divergence::what) is in a step record: its entry, or null.
const Json& entry_of(const Json& record, const std::string& what) {
  if (what.rfind("actuator:", 0) == 0) return member(member(record, "actuators"), what.substr(9));
  if (what.rfind("machine:", 0) == 0) return member(member(record, "controllers"), what.substr(8));
  const auto slash = what.find('/');
  if (slash == std::string::npos) {
    static const Json kNull;
    return kNull;
  }
  return member(member(member(record, "layers"), what.substr(0, slash)), what.substr(slash + 1));
}

std::string value_text(const std::string& what, const Json& entry) {
  if (entry.is_null()) return "not in this run";
  if (what.rfind("actuator:", 0) == 0) {
    return fmt::format("{}, {}", shown(member(entry, "value")),
                       member(entry, "written") == true ? "written" : "not written");
  }
  if (what.rfind("machine:", 0) == 0) {
    const Json& state = member(entry, "state");
    std::vector<std::string> events;
    for (const auto& event : member(entry, "events")) {
      if (event.is_string()) events.push_back(event.get<std::string>());
    }
    return fmt::format("state {}, events [{}]",
                       state.is_string() ? state.get<std::string>() : "(none)", join(events, ", "));
  }
  return fmt::format("{}, activation {}", member(entry, "active") == true ? "active" : "inactive",
                     shown(member(entry, "activation")));
}

/// Where the recorded inputs of two recordings first differ, up to `last`: the step and the
/// inputs; nullopt when they are the same, or when either cannot be read (then `error`). The
/// inputs are compared as actuators are.
std::optional<TraceDiff::Divergence> inputs_divergence(const std::string& a, const std::string& b,
                                                       std::uint64_t last, double tolerance,
                                                       std::string& error) {
  RecordingReader first(a);
  RecordingReader second(b);
  TraceDiffer differ(tolerance);
  const auto next = [last](RecordingReader& reader, RecordingReader::Event& event) {
    while (reader.next(event)) {
      if (event.kind == RecordingReader::Event::Kind::kInputs) return event.step <= last;
    }
    return false;
  };
  // The inputs message as a step record whose actuators are the inputs.
  const auto as_record = [](const RecordingReader::Event& event) {
    Json record = Json::object();
    record["step"] = event.step;
    record["layers"] = Json::object();
    record["actuators"] = member(Json::parse(event.text), "inputs");
    return record.dump();
  };
  RecordingReader::Event x;
  RecordingReader::Event y;
  bool more_x = next(first, x);
  bool more_y = next(second, y);
  while (more_x && more_y) {
    if (x.step < y.step) {
      more_x = next(first, x);
    } else if (y.step < x.step) {
      more_y = next(second, y);
    } else {
      differ.compare(x.step, as_record(x), as_record(y));
      const auto found = differ.finish(0, 0, 0).first_divergence;
      if (found) {
        auto divergence = *found;
        for (auto& name : divergence.what) name = name.substr(std::string("actuator:").size());
        return divergence;
      }
      more_x = next(first, x);
      more_y = next(second, y);
    }
  }
  for (const auto* reader : {&first, &second}) {
    if (reader->error()) error = reader->error()->message;
  }
  return std::nullopt;
}

/// As inputs_divergence(), for runs of which one at least is a trace: the actuators `names` (the
/// inputs, as a recording's config names them) of the step records.
std::optional<TraceDiff::Divergence> inputs_in_steps(const std::string& a, const std::string& b,
                                                     const std::vector<std::string>& names,
                                                     std::uint64_t last, double tolerance,
                                                     std::string& error) {
  const auto first = open_trace(a);
  const auto second = open_trace(b);
  TraceDiffer differ(tolerance);
  const auto next = [last](TraceSource& source, TraceRecord& record) {
    while (source.next(record)) {
      if (record.kind == TraceRecord::Kind::kStep) return record.step <= last;
    }
    return false;
  };
  const auto inputs_of = [&](const TraceRecord& record) {
    const Json parsed = Json::parse(record.text);
    const Json& actuators = member(parsed, "actuators");
    Json out = Json::object();
    out["step"] = record.step;
    out["layers"] = Json::object();
    out["actuators"] = Json::object();
    for (const auto& name : names) out["actuators"][name] = member(actuators, name);
    return out.dump();
  };
  TraceRecord x;
  TraceRecord y;
  bool more_x = next(*first, x);
  bool more_y = next(*second, y);
  while (more_x && more_y) {
    if (x.step < y.step) {
      more_x = next(*first, x);
    } else if (y.step < x.step) {
      more_y = next(*second, y);
    } else {
      differ.compare(x.step, inputs_of(x), inputs_of(y));
      if (auto found = differ.finish(0, 0, 0).first_divergence) {
        for (auto& name : found->what) name = name.substr(std::string("actuator:").size());
        return found;
      }
      more_x = next(*first, x);
      more_y = next(*second, y);
    }
  }
  for (const auto* source : {first.get(), second.get()}) {
    if (source->error()) error = source->error()->message;
  }
  return std::nullopt;
}

/// What explain() is asked about `what` (a name as the diff gives it) in a run of `program`: a
/// behaviour itself, a state machine itself, an actuator itself (its writers, their weights and
/// how they were aggregated, or the step whose value it holds). Empty when `program` has no such
/// actuator.
std::string explain_target(const Program& program, const std::string& what) {
  if (what.rfind("machine:", 0) == 0) return "state_machines/" + what.substr(8);
  if (what.rfind("actuator:", 0) != 0) return what;
  const std::string name = what.substr(9);
  for (const auto& actuator : program.actuators) {
    if (actuator.name == name) return "actuators/" + name;
  }
  return {};
}

struct Why {
  std::vector<std::string> only_a;
  std::vector<std::string> only_b;
  std::optional<TraceDiff::Divergence> inputs;  ///< where the inputs first differ
  std::string inputs_unknown;                   ///< why that is not known
  std::string inputs_from;                      ///< with a trace: whose config named the inputs
  std::optional<ProgramDiff> config;            ///< from A's config to B's
  std::string config_unknown;
  std::string target;  ///< what is explained
  struct Side {
    std::string text;  ///< the explanation, or why there is none
    bool explained = false;
  };
  Side a;
  Side b;
};

Why::Side explain_side(const Run& run, const std::string& what, std::uint64_t step) {
  Why::Side side;
  if (!run.config.program) {
    side.text = run.no_program;
    return side;
  }
  const Program& program = *run.config.program;
  const std::string target = explain_target(program, what);
  if (target.empty()) {
    side.text = fmt::format("{} has no {}", run.label, what);
    return side;
  }
  const auto source = open_trace(run.path);
  const Explanation explanation = explain(program, *source, step, target);
  side.explained = explanation.status == Explanation::Status::kOk;
  side.text = side.explained ? explanation.text
                             : fmt::format("{} cannot be explained in {}: {}", target, run.label,
                                           explanation.text);
  return side;
}

Why find_why(Run& a, Run& b, const TraceDiff& diff, double tolerance) {
  Why why;
  const auto& first = *diff.first_divergence;
  const auto in_a = behaviours_of(a.header);
  const auto in_b = behaviours_of(b.header);
  // A run not read again (a pipe) has no header here: nothing is only in the other.
  for (const auto& name :
       a.header.is_null() || b.header.is_null() ? std::vector<std::string>() : in_a) {
    if (std::find(in_b.begin(), in_b.end(), name) == in_b.end()) why.only_a.push_back(name);
  }
  for (const auto& name :
       a.header.is_null() || b.header.is_null() ? std::vector<std::string>() : in_b) {
    if (std::find(in_a.begin(), in_a.end(), name) == in_a.end()) why.only_b.push_back(name);
  }
  if (first.what.empty()) {
    // Nothing differs in the steps both have: one run only goes on longer.
    const bool a_longer = diff.steps_a > diff.steps_b;
    why.inputs_unknown = fmt::format(
        "the runs agree on every step both have; only {0} has step {1} ({0} has {2} steps, {3} "
        "{4})",
        a_longer ? "A" : "B", first.step, std::max(diff.steps_a, diff.steps_b),
        a_longer ? "B" : "A", std::min(diff.steps_a, diff.steps_b));
  } else if (!readable_again(a.path) || !readable_again(b.path)) {
    why.inputs_unknown = !a.no_program.empty() ? a.no_program : b.no_program;
  } else if (a.recording && b.recording) {
    std::string error;
    why.inputs = inputs_divergence(a.path, b.path, first.step, tolerance, error);
    if (!error.empty()) why.inputs_unknown = "the recorded inputs cannot be read: " + error;
  } else if (const Run* known = a.config.program ? &a : b.config.program ? &b : nullptr) {
    // A trace beside a recording: the recording's config names the inputs, which a step record
    // holds as the interface layers' actuators.
    const Program& program = *known->config.program;
    std::vector<std::string> names;
    for (const auto& layer : program.layers) {
      if (!layer.is_interface()) continue;
      for (auto i = layer.actuator_begin; i < layer.actuator_end; ++i) {
        names.push_back(program.actuators[i].name);
      }
    }
    std::string error;
    why.inputs = inputs_in_steps(a.path, b.path, names, first.step, tolerance, error);
    if (!error.empty()) why.inputs_unknown = error;
    why.inputs_from = fmt::format("{}'s config", known->label);
  } else {
    why.inputs_unknown = fmt::format("{} a trace: only recordings keep their inputs apart",
                                     !a.recording && !b.recording ? "A and B are"
                                     : !a.recording               ? "A is"
                                                                  : "B is");
  }
  if (a.config.program && b.config.program) {
    why.config = config_diff(*a.config.program, *b.config.program);
  } else {
    why.config_unknown = !a.no_program.empty() ? a.no_program : b.no_program;
  }
  // A behaviour both runs have tells most, then any behaviour, a state machine, an actuator.
  const auto rank = [&](const std::string& what) {
    if (what.rfind("machine:", 0) == 0) return 2;
    if (what.rfind("actuator:", 0) == 0) return 3;
    if (what.find('/') == std::string::npos) return 4;
    const bool both = std::find(in_a.begin(), in_a.end(), what) != in_a.end() &&
                      std::find(in_b.begin(), in_b.end(), what) != in_b.end();
    return both ? 0 : 1;
  };
  std::vector<std::string> candidates;
  for (const auto& what : first.what) {
    if (rank(what) < 4) candidates.push_back(what);
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [&](const auto& x, const auto& y) { return rank(x) < rank(y); });
  // The first candidate explained in a run (one run's config may lack it).
  for (const auto& what : candidates) {
    Why::Side in_a = explain_side(a, what, first.step);
    Why::Side in_b = explain_side(b, what, first.step);
    if (why.target.empty() || in_a.explained || in_b.explained) {
      why.target = what;
      why.a = std::move(in_a);
      why.b = std::move(in_b);
    }
    if (why.a.explained || why.b.explained) break;
  }
  return why;
}

std::string indented(const std::string& text, const std::string& indent) {
  std::string out;
  std::size_t start = 0;
  while (start < text.size()) {
    auto end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    out += indent + text.substr(start, end - start) + "\n";
    start = end + 1;
  }
  return out;
}

std::string inputs_text(const Why& why, std::uint64_t step) {
  if (!why.inputs_unknown.empty()) return "not known: " + why.inputs_unknown;
  // With a trace, the inputs are the step records' values of the actuators a config names.
  const std::string from =
      why.inputs_from.empty() ? std::string() : " (the inputs " + why.inputs_from + " names)";
  if (why.inputs) {
    return fmt::format("they differed first, at step {} ({}){}: the runs met different inputs{}",
                       why.inputs->step, join(why.inputs->what, ", "),
                       why.inputs->step == step ? ", read before the step's behaviours ran" : "",
                       from);
  }
  if (!from.empty()) {
    return fmt::format(
        "the same up to step {}{}: what differs came from the graph, not from its inputs", step,
        from);
  }
  if (why.config && why.config->empty()) {
    return fmt::format(
        "the same up to step {}: the same inputs met the same config, so something in the run is "
        "not deterministic (a behaviour, state or plugin; docs/replay.md, Determinism)",
        step);
  }
  return fmt::format("the same up to step {}: the same inputs met a different graph", step);
}

std::string text_of(const Run& a, const Run& b, const TraceDiff& diff, const Why& why) {
  const auto& first = *diff.first_divergence;
  std::string out;
  if (!first.what.empty()) {
    out += fmt::format("at step {}:\n", first.step);
    for (const auto& what : first.what) {
      if (what.find('/') == std::string::npos && what.find(':') == std::string::npos) continue;
      const auto value = [&](const Run& run) {
        return run.header.is_null() ? std::string("not read again (not a file)")
                                    : value_text(what, entry_of(run.record, what));
      };
      out += fmt::format("  {}: A {}; B {}\n", what, value(a), value(b));
    }
  }
  if (first.what.empty()) {
    out += why.inputs_unknown + "\n";
  } else {
    out += "inputs: " + inputs_text(why, first.step) + "\n";
  }
  if (why.config) {
    out += why.config->empty() ? std::string("config: the same in A and B\n")
                               : "config, from A's to B's:\n" + format(*why.config, "  ");
  } else {
    out += "config: not known: " + why.config_unknown + "\n";
  }
  if (!why.only_a.empty()) out += "only in A: " + join(why.only_a, ", ") + "\n";
  if (!why.only_b.empty()) out += "only in B: " + join(why.only_b, ", ") + "\n";
  if (!why.target.empty()) {
    for (const auto* side : {&why.a, &why.b}) {
      const Run& run = side == &why.a ? a : b;
      out += fmt::format("why {}, in {} ({}):\n", why.target, run.label, run.path);
      out += indented(side->text, "  ");
    }
  }
  return out;
}

Json json_of(const Run& a, const Run& b, const TraceDiff& diff, const Why& why) {
  const auto& first = *diff.first_divergence;
  Json out = Json::object();
  Json values = Json::array();
  for (const auto& what : first.what) {
    Json item = Json::object();
    item["what"] = what;
    item["a"] = entry_of(a.record, what);
    item["b"] = entry_of(b.record, what);
    values.push_back(std::move(item));
  }
  out["values"] = std::move(values);
  Json inputs = Json::object();
  inputs["known"] = why.inputs_unknown.empty();
  inputs["first"] = !why.inputs_unknown.empty() ? Json() : Json(why.inputs ? "inputs" : "graph");
  inputs["first_difference"] = nullptr;
  if (why.inputs) {
    inputs["first_difference"] = Json::object();
    inputs["first_difference"]["step"] = why.inputs->step;
    inputs["first_difference"]["what"] = why.inputs->what;
  }
  if (!why.inputs_unknown.empty()) inputs["why_not_known"] = why.inputs_unknown;
  out["inputs"] = std::move(inputs);
  Json config = Json::object();
  config["known"] = why.config.has_value();
  if (why.config) {
    Json changes = Json::array();
    for (const auto& change : why.config->changes) {
      Json item = Json::object();
      item["change"] = change.kind == Change::Kind::kAdded     ? "added"
                       : change.kind == Change::Kind::kRemoved ? "removed"
                                                               : "changed";
      item["item"] = change.item;
      item["name"] = change.name;
      item["detail"] = change.detail;
      changes.push_back(std::move(item));
    }
    config["changes"] = std::move(changes);
  } else {
    config["why_not_known"] = why.config_unknown;
  }
  out["config"] = std::move(config);
  out["only_in_a"] = why.only_a;
  out["only_in_b"] = why.only_b;
  out["explain"] = nullptr;
  if (!why.target.empty()) {
    Json explained = Json::object();
    explained["what"] = why.target;
    for (const auto* side : {&why.a, &why.b}) {
      Json item = Json::object();
      item["explained"] = side->explained;
      item["text"] = side->text;
      explained[side == &why.a ? "a" : "b"] = std::move(item);
    }
    out["explain"] = std::move(explained);
  }
  return out;
}

}  // namespace

int diff(const std::string& a, const std::string& b, double tolerance, const std::string& format,
         const LoadOptions& load, std::ostream& out, std::ostream& err) {
  const auto first = open_trace(a);
  const auto second = open_trace(b);
  Diagnostic error;
  const auto result = diff_traces(*first, *second, error, tolerance);
  if (!result) {
    err << arbiter::format(error);
    return 2;
  }
  note_end(a, first->truncated(), first->damaged(), err);
  note_end(b, second->truncated(), second->damaged(), err);
  if (result->identical) {
    out << (format == "json" ? format_json(*result) : format_text(*result, a, b));
    return 0;
  }
  // Both configs load into one registry, so that their classes compare as the same.
  Registry registry = make_registry();
  Run run_a;
  run_a.label = "A";
  run_a.path = a;
  Run run_b;
  run_b.label = "B";
  run_b.path = b;
  for (Run* run : {&run_a, &run_b}) {
    load_run_config(*run, registry, load);
    read_step(*run, result->first_divergence->step);
  }
  const Why why = find_why(run_a, run_b, *result, tolerance);
  if (format == "json") {
    Json whole = Json::parse(format_json(*result));
    whole["why"] = json_of(run_a, run_b, *result, why);
    out << whole.dump() << "\n";
  } else {
    // The values, states and events quoted are the runs': escaped as explain escapes them.
    out << format_text(*result, "A " + a, "B " + b)
        << printable(text_of(run_a, run_b, *result, why), true);
  }
  return 1;
}

}  // namespace arbiter::cli

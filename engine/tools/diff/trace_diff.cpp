#include "arbiter/trace_diff.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <string_view>

namespace arbiter {

namespace {

using Json = nlohmann::json;

const Json& member(const Json& object, const std::string& key) {
  static const Json kNull;
  if (!object.is_object()) return kNull;
  const auto found = object.find(key);
  return found == object.end() ? kNull : *found;
}

bool same(const Json& a, const Json& b, double tolerance) {
  if (a.is_number() && b.is_number()) {
    const double x = a.get<double>();
    const double y = b.get<double>();
    return x == y || std::fabs(x - y) <= tolerance || (std::isnan(x) && std::isnan(y));
  }
  if (a.is_array() && b.is_array()) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (!same(a[i], b[i], tolerance)) return false;
    }
    return true;
  }
  if (a.is_object() && b.is_object()) {
    if (a.size() != b.size()) return false;
    for (auto it = a.begin(); it != a.end(); ++it) {
      if (!same(it.value(), member(b, it.key()), tolerance)) return false;
    }
    return true;
  }
  return a == b;
}

/// The keys of a member object in either record, each once.
std::set<std::string> keys(const Json& a, const Json& b) {
  std::set<std::string> out;
  for (const Json* side : {&a, &b}) {
    if (!side->is_object()) continue;
    for (auto it = side->begin(); it != side->end(); ++it) out.insert(it.key());
  }
  return out;
}

void count(TraceDiff::Count& entry, std::uint64_t step) {
  if (entry.differ++ == 0) entry.first = step;
  entry.last = step;
}

/// A behaviour, actuator or machine a run does not have compares as one that does nothing.
bool behaviour_differs(const Json& a, const Json& b, double tolerance) {
  const auto active = [](const Json& x) { return member(x, "active") == true; };
  const auto activation = [](const Json& x) {
    const Json& level = member(x, "activation");
    return level.is_number() ? level : Json(0.0);
  };
  return active(a) != active(b) || !same(activation(a), activation(b), tolerance);
}

bool actuator_differs(const Json& a, const Json& b, double tolerance) {
  const bool written_a = member(a, "written") == true;
  const bool written_b = member(b, "written") == true;
  if (a.is_null() || b.is_null()) return written_a || written_b;
  return written_a != written_b || !same(member(a, "value"), member(b, "value"), tolerance);
}

bool machine_differs(const Json& a, const Json& b) {
  const auto events = [](const Json& x) {
    const Json& list = member(x, "events");
    return list.is_array() ? list : Json::array();
  };
  return member(a, "state") != member(b, "state") || events(a) != events(b);
}

Json without_timing(Json record) {
  if (record.is_object()) {
    record.erase("t");
    record.erase("duration");
  }
  return record;
}

// Where two records that differ first differ: "layers.control.kick_ball.inhibited_by".
std::string first_difference(const Json& a, const Json& b, const std::string& path) {
  if (a.is_object() && b.is_object()) {
    for (const auto& key : keys(a, b)) {
      const auto x = a.find(key);
      const auto y = b.find(key);
      const std::string inner = path.empty() ? key : path + "." + key;
      if (x == a.end() || y == b.end()) return inner;
      if (*x != *y) return first_difference(*x, *y, inner);
    }
  }
  return path;
}

/// A step record after its number and timing, which the trace writer writes first: `{"step": N`,
/// then `, "t": T, "duration": D` when the run was timed. Two records of a step with the same
/// rest are the same to any comparison, read or not. Empty when the record is not laid out so.
std::string_view after_timing(std::string_view record) {
  constexpr std::string_view kStep = R"({"step": )";
  if (record.substr(0, kStep.size()) != kStep) return {};
  auto at = record.find(", ", kStep.size());
  for (const std::string_view key : {R"(, "t": )", R"(, "duration": )"}) {
    if (at == std::string_view::npos || record.substr(at, key.size()) != key) continue;
    at = record.find(", ", at + key.size());
  }
  return at == std::string_view::npos ? std::string_view() : record.substr(at);
}

bool next_step(TraceSource& source, TraceRecord& record) {
  while (source.next(record)) {
    if (record.kind == TraceRecord::Kind::kStep) return true;
  }
  return false;
}

}  // namespace

TraceDiffer::TraceDiffer(double tolerance, bool exact) : tolerance_(tolerance), exact_(exact) {}

void TraceDiffer::unmatched(std::uint64_t step) {
  if (!diff_.first_divergence) diff_.first_divergence = TraceDiff::Divergence{step, {}};
}

void TraceDiffer::compare(std::uint64_t step, const std::string& a, const std::string& b) {
  differed_.clear();
  // Most steps of two runs compared are the same: those are told apart without parsing.
  if (const auto rest = after_timing(a); !rest.empty() && rest == after_timing(b)) return;
  const Json x = Json::parse(a);
  const Json y = Json::parse(b);
  std::vector<std::string> what;
  const Json& layers_x = member(x, "layers");
  const Json& layers_y = member(y, "layers");
  for (const auto& layer : keys(layers_x, layers_y)) {
    const Json& lx = member(layers_x, layer);
    const Json& ly = member(layers_y, layer);
    for (const auto& name : keys(lx, ly)) {
      if (!behaviour_differs(member(lx, name), member(ly, name), tolerance_)) continue;
      const auto key = layer + "/" + name;
      count(diff_.behaviours[key], step);
      what.push_back(key);
    }
  }
  const Json& actuators_x = member(x, "actuators");
  const Json& actuators_y = member(y, "actuators");
  for (const auto& name : keys(actuators_x, actuators_y)) {
    if (!actuator_differs(member(actuators_x, name), member(actuators_y, name), tolerance_)) {
      continue;
    }
    count(diff_.actuators[name], step);
    what.push_back("actuator:" + name);
  }
  const Json& machines_x = member(x, "controllers");
  const Json& machines_y = member(y, "controllers");
  for (const auto& name : keys(machines_x, machines_y)) {
    if (!machine_differs(member(machines_x, name), member(machines_y, name))) continue;
    count(diff_.machines[name], step);
    what.push_back("machine:" + name);
  }
  if (exact_ && what.empty()) {
    const Json timeless_x = without_timing(x);
    const Json timeless_y = without_timing(y);
    if (timeless_x != timeless_y) what.push_back(first_difference(timeless_x, timeless_y, ""));
  }
  differed_ = std::move(what);
  if (!differed_.empty() && !diff_.first_divergence) {
    diff_.first_divergence = TraceDiff::Divergence{step, differed_};
  }
}

TraceDiff TraceDiffer::finish(std::uint64_t steps_a, std::uint64_t steps_b,
                              std::uint64_t first_extra) {
  TraceDiff diff = diff_;
  diff.steps_a = steps_a;
  diff.steps_b = steps_b;
  if (!diff.first_divergence && steps_a != steps_b) {
    diff.first_divergence = TraceDiff::Divergence{first_extra, {}};
  }
  diff.identical = !diff.first_divergence;
  return diff;
}

TraceDiff diff_traces(const Trace& a, const Trace& b, double tolerance, bool exact) {
  TraceDiffer differ(tolerance, exact);
  std::size_t i = 0;
  std::size_t j = 0;
  while (i < a.steps.size() && j < b.steps.size()) {
    if (a.steps[i].step != b.steps[j].step) {
      // A step one run has and the other lacks (dropped while recording): nothing to align.
      differ.unmatched(std::min(a.steps[i].step, b.steps[j].step));
      (a.steps[i].step < b.steps[j].step ? i : j)++;
      continue;
    }
    differ.compare(a.steps[i].step, a.steps[i].text, b.steps[j].text);
    ++i;
    ++j;
  }
  const auto& longer = a.steps.size() > b.steps.size() ? a.steps : b.steps;
  const std::uint64_t first_extra =
      std::min(i, j) < longer.size() ? longer[std::min(i, j)].step : 0;
  return differ.finish(a.steps.size(), b.steps.size(), first_extra);
}

bool StepAligner::next() {
  return next_step(a_, record_);
}

bool StepAligner::start() {
  more_ = next();
  return !a_.error();
}

void StepAligner::compare(std::uint64_t step, const std::string& b) {
  ++steps_b_;
  while (more_ && record_.step < step) {
    // A step one run has and the other lacks (dropped while recording): nothing to align.
    differ_.unmatched(record_.step);
    ++steps_a_;
    more_ = next();
  }
  if (more_ && record_.step == step) {
    differ_.compare(step, record_.text, b);
    ++steps_a_;
    more_ = next();
  } else {
    differ_.unmatched(step);
  }
}

TraceDiff StepAligner::finish(std::uint64_t last) {
  const std::uint64_t first_extra = more_ && record_.step <= last ? record_.step : 0;
  while (more_ && record_.step <= last) {
    ++steps_a_;
    more_ = next();
  }
  return differ_.finish(steps_a_, steps_b_, first_extra);
}

void StepAligner::drain() {
  while (more_) more_ = next();
}

std::optional<TraceDiff> diff_traces(TraceSource& a, TraceSource& b, Diagnostic& error,
                                     double tolerance, bool exact) {
  TraceDiffer differ(tolerance, exact);
  StepAligner aligner(a, differ);
  aligner.start();
  // A source that failed stops the diff at once: the other is not read on to its end first.
  TraceRecord y;
  while (!a.error() && next_step(b, y)) aligner.compare(y.step, y.text);
  std::optional<TraceDiff> diff;
  if (!a.error() && !b.error()) diff = aligner.finish();
  for (const auto* source : {&a, &b}) {
    if (source->error()) {
      error = *source->error();
      return std::nullopt;
    }
  }
  return diff;
}

std::string format_json(const TraceDiff& diff) {
  using Ordered = nlohmann::ordered_json;
  Ordered out = Ordered::object();
  out["identical"] = diff.identical;
  out["steps"] = {diff.steps_a, diff.steps_b};
  out["first_divergence"] = nullptr;
  if (diff.first_divergence) {
    out["first_divergence"] = Ordered::object();
    out["first_divergence"]["step"] = diff.first_divergence->step;
    out["first_divergence"]["what"] = diff.first_divergence->what;
  }
  const auto counts = [](const std::map<std::string, TraceDiff::Count>& entries) {
    Ordered object = Ordered::object();
    for (const auto& [name, entry] : entries) {
      auto& item = object[name] = Ordered::object();
      item["differ"] = entry.differ;
      item["first"] = entry.first;
      item["last"] = entry.last;
    }
    return object;
  };
  out["behaviours"] = counts(diff.behaviours);
  out["actuators"] = counts(diff.actuators);
  out["machines"] = counts(diff.machines);
  return out.dump() + "\n";
}

std::string format_text(const TraceDiff& diff, const std::string& a, const std::string& b) {
  std::string out;
  if (diff.identical) {
    return fmt::format("{} and {} are identical: {} steps\n", a, b, diff.steps_a);
  }
  out += fmt::format("{} ({} steps) and {} ({} steps) differ\n", a, diff.steps_a, b, diff.steps_b);
  const auto& first = *diff.first_divergence;
  if (first.what.empty()) {
    out += fmt::format("first divergence: step {}\n", first.step);
  } else {
    out += fmt::format("first divergence: step {}: ", first.step);
    for (std::size_t i = 0; i < first.what.size(); ++i) {
      out += (i > 0 ? ", " : "") + first.what[i];
    }
    out += "\n";
  }
  const auto section = [&](const char* title, const std::map<std::string, TraceDiff::Count>& map) {
    if (map.empty()) return;
    out += fmt::format("{}:\n", title);
    for (const auto& [name, entry] : map) {
      out += fmt::format("  {}: differs in {} step{} ({} to {})\n", name, entry.differ,
                         entry.differ == 1 ? "" : "s", entry.first, entry.last);
    }
  };
  section("behaviours (active or activation)", diff.behaviours);
  section("actuators (value or written)", diff.actuators);
  section("state machines (state or events)", diff.machines);
  return out;
}

}  // namespace arbiter

#include "arbiter/scenario.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <system_error>

namespace arbiter {
namespace {

constexpr std::string_view kTopKeys[] = {"$schema",    "arbiter_test", "config",
                                         "substitute", "inputs",       "replay",
                                         "expect",     "expect_trace", "steps"};
constexpr std::string_view kExpectKeys[] = {"step",      "steps",        "active",
                                            "inactive",  "activation",   "requested",
                                            "actuators", "inhibited_by", "machines"};
constexpr std::string_view kMachineKeys[] = {"state", "queue"};

// The length of the `.test.yaml` (`.test.yml`, `.test.json`) that ends `path`, or 0.
std::size_t scenario_suffix(std::string_view path) {
  for (std::string_view suffix : {".test.yaml", ".test.yml", ".test.json"}) {
    if (path.size() > suffix.size() && path.substr(path.size() - suffix.size()) == suffix) {
      return suffix.size();
    }
  }
  return 0;
}

template <std::size_t N>
std::vector<std::string> names_of(const std::string_view (&keys)[N]) {
  return {std::begin(keys), std::end(keys)};
}

class ScenarioReader {
 public:
  explicit ScenarioReader(Diagnostics& diagnostics) : diagnostics_(diagnostics) {}

  std::optional<Scenario> read(const Node& root) {
    const std::size_t errors = diagnostics_.error_count();
    Scenario scenario;
    scenario.file = root.location().file;
    scenario.name = std::filesystem::path(scenario.file).filename().string();
    scenario.name.resize(scenario.name.size() - scenario_suffix(scenario.name));
    if (!root.is_mapping()) {
      diagnostics_.error(root.location(), "wrong-type",
                         fmt::format("a test file must be a mapping starting with "
                                     "'arbiter_test: 1', found {}",
                                     root.describe()));
      return std::nullopt;
    }
    check_keys(root, names_of(kTopKeys), "a test file");
    const Node* version = root.find("arbiter_test");
    if (version == nullptr) {
      diagnostics_.error(root.location(), "missing-key",
                         "a test file must start with 'arbiter_test: 1'");
    } else if (version->as_int() != 1) {
      diagnostics_.error(
          version->location(), "bad-version",
          fmt::format("this arbiter reads test files of version 1, found {}", version->describe()));
    }
    read_config(root.find("config"), root, scenario);
    const Node* replay = root.find("replay");
    if (replay != nullptr) read_replay(*replay, root, scenario);
    if (const Node* steps = root.find("steps")) {
      scenario.steps_location = steps->location();
      if (auto count = positive(*steps, "'steps'")) scenario.steps = *count;
    } else if (replay == nullptr) {
      diagnostics_.error(root.location(), "missing-key",
                         "a test file must say how many steps to run ('steps: N')");
    }
    if (const Node* substitute = root.find("substitute")) read_substitute(*substitute, scenario);
    if (const Node* inputs = root.find("inputs")) {
      scenario.inputs_location = key_location(root, "inputs");
      read_inputs(*inputs, scenario);
    }
    const Node* expect = root.find("expect");
    const Node* expect_trace = root.find("expect_trace");
    if (expect != nullptr) read_expect(*expect, scenario);
    if (expect_trace != nullptr) {
      TraceExpectation expectation;
      expectation.kind = TraceExpectation::Kind::kTrace;
      if (read_file(*expect_trace, "'expect_trace'", "trace", scenario, expectation.file,
                    expectation.path)) {
        scenario.trace_expectations.push_back(std::move(expectation));
      }
    }
    if (expect == nullptr && expect_trace == nullptr) {
      diagnostics_.error(root.location(), "missing-key",
                         "a test file must say what it expects ('expect: [...]', 'expect: "
                         "identical' or 'expect_trace: FILE')");
    }
    scenario.complete = diagnostics_.error_count() == errors;
    return scenario;
  }

 private:
  static SourceLocation key_location(const Node& mapping, std::string_view key) {
    for (const auto& entry : mapping.entries()) {
      if (entry.key == key) return entry.key_location;
    }
    return mapping.location();
  }

  void check_keys(const Node& mapping, const std::vector<std::string>& allowed,
                  std::string_view what) {
    for (const auto& entry : mapping.entries()) {
      if (std::find(allowed.begin(), allowed.end(), entry.key) != allowed.end()) continue;
      diagnostics_
          .error(entry.key_location, "unknown-key",
                 fmt::format("unknown key '{}' in {}", entry.key, what))
          .unknown_name(entry.key, allowed, {}, "allowed");
    }
  }

  std::optional<std::uint64_t> positive(const Node& node, std::string_view what) {
    const auto value = node.as_int();
    if (!value || *value < 1) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("{} must be a step number (an integer from 1), found {}", what,
                                     node.describe()));
      return std::nullopt;
    }
    return static_cast<std::uint64_t>(*value);
  }

  std::optional<std::string> text(const Node& node, std::string_view what) {
    if (!node.is_scalar() || (!node.quoted() && node.reads_as_null())) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("{} must be a string, found {}", what, node.describe()));
      return std::nullopt;
    }
    return node.text();
  }

  void read_config(const Node* node, const Node& root, Scenario& scenario) {
    if (node == nullptr) {
      diagnostics_.error(root.location(), "missing-key",
                         "a test file must name the config it tests ('config: PATH', relative "
                         "to the test file)");
      return;
    }
    read_file(*node, "'config'", "config", scenario, scenario.config, scenario.config_path);
  }

  // A file the test file names, relative to it; reported at `node` when there is no such file.
  bool read_file(const Node& node, std::string_view key, std::string_view what,
                 const Scenario& scenario, ScenarioName& name, std::string& resolved_path) {
    auto path = text(node, key);
    if (!path) return false;
    name = {*path, node.location()};
    namespace fs = std::filesystem;
    fs::path resolved(*path);
    if (resolved.is_relative()) resolved = fs::path(scenario.file).parent_path() / resolved;
    resolved_path = resolved.lexically_normal().string();
    std::error_code error;
    const fs::file_status status = fs::status(resolved, error);
    if (fs::is_regular_file(status)) return true;
    // What is there, when something is: a directory or a device is no file to read (/dev/zero
    // never ends), and a path that cannot be looked at has its reason.
    const std::string at = printable(resolved_path);
    std::string why = fmt::format("does not exist (looked for {})", at);
    if (error && error != std::errc::no_such_file_or_directory) {
      why = fmt::format("cannot be looked at (at {}): {}", at, error.message());
    } else if (fs::is_directory(status)) {
      why = fmt::format("is a directory (at {})", at);
    } else if (fs::exists(status)) {
      why = fmt::format("is not a regular file (a FIFO, socket or device at {})", at);
    }
    diagnostics_.error(node.location(), "unreadable-file",
                       fmt::format("{} '{}' {}", what, printable(*path), why));
    return false;
  }

  void read_replay(const Node& node, const Node& root, Scenario& scenario) {
    read_file(node, "'replay'", "recording", scenario, scenario.replay, scenario.replay_path);
    if (root.find("inputs") != nullptr) {
      const SourceLocation inputs = key_location(root, "inputs");
      diagnostics_
          .error(node.location(), "conflicting-keys",
                 "a test's inputs come from 'inputs:' or from a recording ('replay:'): give one "
                 "of the two")
          .notes.push_back({fmt::format("'inputs:' is at line {}", inputs.line), inputs});
    }
  }

  void read_substitute(const Node& node, Scenario& scenario) {
    if (!node.is_mapping()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("'substitute' must map what is replaced (a behaviour, "
                                     "state, interface layer or class) to its replacement, "
                                     "found {}",
                                     node.describe()));
      return;
    }
    for (const auto& entry : node.entries()) {
      ScenarioSubstitution substitution;
      substitution.target = {entry.key, entry.key_location};
      substitution.inputs =
          entry.value.is_scalar() && !entry.value.quoted() && entry.value.text() == "inputs";
      substitution.declaration = entry.value;
      scenario.substitutions.push_back(std::move(substitution));
    }
  }

 public:
  // Also a file of inputs by itself (read_inputs_file).
  void read_inputs(const Node& node, Scenario& scenario) {
    if (!node.is_sequence()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("'inputs' must be a list of {{step: N, ACTUATOR: VALUE, "
                                     "...}}, found {}",
                                     node.describe()));
      return;
    }
    for (const auto& item : node.items()) {
      if (!item.is_mapping()) {
        diagnostics_.error(item.location(), "wrong-type",
                           fmt::format("an 'inputs' entry must be a mapping {{step: N, "
                                       "ACTUATOR: VALUE, ...}}, found {}",
                                       item.describe()));
        continue;
      }
      ScenarioInput input;
      input.location = item.location();
      const Node* step = item.find("step");
      if (step == nullptr) {
        diagnostics_.error(item.location(), "missing-key",
                           "an 'inputs' entry must say from which step its values hold "
                           "('step: N')");
        continue;
      }
      auto first = positive(*step, "'step'");
      if (!first) continue;
      input.step = *first;
      for (const auto& other : scenario.inputs) {
        if (other.step == input.step) {
          diagnostics_
              .error(step->location(), "duplicate-step",
                     fmt::format("two 'inputs' entries for step {}", input.step))
              .notes.push_back(
                  {fmt::format("the other is at {}", to_string(other.location)), other.location});
        }
      }
      for (const auto& entry : item.entries()) {
        if (entry.key == "step") continue;
        input.values.push_back({{entry.key, entry.key_location}, entry.value});
      }
      scenario.inputs.push_back(std::move(input));
    }
    std::stable_sort(
        scenario.inputs.begin(), scenario.inputs.end(),
        [](const ScenarioInput& a, const ScenarioInput& b) { return a.step < b.step; });
  }

 private:
  void read_expect(const Node& node, Scenario& scenario) {
    if (node.is_scalar() && node.text() == "identical") {
      if (scenario.replay.text.empty()) {
        diagnostics_.error(node.location(), "identical-without-replay",
                           "'expect: identical' compares the run with the recording it replays, "
                           "but the test replays none: give 'replay: RUN.mcap', or compare with "
                           "a trace ('expect_trace: FILE')");
        return;
      }
      TraceExpectation expectation;
      expectation.kind = TraceExpectation::Kind::kIdentical;
      expectation.file = {"identical", node.location()};
      scenario.trace_expectations.push_back(std::move(expectation));
      return;
    }
    if (!node.is_sequence()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("'expect' must be a list of {{step: N, ...}} or "
                                     "{{steps: [FIRST, LAST], ...}}, or 'identical', found {}",
                                     node.describe()));
      return;
    }
    for (const auto& item : node.items()) read_expectation(item, scenario);
  }

  // The steps an `expect:` entry covers; nullopt after reporting.
  std::optional<std::pair<std::uint64_t, std::uint64_t>> read_steps(const Node& item,
                                                                    const Scenario& scenario) {
    const Node* step = item.find("step");
    const Node* steps = item.find("steps");
    if ((step == nullptr) == (steps == nullptr)) {
      diagnostics_.error(item.location(), step == nullptr ? "missing-key" : "conflicting-keys",
                         "an 'expect' entry holds at one step ('step: N') or at every step of a "
                         "range ('steps: [FIRST, LAST]'): give one of the two");
      return std::nullopt;
    }
    std::pair<std::uint64_t, std::uint64_t> range;
    const Node& at = step != nullptr ? *step : *steps;
    if (step != nullptr) {
      auto first = positive(*step, "'step'");
      if (!first) return std::nullopt;
      range = {*first, *first};
    } else {
      if (!steps->is_sequence() || steps->items().size() != 2) {
        diagnostics_.error(
            steps->location(), "wrong-type",
            fmt::format("'steps' must be a range [FIRST, LAST], found {}", steps->describe()));
        return std::nullopt;
      }
      auto first = positive(steps->items()[0], "the first step of 'steps'");
      auto last = positive(steps->items()[1], "the last step of 'steps'");
      if (!first || !last) return std::nullopt;
      if (*last < *first) {
        diagnostics_.error(steps->location(), "out-of-range",
                           fmt::format("'steps' [{}, {}] ends before it starts", *first, *last));
        return std::nullopt;
      }
      range = {*first, *last};
    }
    if (scenario.steps != 0 && range.second > scenario.steps) {
      diagnostics_.error(at.location(), "out-of-range",
                         fmt::format("step {} is after the last step the test runs ({}, "
                                     "'steps:')",
                                     range.second, scenario.steps));
      return std::nullopt;
    }
    return range;
  }

  void read_expectation(const Node& item, Scenario& scenario) {
    if (!item.is_mapping()) {
      diagnostics_.error(item.location(), "wrong-type",
                         fmt::format("an 'expect' entry must be a mapping {{step: N, active: "
                                     "[...], ...}}, found {}",
                                     item.describe()));
      return;
    }
    const std::size_t errors = diagnostics_.error_count();
    check_keys(item, names_of(kExpectKeys), "an 'expect' entry");
    const auto range = read_steps(item, scenario);
    if (!range) return;
    std::size_t checks = 0;
    const auto add = [&](Expectation expectation) {
      expectation.first_step = range->first;
      expectation.last_step = range->second;
      scenario.expectations.push_back(std::move(expectation));
      ++checks;
    };
    for (const auto& entry : item.entries()) {
      const Node& value = entry.value;
      if (entry.key == "active" || entry.key == "inactive") {
        const auto kind =
            entry.key == "active" ? Expectation::Kind::kActive : Expectation::Kind::kInactive;
        for_names(value, entry.key, [&](const std::string& name, const SourceLocation& where) {
          Expectation expectation;
          expectation.kind = kind;
          expectation.target = {name, where};
          add(std::move(expectation));
        });
      } else if (entry.key == "activation" || entry.key == "requested") {
        for_entries(value, entry.key, "a behaviour to a level or a range [LOW, HIGH]",
                    [&](const Node::Entry& level) {
                      Expectation expectation;
                      expectation.kind = entry.key == "activation" ? Expectation::Kind::kActivation
                                                                   : Expectation::Kind::kRequested;
                      expectation.target = {level.key, level.key_location};
                      if (read_level(level.value, entry.key, expectation))
                        add(std::move(expectation));
                    });
      } else if (entry.key == "inhibited_by") {
        for_entries(value, entry.key, "a behaviour to the list of its inhibitors",
                    [&](const Node::Entry& list) {
                      Expectation expectation;
                      expectation.kind = Expectation::Kind::kInhibitedBy;
                      expectation.target = {list.key, list.key_location};
                      if (read_list(list.value, "inhibited_by", expectation.names)) {
                        add(std::move(expectation));
                      }
                    });
      } else if (entry.key == "actuators") {
        for_entries(value, entry.key, "an actuator to its value", [&](const Node::Entry& actuator) {
          Expectation expectation;
          expectation.kind = Expectation::Kind::kActuator;
          expectation.target = {actuator.key, actuator.key_location};
          expectation.value = actuator.value;
          add(std::move(expectation));
        });
      } else if (entry.key == "machines") {
        for_entries(value, entry.key, "a state machine to {state: S, queue: [...]}",
                    [&](const Node::Entry& machine) { read_machine(machine, add); });
      }
    }
    if (checks == 0 && diagnostics_.error_count() == errors) {
      diagnostics_.error(item.location(), "empty-expectation",
                         "this 'expect' entry checks nothing: give 'active', 'inactive', "
                         "'activation', 'requested', 'inhibited_by', 'actuators' or 'machines'");
    }
  }

  template <typename F>
  void read_machine(const Node::Entry& machine, F&& add) {
    if (!machine.value.is_mapping()) {
      diagnostics_.error(machine.value.location(), "wrong-type",
                         fmt::format("the expectation of state machine '{}' must be a mapping "
                                     "{{state: S, queue: [...]}}, found {}",
                                     machine.key, machine.value.describe()));
      return;
    }
    check_keys(machine.value, names_of(kMachineKeys), "a state machine's expectation");
    for (const auto& field : machine.value.entries()) {
      Expectation expectation;
      expectation.target = {machine.key, field.key_location};
      if (field.key == "state") {
        auto state = text(field.value, "'state'");
        if (!state) continue;
        expectation.kind = Expectation::Kind::kState;
        expectation.state = *state;
        add(std::move(expectation));
      } else if (field.key == "queue") {
        expectation.kind = Expectation::Kind::kQueue;
        if (read_list(field.value, "queue", expectation.names)) add(std::move(expectation));
      }
    }
  }

  template <typename F>
  void for_names(const Node& node, const std::string& key, F&& visit) {
    if (node.is_scalar() && !node.reads_as_null()) {
      visit(node.text(), node.location());
      return;
    }
    if (!node.is_sequence()) {
      diagnostics_.error(
          node.location(), "wrong-type",
          fmt::format("'{}' must be a list of behaviours, found {}", key, node.describe()));
      return;
    }
    for (const auto& item : node.items()) {
      if (auto name = text(item, fmt::format("a behaviour in '{}'", key))) {
        visit(*name, item.location());
      }
    }
  }

  template <typename F>
  void for_entries(const Node& node, const std::string& key, std::string_view shape, F&& visit) {
    if (!node.is_mapping()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("'{}' must map {}, found {}", key, shape, node.describe()));
      return;
    }
    for (const auto& entry : node.entries()) visit(entry);
  }

  bool read_level(const Node& node, const std::string& key, Expectation& expectation) {
    const auto in_unit = [](double level) { return level >= 0.0 && level <= 1.0; };
    if (auto level = node.as_double()) {
      if (!in_unit(*level)) {
        diagnostics_.error(node.location(), "out-of-range",
                           fmt::format("a level is in [0, 1], found {}", node.text()));
        return false;
      }
      expectation.low = expectation.high = *level;
      expectation.within_tolerance = true;
      return true;
    }
    if (node.is_sequence() && node.items().size() == 2) {
      const auto low = node.items()[0].as_double();
      const auto high = node.items()[1].as_double();
      if (low && high && in_unit(*low) && in_unit(*high) && *low <= *high) {
        expectation.low = *low;
        expectation.high = *high;
        return true;
      }
      // Two numbers are a range: what is wrong with it is said, not that it is no level.
      if (low && high) {
        for (const Node& bound : node.items()) {
          if (!in_unit(*bound.as_double())) {
            diagnostics_.error(bound.location(), "out-of-range",
                               fmt::format("a level is in [0, 1], found {}", bound.text()));
            return false;
          }
        }
        diagnostics_.error(
            node.location(), "out-of-range",
            fmt::format("'{}' of '{}' [{}, {}] ends below where it starts", key,
                        expectation.target.text, node.items()[0].text(), node.items()[1].text()));
        return false;
      }
    }
    diagnostics_.error(node.location(), "wrong-type",
                       fmt::format("'{}' of '{}' must be a level in [0, 1] or a range [LOW, HIGH] "
                                   "within it, found {}",
                                   key, expectation.target.text, node.describe()));
    return false;
  }

  bool read_list(const Node& node, std::string_view what, std::vector<std::string>& out) {
    if (!node.is_sequence()) {
      diagnostics_.error(
          node.location(), "wrong-type",
          fmt::format("'{}' must be a list of names, found {}", what, node.describe()));
      return false;
    }
    for (const auto& item : node.items()) {
      auto name = text(item, fmt::format("an item of '{}'", what));
      if (!name) return false;
      out.push_back(*name);
    }
    return true;
  }

  Diagnostics& diagnostics_;
};

}  // namespace

std::optional<std::vector<ScenarioInput>> read_inputs_file(const std::string& path,
                                                           Diagnostics& diagnostics,
                                                           const ReadLimits& limits) {
  auto document = read_document(path, diagnostics, limits);
  if (!document || diagnostics.has_errors()) return std::nullopt;
  Scenario scenario;
  ScenarioReader(diagnostics).read_inputs(*document, scenario);
  if (diagnostics.has_errors()) return std::nullopt;
  return std::move(scenario.inputs);
}

bool is_scenario_file(std::string_view path) {
  return scenario_suffix(path) > 0;
}

std::optional<Scenario> build_scenario(const Node& root, Diagnostics& diagnostics) {
  return ScenarioReader(diagnostics).read(root);
}

std::optional<Scenario> read_scenario(const std::string& path, Diagnostics& diagnostics,
                                      const ReadLimits& limits) {
  auto document = read_document(path, diagnostics, limits);
  if (!document || diagnostics.has_errors()) return std::nullopt;
  return build_scenario(*document, diagnostics);
}

}  // namespace arbiter

#include "arbiter/scenario_run.hpp"

#include <fmt/format.h>

#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>

#include "arbiter/explain.hpp"
#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/program.hpp"
#include "arbiter/recorded_inputs.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/substitute.hpp"
#include "arbiter/trace.hpp"
#include "tools/scenario/scenario_checks.hpp"
#include "tools/scenario/scenario_inputs.hpp"

namespace arbiter {
namespace {

// A test's trace, kept for explain() when an expectation fails: in a file of its own, removed
// with it, not in memory, as a test may run millions of steps (some 700 bytes each for a small
// config; 1.2 million steps held 800 MB). Where no temporary file can be made, in memory.
class KeptTrace {
 public:
  KeptTrace() {
    std::error_code error;
    const auto directory = std::filesystem::temp_directory_path(error);
    if (error) return;
    std::string name = (directory / "arbiter-test-XXXXXX").string();
    const int fd = ::mkstemp(name.data());
    if (fd < 0) return;
    ::close(fd);
    path_ = name;
    file_.open(path_, std::ios::binary | std::ios::trunc);
    if (!file_) remove();
  }
  ~KeptTrace() { remove(); }
  KeptTrace(const KeptTrace&) = delete;
  KeptTrace& operator=(const KeptTrace&) = delete;

  std::ostream& out() { return path_.empty() ? static_cast<std::ostream&>(memory_) : file_; }
  /// The trace from its start; written up to here.
  std::unique_ptr<std::istream> read() {
    if (path_.empty()) return std::make_unique<std::istringstream>(memory_.str());
    file_.flush();
    return std::make_unique<std::ifstream>(path_, std::ios::binary);
  }

 private:
  void remove() {
    if (path_.empty()) return;
    file_.close();
    std::error_code error;
    std::filesystem::remove(path_, error);
    path_.clear();
  }
  std::string path_;
  std::ofstream file_;
  std::ostringstream memory_;
};

std::string explain_at(const Program& program, KeptTrace& trace, std::uint64_t step,
                       const std::vector<std::string>& targets) {
  std::string out;
  for (const auto& target : targets) {
    const auto in = trace.read();
    const auto explanation = explain(program, *in, step, target);
    if (explanation.status == Explanation::Status::kOk) out += explanation.text;
  }
  return out;
}

// The recording a scenario replays: its inputs, its steps, and how many of them can be replayed.
struct Replayed {
  std::unique_ptr<RecordedInputs> inputs;
  Trace trace;
  std::uint64_t steps = 0;
};

std::optional<Replayed> read_replayed(const Scenario& scenario, Diagnostics& diagnostics) {
  const auto& where = scenario.replay.location;
  Diagnostic error;
  auto run = read_recorded_run(scenario.replay_path, error);
  std::optional<Trace> trace;
  if (run) trace = read_trace(scenario.replay_path, error);
  if (!run || !trace) {
    diagnostics.error(where, "unreadable-recording",
                      fmt::format("cannot replay '{}': {}", scenario.replay.text, error.message));
    return std::nullopt;
  }
  if (!trace->truncated.empty()) {
    diagnostics.error(where, "unreadable-recording",
                      fmt::format("recording '{}' was cut off while it was written: {}",
                                  scenario.replay.text, trace->truncated));
    return std::nullopt;
  }
  Replayed replayed;
  replayed.inputs = std::make_unique<RecordedInputs>(run->inputs);
  replayed.trace = std::move(*trace);
  replayed.steps = replayed.inputs->steps();
  // A scenario test replays the first config only (`arbiter replay` applies recorded reloads);
  // a dropped step's inputs are lost: what can be replayed ends before either.
  if (!run->reloads.empty() && run->reloads.front().after_step < replayed.steps) {
    replayed.steps = run->reloads.front().after_step;
    diagnostics.warning(
        where, "replay-cut",
        replay_cut(ReplayCut::kReloaded, run->reloads.front().after_step, 0, "the test"));
  }
  if (run->first_gap && *run->first_gap < replayed.steps) {
    replayed.steps = *run->first_gap;
    diagnostics.warning(
        where, "replay-cut",
        replay_cut(ReplayCut::kDropped, *run->first_gap, run->first_gap_dropped, "the test"));
  }
  if (scenario.steps > replayed.steps) {
    diagnostics.error(scenario.steps_location, "out-of-range",
                      fmt::format("'steps' is {}, but the recording has {} steps to replay",
                                  scenario.steps, replayed.steps));
    return std::nullopt;
  }
  if (scenario.steps == 0) {
    // The expectations' steps were checked against `steps:` when read; here, the recording's.
    bool fits = true;
    for (const auto& expectation : scenario.expectations) {
      if (expectation.last_step <= replayed.steps) continue;
      diagnostics.error(expectation.target.location, "out-of-range",
                        fmt::format("step {} is after the last step the test replays ({}, the "
                                    "recording's)",
                                    expectation.last_step, replayed.steps));
      fits = false;
    }
    if (!fits) return std::nullopt;
  }
  return replayed;
}

// Feeds every interface layer that the scenario leaves as the config has it from the recording,
// then checks that every recorded input has its place.
bool feed_from_recording(Model& model, const std::vector<const ClassInfo*>& before,
                         const Scenario& scenario, const RecordedInputs& recorded,
                         const Registry& registry, Diagnostics& diagnostics) {
  std::vector<Substitution> substitutions;
  for (std::size_t l = 0; l < model.layers.size(); ++l) {
    const auto& layer = model.layers[l];
    if (!layer.is_interface() || layer.interface != before[l]) continue;
    Substitution substitution;
    substitution.target = layer.name.text;
    substitution.location = scenario.replay.location;
    substitution.cls = &recorded.interface_class();
    substitutions.push_back(std::move(substitution));
  }
  if (!substitute(model, substitutions, registry, diagnostics)) return false;
  const std::size_t errors = diagnostics.error_count();
  recorded.check_places(model, scenario.replay.location, diagnostics);
  return diagnostics.error_count() == errors;
}

/// A failure in step `step`, reported at `location`.
ScenarioFailure failure_at(const SourceLocation& location, std::string code, std::string message,
                           std::uint64_t step, std::string explanation = {}) {
  ScenarioFailure failure;
  failure.diagnostic.location = location;
  failure.diagnostic.code = std::move(code);
  failure.diagnostic.message = std::move(message);
  failure.step = step;
  failure.explanation = std::move(explanation);
  return failure;
}

}  // namespace

InputFeed::InputFeed() : inputs_(std::make_unique<ScheduledInputs>()) {}
InputFeed::~InputFeed() = default;

bool InputFeed::read(const std::string& path, Diagnostics& diagnostics, const ReadLimits& limits) {
  auto entries = read_inputs_file(path, diagnostics, limits);
  if (!entries) return false;
  entries_ = std::move(*entries);
  where_.file = path;
  where_.line = 1;
  where_.column = 1;
  return true;
}

bool InputFeed::edit(Model& model, const Registry& registry, Diagnostics& diagnostics) {
  inputs_->feed_builtin_layers(model, registry);
  return inputs_->prepare(entries_, where_, model, diagnostics);
}

ScenarioResult run_scenario(const Scenario& scenario, Registry& registry,
                            const ScenarioOptions& options) {
  ScenarioResult result;
  result.file = scenario.file;
  result.name = scenario.name;
  for (const std::string& named : {scenario.config_path, scenario.replay_path}) {
    if (!named.empty()) result.named_files.push_back(named);
  }
  for (const auto& expected : scenario.trace_expectations) {
    if (!expected.path.empty()) result.named_files.push_back(expected.path);
  }
  Diagnostics& diagnostics = result.diagnostics;

  // The input sources and the checks are separate pieces: each source substitutes its own
  // interface class, each kind of check compares its own things after each step.
  // An incomplete scenario reported the files it names that do not exist, and a replay beside
  // `inputs:`.
  const auto readable = [&](const std::string& path) {
    std::error_code error;
    return scenario.complete || std::filesystem::is_regular_file(path, error);
  };
  std::optional<Replayed> replayed;
  if (!scenario.replay.text.empty() && readable(scenario.replay_path) &&
      (scenario.complete || scenario.inputs_location.file.empty())) {
    replayed = read_replayed(scenario, diagnostics);
    if (!replayed) {
      diagnostics.sort();
      return result;
    }
  }
  const std::uint64_t steps = replayed && scenario.steps == 0 ? replayed->steps : scenario.steps;
  ScheduledInputs inputs;
  std::vector<Substitution> substitutions;
  for (const auto& item : scenario.substitutions) {
    Substitution substitution;
    substitution.target = item.target.text;
    substitution.location = item.target.location;
    substitution.declaration = item.declaration;
    if (item.inputs) substitution.cls = &inputs.interface_class();
    substitutions.push_back(std::move(substitution));
  }
  LoadOptions load;
  load.limits = options.limits;
  load.plugins = options.plugins;
  // No lint step: a test reports what it tests; `arbiter validate` lints the config.
  bool edit_failed = false;
  load.edit_model = [&](Model& model, Diagnostics& reported) {
    std::vector<const ClassInfo*> before;
    for (const auto& layer : model.layers) before.push_back(layer.interface);
    const bool substituted = substitute(model, substitutions, registry, reported);
    // A recording feeds every interface layer the test leaves alone, the built-in ones too.
    if (!replayed) inputs.feed_builtin_layers(model, registry);
    // Once a layer that `inputs:` should feed failed to be substituted, what the inputs would be
    // told follows from that mistake.
    bool fed = true;
    for (const auto& item : scenario.substitutions) {
      const LayerDecl* layer = model.find_layer(item.target.text);
      fed = fed && (!item.inputs || substituted ||
                    (layer != nullptr && layer->interface == &inputs.interface_class()));
    }
    const bool prepared =
        fed && inputs.prepare(scenario.inputs, scenario.inputs_location, model, reported);
    edit_failed = !(substituted && prepared &&
                    (!replayed || feed_from_recording(model, before, scenario, *replayed->inputs,
                                                      registry, reported)));
    return !edit_failed;
  };
  if (!readable(scenario.config_path)) {
    diagnostics.sort();
    return result;
  }
  Loaded loaded = load_config(scenario.config_path, registry, load);
  diagnostics.append(loaded.diagnostics);
  auto& program = loaded.program;
  // The names the expectations use are the config's with or without the substitutions: when
  // those are wrong, the names are checked against the config as it is, in the same run.
  std::optional<Program> unedited;
  if (edit_failed) {
    LoadOptions plain;
    plain.limits = options.limits;
    plain.plugins = options.plugins;
    unedited = load_config(scenario.config_path, registry, plain).program;
  }
  const Program* named = program ? &*program : unedited ? &*unedited : nullptr;
  ExpectationChecks checks;
  TraceChecks traces;
  bool resolved = named != nullptr && checks.resolve(scenario, *named, diagnostics);
  resolved = traces.resolve(scenario, replayed ? &replayed->trace : nullptr, steps, diagnostics) &&
             resolved;
  if (!program || !resolved || !scenario.complete) {
    diagnostics.sort();
    return result;
  }
  result.expectations = checks.size() + traces.size();

  Manager manager(std::move(*program));
  KeptTrace trace;  // for explain(), when an expectation fails
  TraceWriter writer(trace.out());
  manager.add_observer(writer);
  while (manager.steps() < steps && !manager.stopped()) {
    manager.step();
    checks.check(manager, options.tolerance);
    traces.check(manager);
  }
  manager.finish();
  manager.remove_observer(writer);
  result.steps = manager.steps();
  traces.finish(result.steps);

  for (const auto& failed : checks.failures()) {
    const Expectation& expectation = scenario.expectations[failed.expectation];
    result.failures.push_back(
        failure_at(expectation.target.location, "expectation", failed.message, failed.step,
                   failed.explain.empty()
                       ? fmt::format("no behaviour that writes '{}' was active at step {}\n",
                                     expectation.target.text, failed.step)
                       : explain_at(manager.program(), trace, failed.step, failed.explain)));
  }
  for (const auto& failed : traces.failures()) {
    const TraceExpectation& expectation = scenario.trace_expectations[failed.expectation];
    result.failures.push_back(failure_at(expectation.file.location, "expectation", failed.message,
                                         failed.step, failed.summary));
  }
  if (manager.stopped()) {
    result.failures.push_back(
        failure_at(scenario.config.location, "run-stopped",
                   fmt::format("expected {} steps, got a run that stopped at step {}: {}", steps,
                               manager.steps(), manager.stop_reason()),
                   manager.steps()));
  }
  result.status =
      result.failures.empty() ? ScenarioResult::Status::kPassed : ScenarioResult::Status::kFailed;
  return result;
}

ScenarioResult run_scenario_file(const std::string& path, Registry& registry,
                                 const ScenarioOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Diagnostics diagnostics;
  auto scenario = read_scenario(path, diagnostics, options.limits);
  ScenarioResult result;
  if (scenario) {
    result = run_scenario(*scenario, registry, options);
    diagnostics.append(result.diagnostics);
  } else {
    result.file = path;
    result.name = path;
  }
  diagnostics.sort();
  result.diagnostics = std::move(diagnostics);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

namespace {

std::string indented(const std::string& text) {
  std::string out;
  bool line_start = true;
  for (char c : text) {
    if (line_start && c != '\n') out += "    ";
    out += c;
    line_start = c == '\n';
  }
  if (!out.empty() && out.back() != '\n') out += '\n';
  return out;
}

}  // namespace

std::string format_failures(const ScenarioResult& result, const FormatOptions& options) {
  std::string out = format(result.diagnostics, options);
  for (const auto& failure : result.failures) {
    out += format(failure.diagnostic, options);
    out += indented(printable(failure.explanation, true));
  }
  return out;
}

}  // namespace arbiter

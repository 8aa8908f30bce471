#include "arbiter/scenario_run.hpp"

#include <fmt/format.h>

#include <sstream>

#include "arbiter/explain.hpp"
#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/program.hpp"
#include "arbiter/substitute.hpp"
#include "arbiter/trace.hpp"
#include "scenario_checks.hpp"
#include "scenario_inputs.hpp"

namespace arbiter {
namespace {

std::string explain_at(const Program& program, const std::string& trace, std::uint64_t step,
                       const std::vector<std::string>& targets) {
  std::string out;
  for (const auto& target : targets) {
    std::istringstream in(trace);
    const auto explanation = explain(program, in, step, target);
    if (explanation.status == Explanation::Status::kOk) out += explanation.text;
  }
  return out;
}

}  // namespace

ScenarioResult run_scenario(const Scenario& scenario, Registry& registry,
                            const ScenarioOptions& options) {
  ScenarioResult result;
  result.file = scenario.file;
  result.name = scenario.name;
  Diagnostics& diagnostics = result.diagnostics;

  // The input source and the checks are separate pieces: another source (a recording's inputs)
  // substitutes its own interface class, other checks compare other things after each step.
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
  load.edit_model = [&](Model& model, Diagnostics& reported) {
    return substitute(model, substitutions, registry, reported) &&
           inputs.prepare(scenario, model, reported);
  };
  Loaded loaded = load_config(scenario.config_path, registry, load);
  diagnostics = std::move(loaded.diagnostics);
  auto& program = loaded.program;
  ExpectationChecks checks;
  if (!program || !checks.resolve(scenario, *program, diagnostics)) {
    diagnostics.sort();
    return result;
  }
  result.expectations = checks.size();

  Manager manager(std::move(*program));
  std::ostringstream trace;  // for explain(), when an expectation fails
  TraceWriter writer(trace);
  manager.add_observer(writer);
  while (manager.steps() < scenario.steps && !manager.stopped()) {
    manager.step();
    checks.check(manager, options.tolerance);
  }
  manager.finish();
  manager.remove_observer(writer);
  result.steps = manager.steps();

  const std::string text = trace.str();
  for (const auto& failed : checks.failures()) {
    const Expectation& expectation = scenario.expectations[failed.expectation];
    ScenarioFailure failure;
    failure.diagnostic.location = expectation.target.location;
    failure.diagnostic.code = "expectation";
    failure.diagnostic.message = failed.message;
    failure.step = failed.step;
    failure.explanation = explain_at(manager.program(), text, failed.step, failed.explain);
    if (failed.explain.empty()) {
      failure.explanation = fmt::format("no behaviour that writes '{}' was active at step {}\n",
                                        expectation.target.text, failed.step);
    }
    result.failures.push_back(std::move(failure));
  }
  if (manager.stopped()) {
    ScenarioFailure failure;
    failure.diagnostic.location = scenario.config.location;
    failure.diagnostic.code = "run-stopped";
    failure.diagnostic.message =
        fmt::format("expected {} steps, got a run that stopped at step {}: {}", scenario.steps,
                    manager.steps(), manager.stop_reason());
    failure.step = manager.steps();
    result.failures.push_back(std::move(failure));
  }
  result.status =
      result.failures.empty() ? ScenarioResult::Status::kPassed : ScenarioResult::Status::kFailed;
  return result;
}

ScenarioResult run_scenario_file(const std::string& path, Registry& registry,
                                 const ScenarioOptions& options) {
  Diagnostics diagnostics;
  auto scenario = read_scenario(path, diagnostics, options.limits);
  if (!scenario) {
    ScenarioResult result;
    result.file = path;
    result.name = path;
    result.diagnostics = std::move(diagnostics);
    result.diagnostics.sort();
    return result;
  }
  return run_scenario(*scenario, registry, options);
}

}  // namespace arbiter

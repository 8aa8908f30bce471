// Scenario tests (`*.test.yaml`) run by the engine's scenario runner, as `arbiter test` runs them,
// for the pytest plugin (arbiter/pytest_plugin.py).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>

#include "arbiter/scenario.hpp"
#include "arbiter/scenario_run.hpp"
#include "builtins.hpp"
#include "module.hpp"

namespace arbiter::python {

namespace {

const char* status_name(ScenarioResult::Status status) {
  switch (status) {
    case ScenarioResult::Status::kPassed:
      return "passed";
    case ScenarioResult::Status::kFailed:
      return "failed";
    case ScenarioResult::Status::kInvalid:
      break;
  }
  return "invalid";
}

py::dict run_scenario(const std::filesystem::path& path,
                      const std::vector<std::string>& plugin_path, double tolerance) {
  Registry registry;
  register_builtin_behaviours(registry);
  ScenarioOptions options;
  options.plugins.path = plugin_path;
  options.tolerance = tolerance;
  // The config's Python classes exist only once this process has imported them, as
  // arbiter.load() does.
  options.plugins.import_python = import_python_plugin;
  const ScenarioResult result = run_scenario_file(path.string(), registry, options);
  py::dict out;
  out["status"] = status_name(result.status);
  out["name"] = result.name;
  out["expectations"] = result.expectations;
  out["failed"] = result.failures.size();
  out["steps"] = result.steps;
  out["text"] = format_failures(result, FormatOptions::readable());
  out["diagnostics"] = to_python(result.diagnostics);
  return out;
}

}  // namespace

void bind_scenario(py::module_& m) {
  m.def("_run_scenario", &run_scenario, py::arg("path"), py::arg("plugin_path"),
        py::arg("tolerance"));
}

}  // namespace arbiter::python

// The extension module arbiter._arbiter: the engine's own pipeline, manager, readers and scenario
// runner bound for Python. The package around it (arbiter/__init__.py) adds what is simpler in
// Python: ConfigError, argument checks, the DataFrame and the pytest plugin.

#include <pybind11/stl.h>

#include <utility>

#include "arbiter/dump.hpp"
#include "arbiter/lint.hpp"
#include "builtins.hpp"
#include "module.hpp"

namespace arbiter::python {

namespace {

std::shared_ptr<Session> make_session(const std::string& path,
                                      const std::vector<std::string>& plugin_path, bool strict) {
  auto session = std::make_shared<Session>();
  register_builtin_behaviours(session->registry);
  session->options.strict = strict;
  session->options.lint = lint;
  session->options.plugins.path = plugin_path;
  session->options.plugins.import_python = import_python_plugin;
  session->path = path;
  return session;
}

/// load(): the program, or ConfigError with every diagnostic, as `arbiter validate` reports them.
std::unique_ptr<PyProgram> load_checked(const std::string& path,
                                        const std::vector<std::string>& plugin_path, bool strict) {
  auto session = make_session(path, plugin_path, strict);
  Loaded loaded = load_config(path, session->registry, session->options);
  Diagnostics diagnostics = std::move(loaded.diagnostics);
  diagnostics.sort();
  if (!loaded.program || diagnostics.has_errors()) raise_config_error(diagnostics);
  auto result = std::make_unique<PyProgram>();
  result->session = std::move(session);
  result->program = std::move(*loaded.program);
  result->warnings = std::move(diagnostics);
  return result;
}

std::vector<std::string> behaviour_names(const Program& program) {
  std::vector<std::string> names;
  for (const auto& behaviour : program.behaviours) {
    names.push_back(program.layers[behaviour.layer].name + "/" + behaviour.name);
  }
  return names;
}

}  // namespace

}  // namespace arbiter::python

PYBIND11_MODULE(_arbiter, m) {
  using namespace arbiter;
  using namespace arbiter::python;
  m.doc() = "The Arbiter behaviour engine (docs/python.md). Use the package `arbiter`.";

  bind_diagnostics(m);
  bind_plugins(m);

  py::class_<PyProgram>(m, "Program",
                        "A config loaded and compiled: its layers, behaviours, actuators and state "
                        "machines, and its graph. manager() runs it.")
      .def_property_readonly("name", [](const PyProgram& p) { return p.program.name; })
      .def_property_readonly("path", [](const PyProgram& p) { return p.session->path; })
      .def_property_readonly("rate_hz", [](const PyProgram& p) { return p.program.rate_hz; })
      .def_property_readonly(
          "steps", [](const PyProgram& p) { return p.program.steps; },
          "The config's `steps:` (0: not set).")
      .def_property_readonly("layers",
                             [](const PyProgram& p) {
                               std::vector<std::string> names;
                               for (const auto& layer : p.program.layers)
                                 names.push_back(layer.name);
                               return names;
                             })
      .def_property_readonly(
          "behaviours", [](const PyProgram& p) { return behaviour_names(p.program); },
          "Every behaviour as 'layer/name', layer by layer, each layer in execution order.")
      .def_property_readonly("actuators",
                             [](const PyProgram& p) {
                               std::vector<std::string> names;
                               for (const auto& actuator : p.program.actuators) {
                                 names.push_back(actuator.name);
                               }
                               return names;
                             })
      .def_property_readonly("state_machines",
                             [](const PyProgram& p) {
                               std::vector<std::string> names;
                               for (const auto& c : p.program.controllers)
                                 names.push_back(c->name());
                               return names;
                             })
      .def_property_readonly(
          "warnings", [](const PyProgram& p) { return to_python(p.warnings); },
          "The warnings and lints of the load, as Diagnostic objects.")
      .def(
          "dump",
          [](const PyProgram& p, const std::string& layer) { return dump_text(p.program, layer); },
          py::arg("layer") = "", "`arbiter dump`'s text: layers, order, inhibitions, wiring.")
      .def(
          "to_dot",
          [](const PyProgram& p, const std::string& layer) { return dump_dot(p.program, layer); },
          py::arg("layer") = "", "The graph in Graphviz DOT, as `arbiter dump --format dot`.")
      .def(
          "to_json",
          [](const PyProgram& p, const std::string& layer) { return dump_json(p.program, layer); },
          py::arg("layer") = "", "The graph as `arbiter dump --format json`.");

  m.def("_load", &load_checked, py::arg("path"), py::arg("plugin_path"), py::arg("strict"));

  bind_manager(m);
  bind_recording(m);
  bind_scenario(m);
}

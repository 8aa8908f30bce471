#pragma once
// What the parts of the Python module share: the loaded config's registry and options, which
// every program, manager and reload made from it must outlive.

#include <pybind11/pybind11.h>

#include <memory>
#include <string>

#include "arbiter/diagnostics.hpp"
#include "arbiter/load.hpp"
#include "arbiter/program.hpp"
#include "arbiter/registry.hpp"

namespace arbiter::python {

namespace py = pybind11;

/// A config as the module loaded it: its registry (built-ins and the plugins it named) and the
/// options it was loaded with, kept alive by every object made from it.
struct Session {
  Registry registry;
  LoadOptions options;
  std::string path;
};

/// A loaded config's program, for inspection; a Manager runs a program of its own, loaded again.
struct PyProgram {
  std::shared_ptr<Session> session;
  Program program;
  Diagnostics warnings;
};

/// A Python list of Diagnostic objects.
py::list to_python(const Diagnostics& diagnostics);
/// What `arbiter validate` prints on stderr for these diagnostics of one file.
std::string validate_text(const Diagnostics& diagnostics);
/// Raises arbiter.ConfigError carrying `diagnostics` (its text validate_text()).
[[noreturn]] void raise_config_error(const Diagnostics& diagnostics);

/// Imports the Python module a config's `plugins:` names as `{python: MODULE}` (`node`, in the
/// file `config`) and registers its behaviour and state classes (plugins.cpp); what fails is
/// reported at the module's name. PluginOptions::import_python, for every load from Python.
bool import_python_plugin(const Node& node, const std::string& config, Registry& registry,
                          Diagnostics& diagnostics);

void bind_diagnostics(py::module_& m);
void bind_plugins(py::module_& m);
void bind_manager(py::module_& m);
void bind_recording(py::module_& m);
void bind_scenario(py::module_& m);

}  // namespace arbiter::python

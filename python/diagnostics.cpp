#include <fmt/format.h>
#include <pybind11/stl.h>

#include "module.hpp"

namespace arbiter::python {

namespace {

const char* severity_name(Severity severity) {
  return severity == Severity::kError ? "error" : "warning";
}

}  // namespace

py::list to_python(const Diagnostics& diagnostics) {
  py::list list;
  for (const auto& diagnostic : diagnostics.items()) list.append(py::cast(diagnostic));
  return list;
}

std::string validate_text(const Diagnostics& diagnostics) {
  // As validate_command() prints one file's diagnostics (cli/commands/config_commands.cpp) when
  // stderr is not a terminal.
  return format(diagnostics, FormatOptions::readable()) +
         fmt::format("{} error(s), {} warning(s)\n", diagnostics.error_count(),
                     diagnostics.warning_count());
}

void raise_config_error(const Diagnostics& diagnostics) {
  py::object error_class = py::module_::import("arbiter").attr("ConfigError");
  py::object error = error_class(validate_text(diagnostics), to_python(diagnostics));
  PyErr_SetObject(error_class.ptr(), error.ptr());
  throw py::error_already_set();
}

void bind_diagnostics(py::module_& m) {
  py::class_<Diagnostic>(m, "Diagnostic",
                         "One problem found in a config: where, how bad, and what; str() is the "
                         "text `arbiter validate` prints for it.")
      .def_property_readonly("severity",
                             [](const Diagnostic& d) { return severity_name(d.severity); })
      .def_property_readonly("code", [](const Diagnostic& d) { return d.code; })
      .def_property_readonly("file", [](const Diagnostic& d) { return d.location.file; })
      .def_property_readonly("line", [](const Diagnostic& d) { return d.location.line; })
      .def_property_readonly("column", [](const Diagnostic& d) { return d.location.column; })
      .def_property_readonly("message", [](const Diagnostic& d) { return d.message; })
      .def_property_readonly("notes",
                             [](const Diagnostic& d) {
                               std::vector<std::string> notes;
                               for (const auto& note : d.notes) notes.push_back(note.text);
                               return notes;
                             })
      .def("__str__", [](const Diagnostic& d) { return format(d, FormatOptions::readable()); })
      .def("__repr__", [](const Diagnostic& d) {
        return fmt::format("<Diagnostic {} {} at {}: {}>", severity_name(d.severity), d.code,
                           to_string(d.location), d.message);
      });
}

}  // namespace arbiter::python

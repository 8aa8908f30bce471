#include "module.hpp"

namespace arbiter::python {

void bind_scenario(py::module_&) {}

}  // namespace arbiter::python

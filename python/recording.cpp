#include "module.hpp"

namespace arbiter::python {

void bind_recording(py::module_&) {}

}  // namespace arbiter::python

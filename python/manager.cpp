// Manager: a program run step by step from Python. Its config is loaded again through a Reloader
// (the transactional reload of `arbiter run --watch`), with the layers of the built-in `inputs`
// interface class fed from Python (set_input), as `arbiter run --inputs` feeds them from a file.

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <typeinfo>

#include "arbiter/init_context.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/reload.hpp"
#include "arbiter/trace.hpp"
#include "builtins.hpp"
#include "module.hpp"

namespace arbiter::python {

namespace {

/// The values Python gave the actuators of the fed `inputs` layers, by actuator name.
struct InputTable {
  struct Entry {
    const ValueType* type = nullptr;
    ValueBox value;
    bool set = false;  ///< written from its first set_input() on; before, the default holds
  };
  std::map<std::string, Entry, std::less<>> entries;
  ClassInfo interface_class;
};

/// Writes, in each input pass, the value each of its layer's actuators was last given.
class FedInputs final : public Interface {
 public:
  explicit FedInputs(InputTable& table) : table_(table) {}

  void init(InitContext& ctx) override {
    for (const auto& item : ctx.layer_actuators()) {
      const auto found = table_.entries.find(item.name);
      if (found == table_.entries.end()) continue;
      bound_.push_back({&found->second, ctx.output_to_actuator(item.name, item.location)});
    }
  }

  void input(WriteContext& ctx) override {
    for (const auto& bound : bound_) {
      if (bound.entry->set) ctx.write(bound.output, bound.entry->value);
    }
  }

 private:
  struct Bound {
    const InputTable::Entry* entry;
    AnyOutput output;
  };
  InputTable& table_;
  std::vector<Bound> bound_;
};

py::object value_to_python(const ValueType& type, const void* value) {
  const std::type_info* cpp = type.cpp_type;
  if (cpp != nullptr) {
    if (*cpp == typeid(bool)) return py::bool_(*static_cast<const bool*>(value));
    if (*cpp == typeid(std::int64_t)) return py::int_(*static_cast<const std::int64_t*>(value));
    if (*cpp == typeid(double)) return py::float_(*static_cast<const double*>(value));
    if (*cpp == typeid(std::string)) return py::str(*static_cast<const std::string*>(value));
    if (*cpp == typeid(Vec2)) {
      const auto& v = *static_cast<const Vec2*>(value);
      return py::make_tuple(v.x, v.y);
    }
    if (*cpp == typeid(Vec3)) {
      const auto& v = *static_cast<const Vec3*>(value);
      return py::make_tuple(v.x, v.y, v.z);
    }
  }
  // A plugin's type: its JSON, as the trace has it.
  std::string json;
  type.append_json(value, json);
  return py::module_::import("json").attr("loads")(json);
}

class PyManager {
 public:
  PyManager(const PyProgram& program) : session_(program.session) {
    table_ = std::make_unique<InputTable>();
    table_->interface_class.name = kInputsInterface;
    table_->interface_class.kind = ClassKind::kInterface;
    table_->interface_class.origin = "the Python module's set_input()";
    table_->interface_class.make_interface = [table = table_.get()] {
      return std::make_unique<FedInputs>(*table);
    };
    LoadOptions options = session_->options;
    options.edit_model = [this](Model& model, Diagnostics&) {
      feed_inputs_layers(model);
      return true;
    };
    reloader_ = std::make_unique<Reloader>(session_->registry, std::move(options));
    Diagnostics diagnostics;
    auto loaded = reloader_->load(session_->path, diagnostics);
    if (!loaded) raise_config_error(diagnostics);
    manager_.emplace(std::move(*loaded));
  }

  ~PyManager() {
    if (trace_) manager_->remove_observer(*trace_);
  }

  void step(std::uint64_t count) {
    for (std::uint64_t i = 0; i < count && !manager_->stopped(); ++i) {
      manager_->step();
      if (paused_) manager_->safe_pass();
    }
  }

  std::uint32_t behaviour(const std::string& key) const {
    const Program& program = manager_->program();
    const auto slash = key.find('/');
    std::vector<std::string> known;
    std::optional<std::uint32_t> found;
    bool ambiguous = false;
    for (std::uint32_t i = 0; i < program.behaviours.size(); ++i) {
      const auto& b = program.behaviours[i];
      const std::string& layer = program.layers[b.layer].name;
      known.push_back(slash == std::string::npos ? b.name : layer + "/" + b.name);
      const bool match = slash == std::string::npos
                             ? b.name == key
                             : key.compare(0, slash, layer) == 0 && slash == layer.size() &&
                                   key.compare(slash + 1, std::string::npos, b.name) == 0;
      if (!match) continue;
      ambiguous = found.has_value();
      found = i;
    }
    if (ambiguous) {
      throw py::key_error(
          fmt::format("behaviour '{}' is in more than one layer: say which, as "
                      "'layer/{}'",
                      key, key));
    }
    if (!found) {
      throw py::key_error(fmt::format("no behaviour '{}'; {}", key, suggest(key, known)));
    }
    return *found;
  }

  py::dict levels(std::uint32_t b) const {
    py::dict d;
    d["activation"] = manager_->activation(b);
    d["requested"] = manager_->requested(b);
    d["active"] = manager_->active(b);
    return d;
  }

  py::dict all_levels() const {
    py::dict all;
    const Program& program = manager_->program();
    for (std::uint32_t i = 0; i < program.behaviours.size(); ++i) {
      const auto& b = program.behaviours[i];
      all[py::str(program.layers[b.layer].name + "/" + b.name)] = levels(i);
    }
    return all;
  }

  std::uint32_t actuator_index(const std::string& name) const {
    const Program& program = manager_->program();
    if (auto index = program.find_actuator(name)) return *index;
    std::vector<std::string> known;
    for (const auto& a : program.actuators) known.push_back(a.name);
    throw py::key_error(fmt::format("no actuator '{}'; {}", name, suggest(name, known)));
  }

  py::object actuator(const std::string& name) const {
    const auto index = actuator_index(name);
    return value_to_python(*manager_->program().actuators[index].type,
                           manager_->actuator_value(index));
  }

  py::dict actuators() const {
    py::dict all;
    const Program& program = manager_->program();
    for (std::uint32_t i = 0; i < program.actuators.size(); ++i) {
      all[py::str(program.actuators[i].name)] =
          value_to_python(*program.actuators[i].type, manager_->actuator_value(i));
    }
    return all;
  }

  const Controller& controller(const std::string& name) const {
    const Program& program = manager_->program();
    if (const Controller* c = program.find_controller(name)) return *c;
    std::vector<std::string> known;
    for (const auto& c : program.controllers) known.push_back(c->name());
    throw py::key_error(fmt::format("no state machine '{}'; {}", name, suggest(name, known)));
  }

  py::object state(const std::string& name) const {
    const auto current = controller(name).current_state();
    if (current.empty()) return py::none();
    return py::str(std::string(current));
  }

  py::dict states() const {
    py::dict all;
    for (const auto& c : manager_->program().controllers)
      all[py::str(c->name())] = state(c->name());
    return all;
  }

  std::string status(const std::string& name) const { return to_string(controller(name).status()); }

  py::object error(const std::string& name) const {
    const Controller& c = controller(name);
    if (c.status() != ControllerStatus::kError) return py::none();
    return py::str(c.error());
  }

  void set_input(const std::string& name, const py::object& value) {
    const auto found = table_->entries.find(name);
    if (found == table_->entries.end()) {
      std::vector<std::string> known;
      for (const auto& [fed, entry] : table_->entries) known.push_back(fed);
      throw py::key_error(fmt::format(
          "set_input(): no input '{}'; {}", name,
          known.empty() ? std::string("the config has no layer with 'interface: inputs'")
                        : suggest(name, known, "the inputs")));
    }
    InputTable::Entry& entry = found->second;
    // One conversion for every value type, a plugin's too: the value's JSON read as a config
    // value is read.
    std::string json;
    try {
      json = py::cast<std::string>(py::module_::import("json").attr("dumps")(value));
    } catch (const py::error_already_set&) {
      throw py::type_error(
          fmt::format("set_input(): value for '{}' (type {}) must be a JSON "
                      "value, not {}",
                      name, entry.type->name,
                      py::str(py::type::of(value).attr("__name__")).cast<std::string>()));
    }
    Diagnostics diagnostics;
    const auto node = parse_document(json, "<value>", DocumentFormat::kJson, diagnostics);
    ValueBox box(*entry.type);
    std::string expected;
    if (!node || !entry.type->from_node(*node, box.data(), expected)) {
      throw py::type_error(
          fmt::format("set_input(): value for '{}' has type {}: it needs {}, "
                      "found {}",
                      name, entry.type->name, expected, node ? node->describe() : json));
    }
    entry.value = std::move(box);
    entry.set = true;
  }

  std::vector<std::string> inputs() const {
    std::vector<std::string> names;
    for (const auto& [name, entry] : table_->entries) names.push_back(name);
    return names;
  }

  void pause() {
    paused_ = true;
    manager_->safe_pass();
  }
  void resume() { paused_ = false; }
  bool paused() const { return paused_; }

  py::dict reload() {
    ReloadResult result = reloader_->reload(*manager_);
    if (!result.staged) raise_config_error(result.diagnostics);
    py::dict out;
    std::vector<std::string> changes;
    for (const auto& change : result.diff.changes) {
      ProgramDiff one;
      one.changes.push_back(change);
      std::string line = format(one, "");
      if (!line.empty() && line.back() == '\n') line.pop_back();
      changes.push_back(line);
    }
    out["changes"] = changes;
    out["restarted"] = result.restarted;
    out["warnings"] = to_python(result.diagnostics);
    return out;
  }

  void trace(const std::filesystem::path& path) {
    if (trace_) throw py::value_error("trace(): this manager writes a trace already");
    trace_file_.open(path, std::ios::binary | std::ios::trunc);
    if (!trace_file_)
      throw py::value_error(fmt::format("trace(): cannot write '{}'", path.string()));
    trace_ = std::make_unique<TraceWriter>(trace_file_);
    manager_->add_observer(*trace_);
  }

  void finish() {
    manager_->finish();
    if (trace_) trace_file_.flush();
  }

  Manager& manager() { return *manager_; }

 private:
  void feed_inputs_layers(Model& model) {
    const ClassInfo* builtin =
        session_->registry.find_class(ClassKind::kInterface, kInputsInterface);
    for (auto& layer : model.layers) {
      if (builtin == nullptr || layer.interface != builtin) continue;
      layer.interface = &table_->interface_class;
      for (const auto& actuator : layer.actuators) {
        if (actuator.type == nullptr) continue;
        auto& entry = table_->entries[actuator.name.text];
        // A reload that changes an input's type forgets its value.
        if (entry.type != actuator.type) entry = {actuator.type, ValueBox(*actuator.type), false};
      }
    }
  }

  std::shared_ptr<Session> session_;
  std::unique_ptr<InputTable> table_;
  std::unique_ptr<Reloader> reloader_;
  std::optional<Manager> manager_;
  std::ofstream trace_file_;
  std::unique_ptr<TraceWriter> trace_;
  bool paused_ = false;
};

}  // namespace

void bind_manager(py::module_& m) {
  py::class_<PyManager>(m, "Manager",
                        "A program running: step it, read its levels, actuators and states, feed "
                        "its `interface: inputs` layers, pause and reload it.")
      .def(py::init<const PyProgram&>(), py::arg("program"))
      .def("step", &PyManager::step, py::arg("count") = 1,
           "Runs `count` steps (fewer if the manager stops).")
      .def_property_readonly("steps", [](PyManager& self) { return self.manager().steps(); })
      .def_property_readonly("stopped", [](PyManager& self) { return self.manager().stopped(); })
      .def_property_readonly("stop_reason",
                             [](PyManager& self) { return self.manager().stop_reason(); })
      .def(
          "levels",
          [](PyManager& self, const std::string& behaviour) {
            return self.levels(self.behaviour(behaviour));
          },
          py::arg("behaviour"),
          "{'activation', 'requested', 'active'} of a behaviour ('name' or 'layer/name').")
      .def("all_levels", &PyManager::all_levels, "levels() of every behaviour, by 'layer/name'.")
      .def(
          "activation",
          [](PyManager& self, const std::string& behaviour) {
            return self.manager().activation(self.behaviour(behaviour));
          },
          py::arg("behaviour"))
      .def(
          "requested",
          [](PyManager& self, const std::string& behaviour) {
            return self.manager().requested(self.behaviour(behaviour));
          },
          py::arg("behaviour"))
      .def(
          "active",
          [](PyManager& self, const std::string& behaviour) {
            return self.manager().active(self.behaviour(behaviour));
          },
          py::arg("behaviour"))
      .def("actuator", &PyManager::actuator, py::arg("name"),
           "An actuator's value: bool, int, float, str, a tuple for vec2 and vec3.")
      .def("actuators", &PyManager::actuators, "Every actuator's value, by name.")
      .def("state", &PyManager::state, py::arg("machine"),
           "A state machine's current state, or None (before its first step, once finished).")
      .def("states", &PyManager::states, "state() of every state machine, by name.")
      .def("status", &PyManager::status, py::arg("machine"), "'running', 'finished' or 'error'.")
      .def("error", &PyManager::error, py::arg("machine"),
           "Why a state machine of status 'error' stopped (the controller, the state and the "
           "reason, a Python state's traceback with it), else None.")
      .def("set_input", &PyManager::set_input, py::arg("name"), py::arg("value"),
           "Gives an actuator of an `interface: inputs` layer the value it holds from the next "
           "step on.")
      .def_property_readonly("inputs", &PyManager::inputs, "The actuators set_input() can feed.")
      .def("pause", &PyManager::pause,
           "The safe-value pass of a pausing engine; while paused, each step() is followed by "
           "one, as a live view's single step is.")
      .def("resume", &PyManager::resume)
      .def_property_readonly("paused", &PyManager::paused)
      .def("reload", &PyManager::reload,
           "Loads the config again and swaps it in at the next step (as `arbiter run --watch`); "
           "raises ConfigError, the run untouched, when it has errors.")
      .def("trace", &PyManager::trace, py::arg("path"),
           "Writes the run's JSON-lines trace to `path` from the next step on.")
      .def("finish", &PyManager::finish, "Ends the run: the safe-value pass, the trace closed.");
}

}  // namespace arbiter::python

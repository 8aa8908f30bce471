// Behaviour and state classes written in Python (`plugins: [{python: MODULE}]`, docs/python.md):
// the module is imported and each of its arbiter.Behaviour and arbiter.State subclasses registered
// as a class whose params (and a behaviour's ports) the config is checked against, as a C++
// class's are. Every callback calls
// into Python with the GIL held: this is for prototyping, not for the real-time path (no
// zero-allocation guarantee). A Python exception is a C++ exception to the manager
// (py::error_already_set, its message with the traceback), so it is handled as a C++ fault.

#include <fmt/format.h>
#include <pybind11/stl.h>

#include <filesystem>
#include <typeinfo>
#include <variant>

#include "arbiter/init_context.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/state.hpp"
#include "module.hpp"

namespace arbiter::python {

namespace {

/// A port of a Python class: its name, direction and built-in value type.
struct PyPort {
  std::string name;
  bool input = true;
  const std::type_info* type = nullptr;
};

/// What every instance of one Python class shares.
struct PyClass {
  py::object cls;
  std::vector<std::string> params;
  std::vector<PyPort> ports;
};

/// A Python class's instance and the context object its callbacks get, owned by a behaviour or
/// state. A program may be freed by a thread that does not hold the GIL (a reload's retiring
/// one), or after the interpreter is gone (then the objects go with it).
struct PyInstance {
  py::object instance;
  py::object context;

  PyInstance() = default;
  PyInstance(const PyInstance&) = delete;
  PyInstance& operator=(const PyInstance&) = delete;
  ~PyInstance() {
    if (Py_IsInitialized() == 0) {
      instance.release();
      context.release();
      return;
    }
    py::gil_scoped_acquire gil;
    instance = py::object();
    context = py::object();
  }
};

class PyBehaviour;

/// The context a Python callback gets: reads its inputs and, in execute(), writes its outputs, by
/// port name. One per instance, pointed at each call's C++ context.
class PyContext {
 public:
  const StepContext* step = nullptr;
  ExecuteContext* execute = nullptr;
  const PyBehaviour* owner = nullptr;

  std::uint64_t step_number() const { return step->step(); }
  double activation() const {
    if (execute == nullptr) throw py::attribute_error("activation is known in execute() only");
    return execute->activation();
  }
  py::object read(const std::string& port) const;
  void write(const std::string& port, const py::object& value);
};

class PyBehaviour final : public Behaviour {
 public:
  explicit PyBehaviour(std::shared_ptr<const PyClass> cls)
      : class_(std::move(cls)), params_(class_->params.size()), handles_(class_->ports.size()) {
    context_.owner = this;
  }

  void set_param(std::size_t index, const ParamValue& value) { params_[index] = value; }
  void set_handle(std::size_t index, std::uint32_t handle) { handles_[index] = handle; }

  void init(BehaviourInitContext&) override {
    python_.instance = class_->cls();
    for (std::size_t i = 0; i < params_.size(); ++i) {
      py::object value = std::visit(
          [](const auto& v) -> py::object {
            using T = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<T, Vec2>)
              return py::make_tuple(v.x, v.y);
            else if constexpr (std::is_same_v<T, Vec3>)
              return py::make_tuple(v.x, v.y, v.z);
            else if constexpr (std::is_same_v<T, Node>)
              return py::none();
            else
              return py::cast(v);
          },
          params_[i]);
      py::setattr(python_.instance, class_->params[i].c_str(), value);
    }
    python_.context = py::cast(&context_, py::return_value_policy::reference);
    has_update_ = py::hasattr(python_.instance, "update");
    has_execute_ = py::hasattr(python_.instance, "execute");
    has_inhibited_ = py::hasattr(python_.instance, "inhibited");
  }

  void update(const StepContext& ctx) override {
    if (has_update_) call("update", ctx, nullptr);
  }
  double activation(const StepContext& ctx) override {
    return call("activation", ctx, nullptr).cast<double>();
  }
  void execute(ExecuteContext& ctx) override {
    if (has_execute_) call("execute", ctx, &ctx);
  }
  void inhibited(const InhibitedContext& ctx) override {
    if (has_inhibited_) call("inhibited", ctx, nullptr);
  }

  const PyClass& cls() const { return *class_; }
  std::uint32_t handle(std::size_t port) const { return handles_[port]; }

 private:
  py::object call(const char* method, const StepContext& ctx, ExecuteContext* execute) {
    context_.step = &ctx;
    context_.execute = execute;
    return python_.instance.attr(method)(python_.context);
  }

  std::shared_ptr<const PyClass> class_;
  std::vector<ParamValue> params_;
  std::vector<std::uint32_t> handles_;
  PyContext context_;
  PyInstance python_;  // after context_, which its context object points to: destroyed first
  bool has_update_ = false;
  bool has_execute_ = false;
  bool has_inhibited_ = false;
};

std::size_t find_port(const PyClass& cls, const std::string& name, bool input) {
  for (std::size_t i = 0; i < cls.ports.size(); ++i) {
    if (cls.ports[i].name == name && cls.ports[i].input == input) return i;
  }
  std::vector<std::string> known;
  for (const auto& port : cls.ports) {
    if (port.input == input) known.push_back(port.name);
  }
  throw py::key_error(
      fmt::format("no {} port '{}'; {}", input ? "input" : "output", name,
                  known.empty() ? std::string("it declares none") : suggest(name, known)));
}

py::object PyContext::read(const std::string& port) const {
  const PyClass& cls = owner->cls();
  const std::size_t index = find_port(cls, port, true);
  const std::uint32_t handle = owner->handle(index);
  const std::type_info& type = *cls.ports[index].type;
  if (type == typeid(bool)) return py::bool_(step->read(Input<bool>{handle}));
  if (type == typeid(std::int64_t)) return py::int_(step->read(Input<std::int64_t>{handle}));
  if (type == typeid(double)) return py::float_(step->read(Input<double>{handle}));
  if (type == typeid(std::string)) return py::str(step->read(Input<std::string>{handle}));
  if (type == typeid(Vec2)) {
    const Vec2& v = step->read(Input<Vec2>{handle});
    return py::make_tuple(v.x, v.y);
  }
  const Vec3& v = step->read(Input<Vec3>{handle});
  return py::make_tuple(v.x, v.y, v.z);
}

void PyContext::write(const std::string& port, const py::object& value) {
  if (execute == nullptr) throw py::attribute_error("outputs are written in execute() only");
  const PyClass& cls = owner->cls();
  const std::size_t index = find_port(cls, port, false);
  const std::uint32_t handle = owner->handle(index);
  const std::type_info& type = *cls.ports[index].type;
  if (type == typeid(bool)) {
    execute->write(Output<bool>{handle}, value.cast<bool>());
  } else if (type == typeid(std::int64_t)) {
    execute->write(Output<std::int64_t>{handle}, value.cast<std::int64_t>());
  } else if (type == typeid(double)) {
    execute->write(Output<double>{handle}, value.cast<double>());
  } else if (type == typeid(std::string)) {
    execute->write(Output<std::string>{handle}, value.cast<std::string>());
  } else if (type == typeid(Vec2)) {
    const auto v = value.cast<std::vector<double>>();
    if (v.size() != 2) throw py::type_error(fmt::format("output '{}' is a vec2: 2 numbers", port));
    execute->write(Output<Vec2>{handle}, Vec2{v[0], v[1]});
  } else {
    const auto v = value.cast<std::vector<double>>();
    if (v.size() != 3) throw py::type_error(fmt::format("output '{}' is a vec3: 3 numbers", port));
    execute->write(Output<Vec3>{handle}, Vec3{v[0], v[1], v[2]});
  }
}

/// What every pooled object of one Python state class shares.
struct PyStateClass {
  py::object cls;
  std::vector<std::string> params;
  std::vector<ParamKind> kinds;
};

/// The context a Python state's callback gets, mirroring StateContext: the step and cycle, the
/// instance's executions and params, terminate(). Pointed at each call's C++ context.
class PyStateContext {
 public:
  StateContext* state = nullptr;
  const PyStateClass* cls = nullptr;
  const std::vector<std::uint32_t>* handles = nullptr;

  StateContext& context() const {
    if (state == nullptr)
      throw py::attribute_error("a state's context is valid in its callbacks only");
    return *state;
  }
  std::uint64_t step() const { return context().step(); }
  std::uint64_t cycle() const { return context().cycle(); }
  std::uint64_t executions() const { return context().executions(); }
  void terminate() { context().terminate(); }
  py::object param(const std::string& name) const {
    StateContext& ctx = context();
    for (std::size_t i = 0; i < cls->params.size(); ++i) {
      if (cls->params[i] != name) continue;
      const std::uint32_t index = (*handles)[i];
      switch (cls->kinds[i]) {
        case ParamKind::kBool:
          return py::bool_(ctx.param(StateParam<bool>{index}));
        case ParamKind::kInt:
          return py::int_(ctx.param(StateParam<std::int64_t>{index}));
        case ParamKind::kDouble:
          return py::float_(ctx.param(StateParam<double>{index}));
        case ParamKind::kString:
          return py::str(ctx.param(StateParam<std::string>{index}));
        default:
          return py::cast(ctx.param(StateParam<std::vector<double>>{index}));
      }
    }
    throw py::key_error(fmt::format(
        "no param '{}'; {}", name,
        cls->params.empty() ? std::string("the state declares none") : suggest(name, cls->params)));
  }
};

class PyState final : public State {
 public:
  explicit PyState(std::shared_ptr<const PyStateClass> cls)
      : class_(std::move(cls)), handles_(class_->params.size(), kNoIndex) {
    context_.cls = class_.get();
    context_.handles = &handles_;
  }

  void set_handle(std::size_t param, std::uint32_t index) { handles_[param] = index; }

  void init(StateInitContext&) override {
    python_.instance = class_->cls();
    python_.context = py::cast(&context_, py::return_value_policy::reference);
    has_activate_ = py::hasattr(python_.instance, "activate");
    has_deactivate_ = py::hasattr(python_.instance, "deactivate");
  }
  void activate(StateContext& ctx) override {
    if (has_activate_) call("activate", ctx);
  }
  StateResult execute(StateContext& ctx) override {
    const py::object result = call("execute", ctx);
    if (py::isinstance<py::str>(result)) {
      const std::string text = result.cast<std::string>();
      if (text == "hold") return StateResult::kHold;
      if (text == "proceed") return StateResult::kProceed;
    }
    throw py::type_error(
        fmt::format("{}.execute() returned {}: it returns State.HOLD or State.PROCEED",
                    py::str(class_->cls.attr("__name__")).cast<std::string>(),
                    py::repr(result).cast<std::string>()));
  }
  void deactivate(StateContext& ctx) override {
    if (has_deactivate_) call("deactivate", ctx);
  }

 private:
  py::object call(const char* method, StateContext& ctx) {
    context_.state = &ctx;
    py::object result = python_.instance.attr(method)(python_.context);
    context_.state = nullptr;
    return result;
  }

  std::shared_ptr<const PyStateClass> class_;
  std::vector<std::uint32_t> handles_;
  PyStateContext context_;
  PyInstance python_;  // after context_, which its context object points to: destroyed first
  bool has_activate_ = false;
  bool has_deactivate_ = false;
};

const std::type_info* value_type(const std::string& name) {
  if (name == "bool") return &typeid(bool);
  if (name == "int") return &typeid(std::int64_t);
  if (name == "double") return &typeid(double);
  if (name == "string") return &typeid(std::string);
  if (name == "vec2") return &typeid(Vec2);
  if (name == "vec3") return &typeid(Vec3);
  return nullptr;
}

/// A param's kind and default from its declaration: a default value (its type gives the kind)
/// or a type (required).
void declare_param(ParamSpec& spec, const py::handle& declared) {
  const py::module_ builtins = py::module_::import("builtins");
  const auto is = [&](const char* type) {
    return declared.is(builtins.attr(type)) || py::isinstance(declared, builtins.attr(type));
  };
  const bool required = py::isinstance<py::type>(declared);
  if (is("bool")) {
    spec.kind = ParamKind::kBool;
    if (!required) spec.default_value = declared.cast<bool>();
  } else if (is("int")) {
    spec.kind = ParamKind::kInt;
    if (!required) spec.default_value = declared.cast<std::int64_t>();
  } else if (is("float")) {
    spec.kind = ParamKind::kDouble;
    if (!required) spec.default_value = declared.cast<double>();
  } else if (is("str")) {
    spec.kind = ParamKind::kString;
    if (!required) spec.default_value = declared.cast<std::string>();
  } else if (is("list")) {
    spec.kind = ParamKind::kDoubleList;
    if (!required) spec.default_value = declared.cast<std::vector<double>>();
  } else {
    throw std::invalid_argument(fmt::format(
        "param '{}' is declared as {}: give a default (bool, int, float, str, list of floats) "
        "or one of those types (required)",
        spec.name, py::repr(declared).cast<std::string>()));
  }
}

/// Registers one arbiter.Behaviour subclass; throws std::invalid_argument with what is wrong.
void register_behaviour(Registry& registry, const py::handle& cls, const std::string& module) {
  auto shared = std::make_shared<PyClass>();
  shared->cls = py::reinterpret_borrow<py::object>(cls);
  const std::string name = cls.attr("name").cast<std::string>();
  ClassInfo& info = registry.add_class(name, ClassKind::kBehaviour);
  info.origin = fmt::format("Python module {}", module);
  if (py::object doc = cls.attr("__doc__"); !doc.is_none()) {
    info.description = py::module_::import("inspect").attr("cleandoc")(doc).cast<std::string>();
  }
  for (const auto& [key, declared] : cls.attr("params").cast<py::dict>()) {
    const std::uint32_t index = static_cast<std::uint32_t>(shared->params.size());
    shared->params.push_back(key.cast<std::string>());
    ParamSpec& spec = info.params.emplace_back();
    spec.name = shared->params.back();
    declare_param(spec, declared);
    spec.bind = [index](void* instance, const ParamValue& value, std::uint32_t) {
      static_cast<PyBehaviour*>(static_cast<Behaviour*>(instance))->set_param(index, value);
    };
  }
  for (const bool input : {true, false}) {
    for (const auto& [key, declared] : cls.attr(input ? "inputs" : "outputs").cast<py::dict>()) {
      PyPort port{key.cast<std::string>(), input, value_type(declared.cast<std::string>())};
      if (port.type == nullptr) {
        throw std::invalid_argument(fmt::format(
            "port '{}' has type '{}': the types are bool, int, double, string, vec2, vec3",
            port.name, declared.cast<std::string>()));
      }
      const std::uint32_t index = static_cast<std::uint32_t>(shared->ports.size());
      PortSpec& spec = info.ports.emplace_back();
      spec.name = port.name;
      spec.direction = input ? PortDirection::kInput : PortDirection::kOutput;
      spec.cpp_type = port.type;
      spec.bind = [index](void* instance, std::uint32_t handle) {
        static_cast<PyBehaviour*>(static_cast<Behaviour*>(instance))->set_handle(index, handle);
      };
      shared->ports.push_back(std::move(port));
    }
  }
  info.make_behaviour = [shared]() -> std::unique_ptr<Behaviour> {
    return std::make_unique<PyBehaviour>(shared);
  };
}

/// Registers one arbiter.State subclass; throws std::invalid_argument with what is wrong.
void register_state(Registry& registry, const py::handle& cls, const std::string& module) {
  auto shared = std::make_shared<PyStateClass>();
  shared->cls = py::reinterpret_borrow<py::object>(cls);
  const std::string name = cls.attr("name").cast<std::string>();
  ClassInfo& info = registry.add_class(name, ClassKind::kState);
  info.origin = fmt::format("Python module {}", module);
  if (py::object doc = cls.attr("__doc__"); !doc.is_none()) {
    info.description = py::module_::import("inspect").attr("cleandoc")(doc).cast<std::string>();
  }
  for (const auto& [key, declared] : cls.attr("params").cast<py::dict>()) {
    const std::size_t position = shared->params.size();
    shared->params.push_back(key.cast<std::string>());
    ParamSpec& spec = info.params.emplace_back();
    spec.name = shared->params.back();
    declare_param(spec, declared);
    shared->kinds.push_back(spec.kind);
    // Per planned instance, as a C++ state's StateParam: the object gets the param's index and
    // reads the instance's value in a step.
    spec.member_is_handle = true;
    spec.bind = [position](void* instance, const ParamValue&, std::uint32_t index) {
      static_cast<PyState*>(static_cast<State*>(instance))->set_handle(position, index);
    };
  }
  info.make_state = [shared]() -> std::unique_ptr<State> {
    return std::make_unique<PyState>(shared);
  };
}

/// The exception as Python prints its last line, and a note per frame of the module's own code
/// (not the import machinery's): the user's file and line, where the import failed.
void report_import_failure(const py::error_already_set& error, const SourceLocation& where,
                           const std::string& module, Diagnostics& diagnostics) {
  const py::module_ traceback = py::module_::import("traceback");
  // Its last line ("SyntaxError: invalid syntax"); a SyntaxError's lines before it show the
  // source, which its note gives with the place.
  const py::list lines = traceback.attr("format_exception_only")(error.type(), error.value());
  std::string text = lines.empty() ? std::string(error.what())
                                   : py::str(lines[lines.size() - 1]).cast<std::string>();
  while (!text.empty() && text.back() == '\n') text.pop_back();
  Diagnostic& reported =
      diagnostics.error(where, "python-plugin-failed",
                        fmt::format("cannot load Python module '{}': {}", module, text));
  if (error.matches(PyExc_SyntaxError)) {
    const py::object value = error.value();
    reported.notes.push_back(
        fmt::format("{}:{}: {}", py::str(value.attr("filename")).cast<std::string>(),
                    py::str(value.attr("lineno")).cast<std::string>(),
                    py::str(value.attr("text")).attr("strip")().cast<std::string>()));
  }
  if (!error.trace()) return;
  for (const auto& frame : traceback.attr("extract_tb")(error.trace())) {
    const auto file = frame.attr("filename").cast<std::string>();
    if (file.empty() || file.front() == '<') continue;  // <frozen importlib._bootstrap> and such
    reported.notes.push_back(fmt::format(
        "{}:{}: in {}: {}", file, frame.attr("lineno").cast<long>(),
        frame.attr("name").cast<std::string>(), py::str(frame.attr("line")).cast<std::string>()));
  }
}

}  // namespace

bool import_python_plugin(const Node& node, const std::string& config, Registry& registry,
                          Diagnostics& diagnostics) {
  const std::string module = node.text();
  // Registered as loaded even when it fails: a config names a module once, and a reload does
  // not import it again (docs/python.md).
  registry.keep_loaded(python_plugin_library(module), nullptr);
  // A module beside the config is found as a plugin library beside it is.
  const py::module_ sys = py::module_::import("sys");
  const std::string directory = std::filesystem::path(config).parent_path().string();
  py::list path = sys.attr("path");
  path.insert(0, directory.empty() ? "." : directory);
  const std::size_t errors = diagnostics.error_count();
  try {
    py::module_ imported = py::module_::import(module.c_str());
    const py::module_ arbiter = py::module_::import("arbiter");
    const py::object state = arbiter.attr("State");
    for (const auto& cls : py::list(arbiter.attr("_classes_in")(imported))) {
      if (PyObject_IsSubclass(cls.ptr(), state.ptr()) == 1) {
        register_state(registry, cls, module);
      } else {
        register_behaviour(registry, cls, module);
      }
    }
  } catch (const py::error_already_set& error) {
    report_import_failure(error, node.location(), module, diagnostics);
  } catch (const std::exception& error) {
    diagnostics.error(node.location(), "python-plugin-failed",
                      fmt::format("Python module '{}': {}", module, error.what()));
  }
  path.attr("pop")(0);
  return diagnostics.error_count() == errors;
}

void bind_plugins(py::module_& m) {
  py::class_<PyContext>(m, "Context",
                        "What a Python behaviour's callback may do: read its inputs, and in "
                        "execute() write its outputs, by port name.")
      .def_property_readonly("step", &PyContext::step_number, "The step, counting from 1.")
      .def_property_readonly("activation", &PyContext::activation,
                             "In execute(): this behaviour's refined activation level.")
      .def("read", &PyContext::read, py::arg("port"))
      .def("write", &PyContext::write, py::arg("port"), py::arg("value"));
  py::class_<PyStateContext>(m, "StateContext",
                             "What a Python state's callback may do, as a C++ state's "
                             "StateContext: read the planned instance's params, terminate.")
      .def_property_readonly("step", &PyStateContext::step, "The step, counting from 1.")
      .def_property_readonly("cycle", &PyStateContext::cycle,
                             "The controller's cycle (1 in its first step).")
      .def_property_readonly("executions", &PyStateContext::executions,
                             "How many times this instance executed before this call.")
      .def("param", &PyStateContext::param, py::arg("name"),
           "This instance's param: its planned value, else the state's, else the default.")
      .def("terminate", &PyStateContext::terminate,
           "Ends the state machine in this step (status 'finished').");
}

}  // namespace arbiter::python

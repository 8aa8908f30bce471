// A trace (JSON lines) or recording (MCAP) read back through the engine's reader (tools/read), as
// `arbiter replay`, `diff` and `plot` read them: step by step, or whole as columns for a
// DataFrame. The columns are built here, one array each, never a Python object per step.

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <unordered_map>

#include "arbiter/trace_reader.hpp"
#include "module.hpp"

namespace arbiter::python {

namespace {

// Ordered: the columns come in the trace's order, each layer's behaviours in execution order.
using Json = nlohmann::ordered_json;

[[noreturn]] void raise_bad_file(const TraceSource& source) {
  throw py::value_error(source.error() ? format(*source.error()) : "unreadable recording");
}

py::object parse(const std::string& text) {
  return py::module_::import("json").attr("loads")(text);
}

/// One DataFrame column, filled a row at a time; a row that does not set it gets NaN (numbers),
/// false (flags) or None (text).
struct Column {
  enum class Kind { kNumber, kFlag, kText };
  std::string name;
  Kind kind = Kind::kNumber;
  std::vector<double> numbers;
  std::vector<char> flags;
  std::vector<std::string> texts;
  std::vector<char> has_text;

  std::size_t size() const {
    return kind == Kind::kNumber ? numbers.size()
           : kind == Kind::kFlag ? flags.size()
                                 : texts.size();
  }
  void pad(std::size_t rows) {
    switch (kind) {
      case Kind::kNumber:
        numbers.resize(rows, std::numeric_limits<double>::quiet_NaN());
        break;
      case Kind::kFlag:
        flags.resize(rows, 0);
        break;
      case Kind::kText:
        texts.resize(rows);
        has_text.resize(rows, 0);
        break;
    }
  }
};

class Columns {
 public:
  void number(const std::string& name, double value) {
    Column& c = column(name, Column::Kind::kNumber);
    if (c.kind == Column::Kind::kNumber) c.numbers.push_back(value);
  }
  void flag(const std::string& name, bool value) {
    Column& c = column(name, Column::Kind::kFlag);
    if (c.kind == Column::Kind::kFlag) c.flags.push_back(value ? 1 : 0);
  }
  void text(const std::string& name, std::string value) {
    Column& c = column(name, Column::Kind::kText);
    if (c.kind != Column::Kind::kText) return;
    c.texts.push_back(std::move(value));
    c.has_text.push_back(1);
  }
  /// A value of an actuator: a number or flag is one column, a vector one per component.
  void value(const std::string& name, const Json& value) {
    if (value.is_boolean()) {
      flag(name, value.get<bool>());
    } else if (value.is_number()) {
      number(name, value.get<double>());
    } else if (value.is_string()) {
      text(name, value.get<std::string>());
    } else if (value.is_array() && !value.empty() &&
               std::all_of(value.begin(), value.end(),
                           [](const Json& v) { return v.is_number(); })) {
      for (std::size_t i = 0; i < value.size(); ++i) {
        number(fmt::format("{}[{}]", name, i), value[i].get<double>());
      }
    } else {
      text(name, value.dump());
    }
  }
  /// Ends a row: every column it did not set gets the missing value.
  void end_row() {
    ++rows_;
    for (auto& c : columns_) {
      if (c.size() < rows_) c.pad(rows_);
    }
  }
  std::size_t rows() const { return rows_; }
  const std::vector<Column>& all() const { return columns_; }

 private:
  /// The column `name`; a new one is filled with missing values up to this row. A value of
  /// another kind than the column's first (a reload that changed a type) is dropped.
  Column& column(const std::string& name, Column::Kind kind) {
    const auto found = index_.find(name);
    if (found != index_.end()) return columns_[found->second];
    index_.emplace(name, columns_.size());
    Column& c = columns_.emplace_back();
    c.name = name;
    c.kind = kind;
    c.pad(rows_);
    return c;
  }

  std::vector<Column> columns_;
  std::unordered_map<std::string, std::size_t> index_;
  std::size_t rows_ = 0;
};

void add_step(const Json& record, Columns& columns) {
  columns.number("step", record.at("step").get<double>());
  if (const auto t = record.find("t"); t != record.end() && t->is_number()) {
    columns.number("t", t->get<double>());
  }
  if (const auto layers = record.find("layers"); layers != record.end() && layers->is_object()) {
    std::string name;
    for (const auto& [layer, behaviours] : layers->items()) {
      if (!behaviours.is_object()) continue;
      for (const auto& [behaviour, levels] : behaviours.items()) {
        if (!levels.is_object()) continue;
        name = layer + "/" + behaviour;
        for (const char* level : {"activation", "requested"}) {
          const auto found = levels.find(level);
          if (found != levels.end() && found->is_number()) {
            columns.number(name + "." + level, found->get<double>());
          }
        }
        const auto active = levels.find("active");
        if (active != levels.end() && active->is_boolean()) {
          columns.flag(name + ".active", active->get<bool>());
        }
      }
    }
  }
  if (const auto actuators = record.find("actuators");
      actuators != record.end() && actuators->is_object()) {
    for (const auto& [actuator, entry] : actuators->items()) {
      const auto value = entry.find("value");
      if (entry.is_object() && value != entry.end()) columns.value(actuator, *value);
    }
  }
  if (const auto controllers = record.find("controllers");
      controllers != record.end() && controllers->is_object()) {
    for (const auto& [controller, entry] : controllers->items()) {
      if (!entry.is_object()) continue;
      for (const char* field : {"state", "status"}) {
        const auto found = entry.find(field);
        if (found != entry.end() && found->is_string()) {
          columns.text(controller + "." + field, found->get<std::string>());
        }
      }
    }
  }
  columns.end_row();
}

class PyRecording {
 public:
  explicit PyRecording(const std::filesystem::path& path)
      : path_(path.string()), source_(open_trace(path_)) {
    TraceRecord record;
    if (!source_->next(record)) raise_bad_file(*source_);
    header_ = parse(record.text);
  }

  py::object next() {
    TraceRecord record;
    while (source_->next(record)) {
      if (record.kind == TraceRecord::Kind::kStep) return parse(record.text);
      if (record.kind == TraceRecord::Kind::kReload) header_ = parse(record.text);
    }
    if (source_->error()) raise_bad_file(*source_);
    throw py::stop_iteration();
  }

  /// Every step of the file (read again from its start), as named columns.
  py::tuple columns() const {
    auto source = open_trace(path_);
    Columns columns;
    TraceRecord record;
    {
      py::gil_scoped_release released;
      while (source->next(record)) {
        if (record.kind != TraceRecord::Kind::kStep) continue;
        add_step(Json::parse(record.text), columns);
      }
    }
    if (source->error()) raise_bad_file(*source);
    py::list names;
    py::list arrays;
    for (const auto& c : columns.all()) {
      names.append(c.name);
      switch (c.kind) {
        case Column::Kind::kNumber:
          arrays.append(
              py::array_t<double>(static_cast<py::ssize_t>(c.numbers.size()), c.numbers.data()));
          break;
        case Column::Kind::kFlag: {
          py::array_t<bool> flags(static_cast<py::ssize_t>(c.flags.size()));
          std::copy(c.flags.begin(), c.flags.end(), flags.mutable_data());
          arrays.append(std::move(flags));
          break;
        }
        case Column::Kind::kText: {
          py::list texts;
          for (std::size_t i = 0; i < c.texts.size(); ++i) {
            if (c.has_text[i] != 0) {
              texts.append(py::str(c.texts[i]));
            } else {
              texts.append(py::none());
            }
          }
          arrays.append(std::move(texts));
          break;
        }
      }
    }
    return py::make_tuple(names, arrays, source->truncated());
  }

  const py::object& header() const { return header_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<TraceSource> source_;
  py::object header_;
};

}  // namespace

void bind_recording(py::module_& m) {
  py::class_<PyRecording>(m, "Recording",
                          "A trace (.jsonl) or recording (.mcap) read back: iterate it for its "
                          "step records (dicts, as the trace has them), or to_dataframe().")
      .def(py::init<const std::filesystem::path&>(), py::arg("path"))
      .def("__iter__", [](PyRecording& self) -> PyRecording& { return self; })
      .def("__next__", &PyRecording::next)
      .def_property_readonly("header", &PyRecording::header,
                             "The header of the program the last step read ran (a reload "
                             "replaces it).")
      .def_property_readonly("path", &PyRecording::path)
      .def("_columns", &PyRecording::columns);
}

}  // namespace arbiter::python

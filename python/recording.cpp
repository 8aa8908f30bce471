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

/// Fills one row of `columns` from a step record as it is parsed (a SAX handler: no tree is
/// built): the record's fields in the order the trace writes them, docs/semantics.md.
class StepHandler final : public nlohmann::json_sax<nlohmann::json> {
 public:
  explicit StepHandler(Columns& columns) : columns_(columns) {}

  bool null() override { return element(); }
  bool boolean(bool value) override {
    if (const std::string* name = column_name()) {
      columns_.flag(*name, value);
    }
    return element();
  }
  bool number_integer(number_integer_t value) override {
    return number(static_cast<double>(value));
  }
  bool number_unsigned(number_unsigned_t value) override {
    return number(static_cast<double>(value));
  }
  bool number_float(number_float_t value, const string_t&) override { return number(value); }
  bool string(string_t& value) override {
    if (const std::string* name = column_name()) columns_.text(*name, std::move(value));
    return element();
  }
  bool binary(binary_t&) override { return element(); }
  bool start_object(std::size_t) override { return open(false); }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(true); }
  bool end_array() override { return close(); }
  bool key(string_t& key) override {
    open_.back().key = std::move(key);
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;  // the reader has checked the record: this does not happen
  }

 private:
  struct Open {
    bool array = false;
    std::string key;          // in an object: the key of the value being read
    std::size_t element = 0;  // in an array: the index of the value being read
  };

  bool number(double value) {
    if (const std::string* name = column_name()) columns_.number(*name, value);
    return element();
  }
  bool open(bool array) {
    open_.push_back({array, {}, 0});
    return true;
  }
  bool close() {
    open_.pop_back();
    return element();
  }
  /// After a value: the next one of an array has the next index.
  bool element() {
    if (!open_.empty() && open_.back().array) ++open_.back().element;
    return true;
  }
  bool at(std::size_t depth, const char* key) const {
    return !open_[depth].array && open_[depth].key == key;
  }
  /// The column of the scalar being read, or nullptr when it is no column.
  const std::string* column_name() {
    const std::size_t depth = open_.size();
    if (depth == 1 && (at(0, "step") || at(0, "t"))) return &open_[0].key;
    if (depth == 4 && at(0, "layers") && !open_[3].array &&
        (at(3, "activation") || at(3, "requested") || at(3, "active"))) {
      name_ = open_[1].key + '/' + open_[2].key + '.' + open_[3].key;
      return &name_;
    }
    if (at(0, "actuators") && depth >= 3 && at(2, "value")) {
      if (depth == 3) return &open_[1].key;
      if (depth == 4 && open_[3].array) {
        name_ = open_[1].key + '[' + std::to_string(open_[3].element) + ']';
        return &name_;
      }
    }
    if (depth == 3 && at(0, "controllers") && (at(2, "state") || at(2, "status"))) {
      name_ = open_[1].key + '.' + open_[2].key;
      return &name_;
    }
    return nullptr;
  }

  Columns& columns_;
  std::vector<Open> open_;
  std::string name_;
};

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
        StepHandler handler(columns);
        nlohmann::json::sax_parse(record.text, &handler);
        columns.end_row();
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

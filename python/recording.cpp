// A trace (JSON lines) or recording (MCAP) read back through the engine's reader (tools/read), as
// `arbiter replay`, `diff` and `plot` read them: step by step, or whole as columns for a
// DataFrame. The columns are built here, one array each, never a Python object per step.

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <limits>
#include <optional>
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
  /// The column `name`, made on first use with the kind of its first value (index()).
  std::size_t index(const std::string& name, Column::Kind kind) {
    const auto found = index_.find(name);
    if (found != index_.end()) return found->second;
    index_.emplace(name, columns_.size());
    Column& c = columns_.emplace_back();
    c.name = name;
    c.kind = kind;
    c.pad(rows_);
    return columns_.size() - 1;
  }
  // A value of another kind than the column's first (a reload that changed a type) is dropped.
  void number(std::size_t column, double value) {
    Column& c = columns_[column];
    if (c.kind == Column::Kind::kNumber) c.numbers.push_back(value);
  }
  void flag(std::size_t column, bool value) {
    Column& c = columns_[column];
    if (c.kind == Column::Kind::kFlag) c.flags.push_back(value ? 1 : 0);
  }
  void text(std::size_t column, std::string value) {
    Column& c = columns_[column];
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
  std::vector<Column> columns_;
  std::unordered_map<std::string, std::size_t> index_;
  std::size_t rows_ = 0;
};

/// Fills one row of `columns` from a step record as it is parsed (a SAX handler: no tree is
/// built): the record's fields in the order the trace writes them, docs/semantics.md. One handler
/// reads every record of a file: the records have the same shape, so the n-th value of a record
/// is looked for in the column the n-th value of the last record went to, which is checked by
/// its keys, not found again by its name.
class StepHandler final : public nlohmann::json_sax<nlohmann::json> {
 public:
  explicit StepHandler(Columns& columns) : columns_(columns) {}

  /// Before each record.
  void begin() {
    depth_in_use_ = 0;
    ordinal_ = 0;
  }

  bool null() override { return element(); }
  bool boolean(bool value) override {
    if (const auto c = column(Column::Kind::kFlag)) columns_.flag(*c, value);
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
    if (const auto c = column(Column::Kind::kText)) columns_.text(*c, std::move(value));
    return element();
  }
  bool binary(binary_t&) override { return element(); }
  bool start_object(std::size_t) override { return open(false); }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(true); }
  bool end_array() override { return close(); }
  bool key(string_t& key) override {
    // A copy: the parser's buffer and ours keep their capacity.
    open_[depth_in_use_ - 1].key.assign(key);
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
  /// Where a column's value is in a record.
  enum class Place { kTop, kLevel, kActuator, kActuatorElement, kController };
  /// The column the n-th value of the last record went to, and where that value was.
  struct Slot {
    Place place = Place::kTop;
    std::string keys[3];
    std::size_t element = 0;
    std::size_t column = 0;
  };

  bool number(double value) {
    if (const auto c = column(Column::Kind::kNumber)) columns_.number(*c, value);
    return element();
  }
  bool open(bool array) {
    // The entries are kept from record to record, with their keys' capacity.
    if (depth_in_use_ == open_.size()) open_.emplace_back();
    open_[depth_in_use_].array = array;
    open_[depth_in_use_].element = 0;
    open_[depth_in_use_].key.clear();
    ++depth_in_use_;
    return true;
  }
  bool close() {
    --depth_in_use_;
    return element();
  }
  /// After a value: the next one of an array has the next index.
  bool element() {
    if (depth_in_use_ > 0 && open_[depth_in_use_ - 1].array) ++open_[depth_in_use_ - 1].element;
    return true;
  }
  bool at(std::size_t depth, const char* key) const {
    return !open_[depth].array && open_[depth].key == key;
  }
  /// Where the scalar being read is, and the keys that name its column; nullopt: no column.
  std::optional<Place> place() const {
    const std::size_t depth = depth_in_use_;
    if (depth == 1 && (at(0, "step") || at(0, "t"))) return Place::kTop;
    if (depth == 4 && at(0, "layers") && !open_[3].array &&
        (at(3, "activation") || at(3, "requested") || at(3, "active"))) {
      return Place::kLevel;
    }
    if (at(0, "actuators") && depth >= 3 && at(2, "value")) {
      if (depth == 3) return Place::kActuator;
      if (depth == 4 && open_[3].array) return Place::kActuatorElement;
    }
    if (depth == 3 && at(0, "controllers") && (at(2, "state") || at(2, "status"))) {
      return Place::kController;
    }
    return std::nullopt;
  }
  /// The keys of open_ that name a column at `where`, and the array index for an element.
  void keys_of(Place where, const std::string* (&keys)[3], std::size_t& element) const {
    keys[0] = keys[1] = keys[2] = nullptr;
    element = 0;
    switch (where) {
      case Place::kTop:
        keys[0] = &open_[0].key;
        break;
      case Place::kLevel:
        keys[0] = &open_[1].key;
        keys[1] = &open_[2].key;
        keys[2] = &open_[3].key;
        break;
      case Place::kActuatorElement:
        element = open_[3].element;
        [[fallthrough]];
      case Place::kActuator:
        keys[0] = &open_[1].key;
        break;
      case Place::kController:
        keys[0] = &open_[1].key;
        keys[1] = &open_[2].key;
        break;
    }
  }
  static std::string column_name(Place where, const std::string* const (&keys)[3],
                                 std::size_t element) {
    switch (where) {
      case Place::kTop:
      case Place::kActuator:
        return *keys[0];
      case Place::kLevel:
        return *keys[0] + '/' + *keys[1] + '.' + *keys[2];
      case Place::kActuatorElement:
        return *keys[0] + '[' + std::to_string(element) + ']';
      case Place::kController:
        return *keys[0] + '.' + *keys[1];
    }
    return {};
  }
  /// The column of the scalar being read, or nullopt when it is no column.
  std::optional<std::size_t> column(Column::Kind kind) {
    const auto where = place();
    if (!where) return std::nullopt;
    const std::string* keys[3];
    std::size_t element = 0;
    keys_of(*where, keys, element);
    const std::size_t n = ordinal_++;
    if (n < slots_.size()) {
      const Slot& slot = slots_[n];
      bool same = slot.place == *where && slot.element == element;
      for (int i = 0; same && i < 3; ++i) same = keys[i] == nullptr || *keys[i] == slot.keys[i];
      if (same) return slot.column;
    } else {
      slots_.resize(n + 1);
    }
    Slot& slot = slots_[n];
    slot.place = *where;
    slot.element = element;
    for (int i = 0; i < 3; ++i) slot.keys[i] = keys[i] == nullptr ? std::string() : *keys[i];
    slot.column = columns_.index(column_name(*where, keys, element), kind);
    return slot.column;
  }

  Columns& columns_;
  std::vector<Open> open_;  // [0, depth_in_use_) are open
  std::size_t depth_in_use_ = 0;
  std::vector<Slot> slots_;
  std::size_t ordinal_ = 0;
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
      StepHandler handler(columns);
      while (source->next(record)) {
        if (record.kind != TraceRecord::Kind::kStep) continue;
        handler.begin();
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

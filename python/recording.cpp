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
#include <optional>
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

/// Fills one row of `columns` from a step record, from the events of the reader's own parse of
/// it (TraceSource::listen(): no second parse, no tree): the record's fields in the order the
/// trace writes them, docs/semantics.md. A record's values wait until the reader has said it is a
/// step (commit()); those of a header are dropped (drop()). The records have the same shape, so
/// the n-th value of a record is looked for in the column the n-th value of the last record went
/// to, which is checked by its keys, not found again by its name.
class StepHandler final : public RecordListener {
 public:
  explicit StepHandler(Columns& columns) : columns_(columns) {}

  void begin_record() override {
    depth_in_use_ = 0;
    ordinal_ = 0;
    pending_.clear();
  }
  /// The record was a step: its values are a row.
  void commit() {
    for (auto& value : pending_) {
      switch (value.kind) {
        case Column::Kind::kNumber:
          columns_.number(value.column, value.number);
          break;
        case Column::Kind::kFlag:
          columns_.flag(value.column, value.number != 0);
          break;
        case Column::Kind::kText:
          columns_.text(value.column, std::move(value.text));
          break;
      }
    }
    pending_.clear();
    columns_.end_row();
  }
  void drop() { pending_.clear(); }

  void null() override { element(); }
  void boolean(bool value) override {
    if (const auto c = column(Column::Kind::kFlag)) {
      pending_.push_back({*c, Column::Kind::kFlag, value ? 1.0 : 0.0, {}});
    }
    element();
  }
  void number(double value) override {
    if (const auto c = column(Column::Kind::kNumber)) {
      pending_.push_back({*c, Column::Kind::kNumber, value, {}});
    }
    element();
  }
  void string(std::string_view value) override {
    if (const auto c = column(Column::Kind::kText)) {
      pending_.push_back({*c, Column::Kind::kText, 0.0, std::string(value)});
    }
    element();
  }
  void start_object() override { open(false); }
  void end_object() override { close(); }
  void start_array() override { open(true); }
  void end_array() override { close(); }
  void key(std::string_view key) override { open_[depth_in_use_ - 1].key.assign(key); }

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
  struct Pending {
    std::size_t column;
    Column::Kind kind;
    double number;
    std::string text;
  };

  void open(bool array) {
    // The entries are kept from record to record, with their keys' capacity.
    if (depth_in_use_ == open_.size()) open_.emplace_back();
    open_[depth_in_use_].array = array;
    open_[depth_in_use_].element = 0;
    open_[depth_in_use_].key.clear();
    ++depth_in_use_;
  }
  void close() {
    --depth_in_use_;
    element();
  }
  /// After a value: the next one of an array has the next index.
  void element() {
    if (depth_in_use_ > 0 && open_[depth_in_use_ - 1].array) ++open_[depth_in_use_ - 1].element;
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
  std::vector<Pending> pending_;
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
      source->listen(&handler);
      while (source->next(record)) {
        if (record.kind == TraceRecord::Kind::kStep) {
          handler.commit();
        } else {
          handler.drop();
        }
      }
      source->listen(nullptr);
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

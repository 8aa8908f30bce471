#include "arbiter/trace_reader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "arbiter/document.hpp"
#include "core/record/mcap.hpp"

namespace arbiter {

namespace {

using Json = nlohmann::json;

/// nlohmann's message without its own prefix and position, which the location gives.
std::string parse_message(const Json::parse_error& error) {
  std::string text = error.what();
  if (const auto column = text.find(", column "); column != std::string::npos) {
    if (const auto colon = text.find(": ", column); colon != std::string::npos) {
      return text.substr(colon + 2);
    }
  }
  return text;
}

/// nlohmann's message without its "[json.exception.KIND.ID] " prefix.
std::string without_prefix(const Json::exception& error) {
  std::string text = error.what();
  if (const auto end = text.find("] ");
      text.rfind("[json.exception.", 0) == 0 && end != std::string::npos) {
    return text.substr(end + 2);
  }
  return text;
}

/// Where a record's top-level `"key": value` is written, spanning both, for an error about its
/// value; the record's own location when it cannot be found (or the record is not a line).
SourceLocation field_location(const TraceRecord& record, const std::string& key) {
  SourceLocation where = record.location;
  if (where.line <= 0) return where;
  const std::string quoted = "\"" + key + "\"";
  const auto at = record.text.find(quoted);
  if (at == std::string::npos) return where;
  auto end = record.text.find_first_of(",}", at + quoted.size());
  if (end == std::string::npos) end = record.text.size();
  while (end > at && record.text[end - 1] == ' ') --end;
  // Traces are ASCII outside their strings, so bytes are characters here.
  where.column = static_cast<int>(at) + 1;
  where.length = static_cast<int>(end - at);
  return where;
}

/// What accept() needs to know of a record, gathered by a SAX pass that builds no tree (a tree
/// per record was most of the time of reading a long run): whether it is an object, and the kind
/// and value of the top-level fields that say what record it is. A key given twice counts with
/// its last value, as in a parsed tree.
class RecordShape final : public nlohmann::json_sax<Json> {
 public:
  enum class Kind { kAbsent, kOther, kBool, kUnsigned, kInteger, kFloat, kArray, kObject };
  struct Field {
    Kind kind = Kind::kAbsent;
    bool flag = false;
    std::uint64_t unsigned_value = 0;
    double number = 0;
  };

  bool object = false;
  Field arbiter_trace, reload, after_step, layers, step, safe;
  /// Set when the text is not JSON: the parser's error.
  std::optional<std::string> error;
  std::size_t error_byte = 0;
  bool syntax_error = false;  ///< the text is not JSON, rather than JSON nlohmann refuses

  /// `"arbiter_trace": 1`, compared as numbers as a parsed tree's `== 1` does.
  bool is_header() const {
    return object &&
           ((arbiter_trace.kind == Kind::kUnsigned && arbiter_trace.unsigned_value == 1) ||
            (arbiter_trace.kind == Kind::kInteger && arbiter_trace.number == 1) ||
            (arbiter_trace.kind == Kind::kFloat && arbiter_trace.number == 1));
  }

  bool null() override { return scalar({Kind::kOther}); }
  bool boolean(bool value) override { return scalar({Kind::kBool, value}); }
  bool number_integer(number_integer_t value) override {
    return scalar({Kind::kInteger, false, 0, static_cast<double>(value)});
  }
  bool number_unsigned(number_unsigned_t value) override {
    return scalar({Kind::kUnsigned, false, value, static_cast<double>(value)});
  }
  bool number_float(number_float_t value, const string_t&) override {
    return scalar({Kind::kFloat, false, 0, value});
  }
  bool string(string_t&) override { return scalar({Kind::kOther}); }
  bool binary(binary_t&) override { return scalar({Kind::kOther}); }
  bool start_object(std::size_t) override { return open(Kind::kObject); }
  bool start_array(std::size_t) override { return open(Kind::kArray); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& key) override {
    if (depth_ == 1) current_ = field(key);
    return true;
  }
  bool parse_error(std::size_t, const std::string&,
                   const nlohmann::detail::exception& bad) override {
    if (const auto* syntax = dynamic_cast<const Json::parse_error*>(&bad)) {
      syntax_error = true;
      error_byte = syntax->byte;
      error = parse_message(*syntax);
    } else {
      // Valid syntax the parser still refuses, such as a number too large for a double.
      error = without_prefix(bad);
    }
    return false;
  }

 private:
  Field* field(const std::string& key) {
    if (key == "arbiter_trace") return &arbiter_trace;
    if (key == "reload") return &reload;
    if (key == "after_step") return &after_step;
    if (key == "layers") return &layers;
    if (key == "step") return &step;
    if (key == "safe") return &safe;
    return nullptr;
  }
  bool scalar(Field value) {
    if (depth_ == 1 && current_ != nullptr) *current_ = value;
    return true;
  }
  bool open(Kind kind) {
    if (depth_ == 0) object = kind == Kind::kObject;
    if (depth_ == 1 && current_ != nullptr) *current_ = Field{kind};
    ++depth_;
    return true;
  }
  bool close() {
    --depth_;
    return true;
  }

  std::size_t depth_ = 0;
  Field* current_ = nullptr;
};

/// The check's parse, its events also given to a RecordListener.
class ListenedShape final : public nlohmann::json_sax<Json> {
 public:
  ListenedShape(RecordShape& shape, RecordListener& listener)
      : shape_(shape), listener_(listener) {}

  bool null() override {
    listener_.null();
    return shape_.null();
  }
  bool boolean(bool value) override {
    listener_.boolean(value);
    return shape_.boolean(value);
  }
  bool number_integer(number_integer_t value) override {
    listener_.number(static_cast<double>(value));
    return shape_.number_integer(value);
  }
  bool number_unsigned(number_unsigned_t value) override {
    listener_.number(static_cast<double>(value));
    return shape_.number_unsigned(value);
  }
  bool number_float(number_float_t value, const string_t& text) override {
    listener_.number(value);
    return shape_.number_float(value, text);
  }
  bool string(string_t& value) override {
    listener_.string(value);
    return shape_.string(value);
  }
  bool binary(binary_t& value) override { return shape_.binary(value); }
  bool start_object(std::size_t size) override {
    listener_.start_object();
    return shape_.start_object(size);
  }
  bool end_object() override {
    listener_.end_object();
    return shape_.end_object();
  }
  bool start_array(std::size_t size) override {
    listener_.start_array();
    return shape_.start_array(size);
  }
  bool end_array() override {
    listener_.end_array();
    return shape_.end_array();
  }
  bool key(string_t& key) override {
    listener_.key(key);
    return shape_.key(key);
  }
  bool parse_error(std::size_t position, const std::string& token,
                   const nlohmann::detail::exception& bad) override {
    return shape_.parse_error(position, token, bad);
  }

 private:
  RecordShape& shape_;
  RecordListener& listener_;
};

class JsonlSource : public TraceSource {
 public:
  JsonlSource(std::istream& in, std::string file) : in_(in), file_(std::move(file)) {}

  bool next(TraceRecord& record) override {
    if (error()) return false;
    while (std::getline(in_, record.text)) {
      ++line_;
      if (record.text.empty()) continue;
      record.location = {file_, static_cast<int>(line_), 1};
      return accept(record);
    }
    if (in_.bad()) {
      // A read error is not the end of the run: what was read is not all of it.
      fail({file_, static_cast<int>(line_ + 1), 1}, "cannot read the trace");
      return false;
    }
    return end({file_, 0, 0});
  }

 private:
  std::istream& in_;
  std::string file_;
  std::size_t line_ = 0;
};

/// A JSON-lines trace read from a stream the source owns (a file, or bytes in memory).
class OwnedJsonlSource : public JsonlSource {
 public:
  OwnedJsonlSource(std::unique_ptr<std::istream> in, std::string file)
      : JsonlSource(*in, std::move(file)), owned_(std::move(in)) {}

 private:
  std::unique_ptr<std::istream> owned_;
};

/// A recording: its header messages (the first and each reload's) and step messages, in order,
/// read one chunk at a time.
class McapSource : public TraceSource {
 public:
  McapSource(std::unique_ptr<std::istream> in, std::string file)
      : in_(std::move(in)), reader_(*in_), file_(std::move(file)) {}

  bool next(TraceRecord& record) override {
    if (error()) return false;
    while (reader_.next(message_)) {
      if (message_.kind != mcap::Record::Kind::kMessage) continue;
      if (message_.topic != "/arbiter/header" && message_.topic != "/arbiter/step") continue;
      record.text = std::move(message_.data);
      record.location = {file_, 0, 0};
      if (!accept(record)) {
        fail_at(message_.offset);
        return false;
      }
      last_step_ = record.kind == TraceRecord::Kind::kStep ? record.step : last_step_;
      return true;
    }
    if (!reader_.error().empty()) {
      fail({file_, 0, 0}, reader_.error());
      return false;
    }
    if (reader_.truncated() && !header_seen()) {
      // Not an empty recording: one that was cut off before anything could be read.
      fail({file_, 0, 0}, mcap::cut_before_header(reader_.good_until()));
      return false;
    }
    if (reader_.truncated()) {
      set_truncated(fmt::format(
          "the recording was cut off while it was written: it ends after step {} (byte {}); "
          "what the run did after that is lost",
          last_step_, reader_.good_until()));
    }
    set_damaged(reader_.damaged_end());
    return end({file_, 0, 0});
  }

 private:
  /// The record's own error, told with the byte of its chunk.
  void fail_at(std::uint64_t offset) {
    auto problem = *error();
    reset_error();
    fail(problem.location, fmt::format("at byte {}: {}", offset, problem.message), problem.notes);
  }

  std::unique_ptr<std::istream> in_;
  mcap::Reader reader_;
  mcap::Record message_;
  std::string file_;
  std::uint64_t last_step_ = 0;
};

/// Whether a file starting with `start` (its first bytes, up to MCAP's magic's length) is a
/// recording: it starts with MCAP's magic, or is a piece of it (a recording cut off at once).
bool is_mcap(std::string_view start) {
  return start.size() >= mcap::kMagic.size()
             ? start.substr(0, mcap::kMagic.size()) == mcap::kMagic
             : !start.empty() && mcap::kMagic.substr(0, start.size()) == start;
}

/// A file read through its first bytes again after they were read to tell what it holds: a pipe
/// (`<(cat run.jsonl)`, /dev/stdin) cannot seek back to them. A read error of the file reaches
/// the stream that reads this buffer as its bad().
class PrefixedFile : public std::streambuf {
 public:
  /// False when the file cannot be opened or its first bytes cannot be read.
  bool open(const std::string& path) {
    if (file_.open(path, std::ios::binary | std::ios::in) == nullptr) return false;
    try {
      const auto got = file_.sgetn(buffer_, mcap::kMagic.size());
      prefix_.assign(buffer_, static_cast<std::size_t>(std::max<std::streamsize>(got, 0)));
    } catch (const std::exception&) {
      return false;  // libstdc++ throws on a read error, such as reading a directory
    }
    setg(prefix_.data(), prefix_.data(), prefix_.data() + prefix_.size());
    return true;
  }
  std::string_view prefix() const { return prefix_; }

 protected:
  int_type underflow() override {
    if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
    const auto got = file_.sgetn(buffer_, sizeof buffer_);  // a throw sets the stream's bad()
    if (got <= 0) return traits_type::eof();
    setg(buffer_, buffer_, buffer_ + got);
    return traits_type::to_int_type(*gptr());
  }

 private:
  std::filebuf file_;
  std::string prefix_;
  char buffer_[1 << 16];
};

/// An istream over a PrefixedFile it owns.
class PrefixedStream : public std::istream {
 public:
  PrefixedStream() : std::istream(nullptr) { rdbuf(&file_); }
  PrefixedFile& file() { return file_; }

 private:
  PrefixedFile file_;
};

class UnreadableSource : public TraceSource {
 public:
  explicit UnreadableSource(std::string file) {
    fail({std::move(file), 0, 0}, "cannot read the trace");
  }
  bool next(TraceRecord&) override { return false; }
};

}  // namespace

void TraceSource::fail(SourceLocation where, std::string message, std::vector<Note> notes) {
  if (error_) return;
  error_ = Diagnostic{std::move(where), Severity::kError, "bad-trace", std::move(message),
                      std::move(notes)};
}

bool TraceSource::end(SourceLocation where) {
  if (!header_seen_ && !error_) fail(std::move(where), "the trace is empty");
  return false;
}

bool TraceSource::accept(TraceRecord& record) {
  // Before the parse: every tool copies, compares or prints what it reads, recursively.
  const std::size_t max_depth = ReadLimits().max_depth;
  if (const auto deep = find_too_deep_json(record.text, max_depth)) {
    auto where = record.location;
    std::string message = fmt::format("nesting deeper than {} levels", max_depth);
    if (where.line > 0) {
      where.column = static_cast<int>(*deep) + 1;
    } else {
      message += fmt::format(" (at byte {} of the record)", *deep);
    }
    fail(std::move(where), std::move(message));
    return false;
  }
  RecordShape shape;
  bool parsed = false;
  if (listener_ != nullptr) {
    listener_->begin_record();
    ListenedShape listened(shape, *listener_);
    parsed = Json::sax_parse(record.text, &listened);
  } else {
    parsed = Json::sax_parse(record.text, &shape);
  }
  if (!parsed && shape.error) {
    auto where = record.location;
    if (shape.syntax_error) {
      if (where.line > 0)
        where.column = static_cast<int>(std::max<std::size_t>(shape.error_byte, 1));
      fail(std::move(where), "not JSON: " + *shape.error);
    } else {
      fail(std::move(where), "not readable JSON: " + *shape.error);
    }
    return false;
  }
  using Kind = RecordShape::Kind;
  if (!header_seen_) {
    if (!shape.is_header() || shape.layers.kind != Kind::kArray) {
      fail(record.location,
           "a trace starts with a header {\"arbiter_trace\": 1, \"name\": ..., \"layers\": "
           "[...]}; write one with 'arbiter run CONFIG --trace FILE.jsonl'");
      return false;
    }
    header_seen_ = true;
    record.kind = TraceRecord::Kind::kHeader;
    record.step = 0;
    return true;
  }
  if (shape.is_header() && shape.reload.kind != Kind::kAbsent) {
    if (shape.after_step.kind != Kind::kUnsigned || shape.layers.kind != Kind::kArray) {
      fail(record.location,
           "a reload header has \"after_step\" (the last step before it) and \"layers\"");
      return false;
    }
    record.kind = TraceRecord::Kind::kReload;
    record.step = shape.after_step.unsigned_value;
    return true;
  }
  if (!shape.object || shape.step.kind != Kind::kUnsigned || shape.layers.kind != Kind::kObject) {
    fail(record.location, "not a step record (an object with \"step\" and \"layers\")");
    return false;
  }
  const std::uint64_t step = shape.step.unsigned_value;
  // A "safe" that is no bool is no safe-value pass.
  if (step == last_step_ && shape.safe.kind == Kind::kBool && shape.safe.flag) {
    record.kind = TraceRecord::Kind::kSafe;
    record.step = step;
    return true;
  }
  if (step <= last_step_) {
    fail(field_location(record, "step"),
         fmt::format("step {} follows step {}; steps must increase", step, last_step_));
    return false;
  }
  last_step_ = step;
  record.kind = TraceRecord::Kind::kStep;
  record.step = step;
  return true;
}

std::unique_ptr<TraceSource> jsonl_trace_source(std::istream& in, std::string file) {
  return std::make_unique<JsonlSource>(in, std::move(file));
}

std::unique_ptr<TraceSource> trace_source(std::string bytes, std::string file) {
  const bool mcap = is_mcap(bytes);
  auto in = std::make_unique<std::istringstream>(std::move(bytes));
  if (mcap) return std::make_unique<McapSource>(std::move(in), std::move(file));
  return std::make_unique<OwnedJsonlSource>(std::move(in), std::move(file));
}

bool is_recording(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string start(mcap::kMagic.size(), '\0');
  in.read(start.data(), static_cast<std::streamsize>(start.size()));
  start.resize(static_cast<std::size_t>(in.gcount()));
  return is_mcap(start);
}

std::unique_ptr<TraceSource> open_trace(const std::string& path) {
  auto in = std::make_unique<PrefixedStream>();
  if (!in->file().open(path)) return std::make_unique<UnreadableSource>(path);
  if (is_mcap(in->file().prefix())) return std::make_unique<McapSource>(std::move(in), path);
  return std::make_unique<OwnedJsonlSource>(std::move(in), path);
}

std::optional<Trace> read_trace(TraceSource& source, Diagnostic& error) {
  Trace trace;
  TraceRecord record;
  bool first = true;
  while (source.next(record)) {
    if (first) {
      trace.header = std::move(record);
      first = false;
    } else if (record.kind == TraceRecord::Kind::kReload) {
      trace.reloads.push_back({std::move(record), trace.steps.size()});
    } else if (record.kind == TraceRecord::Kind::kSafe) {
      trace.safe_passes.push_back(std::move(record));
    } else {
      trace.steps.push_back(std::move(record));
    }
    record = TraceRecord();
  }
  if (source.error()) {
    error = *source.error();
    return std::nullopt;
  }
  trace.truncated = source.truncated();
  trace.damaged = source.damaged();
  return trace;
}

std::optional<Trace> read_trace(const std::string& path, Diagnostic& error) {
  auto source = open_trace(path);
  return read_trace(*source, error);
}

}  // namespace arbiter

#pragma once
// engine/tools/read: a trace or recording file in; its header and step records out, checked once,
// for diff, explain, replay and the views.
//
// Stage 5 of the data path, read back: the records of a trace (docs/semantics.md) or of a
// recording, in the order they were written, checked once here so that every tool reports a bad
// file the same way.

#include <cstdint>
#include <istream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/diagnostics.hpp"

namespace arbiter {

/// One record of a run: the first header, the header of a program a hot reload swapped in, or a
/// step, or the safe-value pass of a stopping or pausing engine (a record with `"safe": true` that
/// repeats the number of the step before it). `text` is the record's JSON object on one line, as
/// the trace writer writes it.
struct TraceRecord {
  enum class Kind { kHeader, kReload, kStep, kSafe };
  Kind kind = Kind::kStep;
  std::string text;
  /// kStep: the step number; kSafe: the step it followed; kReload: the last step of the program it
  /// replaced ("after_step").
  std::uint64_t step = 0;
  /// Where the record is: its line in a trace, or (line 0) just the file of a recording.
  SourceLocation location;
};

/// The JSON of each record, as the check parses it (TraceSource::listen()): a reader that builds
/// its own structure from the records (the Python module's DataFrame) takes the events of that one
/// parse instead of parsing every record again. Keys and strings are valid during the call only.
/// The record's kind is known once next() returns: what a listener took from a record that is no
/// step is its own to drop.
class RecordListener {
 public:
  virtual ~RecordListener() = default;
  virtual void begin_record() = 0;
  virtual void null() = 0;
  virtual void boolean(bool value) = 0;
  virtual void number(double value) = 0;
  virtual void string(std::string_view value) = 0;
  virtual void key(std::string_view key) = 0;
  virtual void start_object() = 0;
  virtual void end_object() = 0;
  virtual void start_array() = 0;
  virtual void end_array() = 0;
};

/// The records of one trace or recording, read one at a time, so that a tool that needs a few
/// steps need not hold a whole run. Every record is checked: the first is a header, later
/// headers are reload headers, each step record is an object with an increasing "step" and a
/// "layers" object.
class TraceSource {
 public:
  virtual ~TraceSource() = default;
  /// The next record; false at the end of the run or at the first bad record (then error()).
  virtual bool next(TraceRecord& record) = 0;
  /// Why next() stopped early: `file:line:col: error: ...` through format().
  const std::optional<Diagnostic>& error() const { return error_; }
  /// Set when the file ends in the middle of a record that cannot be read (a recording cut off
  /// while it was written): what was read up to there is whole, and this says what was lost.
  const std::string& truncated() const { return truncated_; }
  /// Set, once next() has returned false, when a recording's steps are whole but what follows
  /// them is not (MCAP's data end CRC, summary, footer or closing magic): a warning, since other
  /// tools may refuse the file.
  const std::string& damaged() const { return damaged_; }
  /// Every record accepted from now on is also parsed into `listener` (null: none), which must
  /// outlive the reads.
  void listen(RecordListener* listener) { listener_ = listener; }

 protected:
  /// Checks `record` (its kind still unknown) against the records before it; false, with
  /// error() set, when it is not a record of a run.
  bool accept(TraceRecord& record);
  void fail(SourceLocation where, std::string message, std::vector<Note> notes = {});
  /// At the end of the input: false, with error() set when there was no header at all.
  bool end(SourceLocation where);
  void set_truncated(std::string what) { truncated_ = std::move(what); }
  void set_damaged(std::string what) { damaged_ = std::move(what); }
  bool header_seen() const { return header_seen_; }
  void reset_error() { error_.reset(); }

 private:
  std::optional<Diagnostic> error_;
  std::string truncated_;
  std::string damaged_;
  bool header_seen_ = false;
  std::uint64_t last_step_ = 0;
  RecordListener* listener_ = nullptr;
};

/// The JSON-lines trace in `in`, named `file` in errors. `in` must outlive the source.
std::unique_ptr<TraceSource> jsonl_trace_source(std::istream& in, std::string file);

/// The trace or recording in `bytes`, named `file` in errors: an MCAP recording when it starts
/// with MCAP's magic (or is a piece of it: a recording cut off at once), else JSON lines.
std::unique_ptr<TraceSource> trace_source(std::string bytes, std::string file);

/// Whether the file at `path` is a recording (it starts with MCAP's magic), not a trace.
bool is_recording(const std::string& path);

/// The trace or recording at `path`, by its content: an MCAP recording starts with MCAP's magic,
/// anything else is read as JSON lines. The file is read as next() needs it, never whole. A file
/// that cannot be opened gives a source whose first next() fails with the reason.
std::unique_ptr<TraceSource> open_trace(const std::string& path);

/// A run read whole.
struct Trace {
  TraceRecord header;
  std::vector<TraceRecord> steps;
  /// The reload headers, each with the index in `steps` of the first step after it.
  struct Reload {
    TraceRecord header;
    std::size_t before = 0;
  };
  std::vector<Reload> reloads;
  /// The safe-value passes, apart from the steps: they output values but step nothing.
  std::vector<TraceRecord> safe_passes;
  std::string truncated;  ///< as TraceSource::truncated()
  std::string damaged;    ///< as TraceSource::damaged()
};

/// Reads all of `source`; nullopt with `error` set when it is malformed or has no header.
std::optional<Trace> read_trace(TraceSource& source, Diagnostic& error);
std::optional<Trace> read_trace(const std::string& path, Diagnostic& error);

}  // namespace arbiter

#pragma once
// `arbiter view FILE --trace TRACE.jsonl`: the web view of a recorded run, scrubbed step by step.
// Also reads trace files for `arbiter plot`.

#include <atomic>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "arbiter/program.hpp"
#include "server/serve.hpp"

namespace arbiter::cli {

/// A trace file (docs/semantics.md, "The trace") or recording read whole by the trace reader: its
/// header and step records, each parsed.
struct TraceFile {
  /// A header written when a hot reload swapped a new program in (docs/hot_reload.md).
  struct Reload {
    std::size_t line = 0;    ///< its line in the file
    std::size_t before = 0;  ///< the index in `records` of the first step after it
    nlohmann::ordered_json header;
  };
  std::string header_line;
  nlohmann::ordered_json header;
  std::vector<std::string> lines;               ///< the step records as written, in order
  std::vector<std::uint64_t> steps;             ///< their step numbers
  std::vector<nlohmann::ordered_json> records;  ///< parsed, unless read with `parse` false
  std::vector<Reload> reloads;
  std::string truncated;  ///< what a recording cut off while written lost (TraceSource)
  std::string damaged;    ///< what is wrong past a recording's steps (TraceSource)
};

/// Reads `path`; on failure nullopt, and `error` says where and what (`file:line:col: ...`),
/// rendered as config errors are (with `format_options.source`, the trace's line underlined).
/// With `parse` false, `records` is left empty: a reader of the lines as they are (the view)
/// does not pay for a JSON tree of each.
std::optional<TraceFile> read_trace_file(const std::string& path, std::string& error,
                                         const FormatOptions& format_options = {},
                                         bool parse = true);

/// A second run shown over the first (`view A --compare B`): its trace or recording, and the
/// program its explain answers come from (null: `no_program` says why there is none).
struct CompareRun {
  std::string path;
  const Program* program = nullptr;
  std::string no_program;
};

/// Serves the page for `trace` (written by running `program`'s config) until `interrupted`;
/// prints the URL to `out`. The page opens at `open_step` (a step of the trace), by default at
/// the last step. With `compare`, the page shows that run over this one, the steps where they
/// differ marked (as `arbiter diff` finds them). Returns the exit code.
/// Only what `access` lets in is served, as for the live view.
int view_trace(const Program& program, const std::string& trace_path, const ServeAddress& address,
               const LiveAccess& access, std::optional<std::uint64_t> open_step,
               const std::atomic<bool>& interrupted, std::ostream& out, std::ostream& err,
               const FormatOptions& format_options = {}, const CompareRun* compare = nullptr);

}  // namespace arbiter::cli

#include "commands/view.hpp"

#include <fmt/format.h>
#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "arbiter/dump.hpp"
#include "arbiter/explain.hpp"
#include "arbiter/trace_reader.hpp"
#include "commands/command.hpp"
#include "commands/record.hpp"

namespace arbiter::cli {

std::optional<TraceFile> read_trace_file(const std::string& path, std::string& error,
                                         const FormatOptions& format_options) {
  Diagnostic problem;
  auto read = read_trace(path, problem);
  if (!read) {
    error = format(problem, format_options);
    error.pop_back();  // the caller ends the line
    return std::nullopt;
  }
  TraceFile trace;
  trace.header_line = std::move(read->header.text);
  trace.header = nlohmann::ordered_json::parse(trace.header_line);
  for (auto& reload : read->reloads) {
    trace.reloads.push_back({static_cast<std::size_t>(reload.header.location.line), reload.before,
                             nlohmann::ordered_json::parse(reload.header.text)});
  }
  for (auto& step : read->steps) {
    trace.records.push_back(nlohmann::ordered_json::parse(step.text));
    trace.lines.push_back(std::move(step.text));
  }
  trace.truncated = std::move(read->truncated);
  trace.damaged = std::move(read->damaged);
  return trace;
}

namespace {

/// The view's refusal of a trace, as the error it prints. Built field by field, out of line:
/// braced Diagnostic temporaries inlined into view_trace() make GCC 12 at -O2 warn, falsely, that
/// their location may be used uninitialised.
[[gnu::noinline]] std::string bad_trace(const std::string& path, int line, std::string message,
                                        std::vector<Note> notes, const FormatOptions& options) {
  Diagnostic diagnostic;
  diagnostic.location.file = path;
  diagnostic.location.line = line;
  diagnostic.location.column = 1;
  diagnostic.code = "bad-trace";
  diagnostic.message = std::move(message);
  diagnostic.notes = std::move(notes);
  return format(diagnostic, options);
}

/// How far the view's explain answers look for an actuator's or a state's story: steps either
/// side of the one asked for, and bytes of records either side (a large graph's records are
/// large, and the answer is wanted while the pointer moves).
constexpr std::uint64_t kStoryReach = 1000;
constexpr std::size_t kStoryBytes = std::size_t{8} << 20;

}  // namespace

int view_trace(const Program& program, const std::string& trace_path, const ServeAddress& address,
               const LiveAccess& access, std::optional<std::uint64_t> open_step,
               const std::atomic<bool>& interrupted, std::ostream& out, std::ostream& err,
               const FormatOptions& format_options) {
  std::string error;
  const auto trace = read_trace_file(trace_path, error, format_options);
  if (!trace) {
    err << error << "\n";
    return 1;
  }
  note_end(trace_path, trace->truncated, trace->damaged, err);
  if (const auto header = check_trace_header(program, trace->header_line);
      header.status != Explanation::Status::kOk) {
    // A recording's header is a message, not a line to quote.
    err << bad_trace(trace_path, is_recording(trace_path) ? 0 : 1, header.text, header.notes,
                     format_options);
    return 1;
  }
  if (!trace->reloads.empty()) {
    err << bad_trace(
        trace_path, static_cast<int>(trace->reloads.front().line),
        fmt::format("the config was reloaded during this run (a reload header); the "
                    "view shows a run of one config: 'arbiter plot {}' draws all of it",
                    trace_path),
        {}, format_options);
    return 1;
  }
  std::vector<std::uint64_t> steps;
  for (const auto& record : trace->records) steps.push_back(record["step"].get<std::uint64_t>());
  if (open_step && !std::binary_search(steps.begin(), steps.end(), *open_step)) {
    err << fmt::format("arbiter view: --step {}: {}\n", *open_step,
                       steps.empty() ? fmt::format("{} has no step records", trace_path)
                                     : fmt::format("{} has steps {} to {}", trace_path,
                                                   steps.front(), steps.back()));
    return 2;
  }
  // Without --step the page opens at the last step: the end of the run, with the timelines of
  // the steps before it.
  const std::string info = fmt::format(R"({{"mode": "trace", "step": {}}})",
                                       open_step ? *open_step : (steps.empty() ? 0 : steps.back()));
  const std::string graph = dump_json(program);
  std::string text = trace->header_line + "\n";
  for (const auto& line : trace->lines) text += line + "\n";

  WebServer server;
  auto& http = server.http();
  http.Get("/info", [&info](const httplib::Request&, httplib::Response& response) {
    response.set_content(info, "application/json");
  });
  http.Get("/graph", [&graph](const httplib::Request&, httplib::Response& response) {
    response.set_content(graph, "application/json");
  });
  http.Get("/trace", [&text](const httplib::Request&, httplib::Response& response) {
    response.set_content(text, "application/x-ndjson");
  });
  // The program is only read here, never stepped: every server thread may explain at once.
  http.Get("/explain", [&](const httplib::Request& request, httplib::Response& response) {
    const std::string step_text = request.get_param_value("step");
    const std::string target = request.get_param_value("target");
    if (step_text.empty() || step_text.size() > 19 ||
        step_text.find_first_not_of("0123456789") != std::string::npos || target.empty()) {
      response.status = 400;
      response.set_content("explain needs ?step=N (from 1) and &target=BEHAVIOUR\n",
                           "text/plain; charset=utf-8");
      return;
    }
    const std::uint64_t step = std::stoull(step_text);
    // explain() reads a trace: give it the header and the records around the step. An
    // actuator's story goes back to the step that wrote the value it holds, a state's from the
    // step its run was planned to the step it ended: for them, up to kStoryReach steps either
    // side (fewer when the records are large), beyond which the answer says it cannot see.
    Explanation unresolved;
    const auto kind = resolve_target(program, target, unresolved);
    const bool story = kind && (kind->kind == ExplainTarget::Kind::kActuator ||
                                kind->kind == ExplainTarget::Kind::kState);
    const std::uint64_t reach = story ? kStoryReach : 1;
    const auto here = static_cast<std::size_t>(std::lower_bound(steps.begin(), steps.end(), step) -
                                               steps.begin());
    std::size_t begin = here;
    std::size_t bytes = 0;
    while (begin > 0 && steps[begin - 1] + reach >= step && bytes < kStoryBytes) {
      bytes += trace->lines[--begin].size();
    }
    std::size_t end = here;
    bytes = 0;
    const std::uint64_t after =
        kind && kind->kind == ExplainTarget::Kind::kState ? reach : std::uint64_t{1};
    while (end < steps.size() && steps[end] <= step + after && bytes < kStoryBytes) {
      bytes += trace->lines[end++].size();
    }
    std::string excerpt = trace->header_line + "\n";
    for (auto i = begin; i < end; ++i) excerpt += trace->lines[i] + "\n";
    std::istringstream in(excerpt);
    const auto [status, answer] = explanation_reply(explain(program, in, step, target));
    response.status = status;
    response.set_content(answer, "text/plain; charset=utf-8");
  });

  // The page's "next step where": `arbiter seek` over the trace served.
  http.Get("/seek", [&](const httplib::Request& request, httplib::Response& response) {
    const std::string condition = request.get_param_value("condition");
    const std::string from_text = request.get_param_value("from");
    if (condition.empty() || from_text.size() > 19 ||
        from_text.find_first_not_of("0123456789") != std::string::npos) {
      response.status = 400;
      response.set_content("seek needs ?condition=CONDITION and &from=N\n",
                           "text/plain; charset=utf-8");
      return;
    }
    std::string refused;
    auto breakpoint =
        make_breakpoint(program, condition, "seek", FormatOptions::readable(), refused);
    if (!breakpoint) {
      response.status = 400;
      response.set_content(refused, "text/plain; charset=utf-8");
      return;
    }
    std::vector<Breakpoint> breakpoints{std::move(*breakpoint)};
    std::istringstream in(text);
    const auto source = jsonl_trace_source(in, trace_path);
    std::optional<Diagnostic> failed;
    const auto hit =
        seek(*source, breakpoints, from_text.empty() ? 0 : std::stoull(from_text), failed);
    if (!hit) {
      response.status = 404;
      response.set_content(failed ? format(*failed)
                                  : fmt::format("no step after step {} where {}\n",
                                                from_text.empty() ? "0" : from_text,
                                                printable(breakpoints.front().condition.text)),
                           "text/plain; charset=utf-8");
      return;
    }
    response.set_content(fmt::format(R"({{"step": {}}})", hit->step), "application/json");
  });

  if (!server.start(address, access, error)) {
    err << fmt::format("arbiter view: {}\n", error);
    return 2;
  }
  err << web_app_note();
  err << exposure_warning(address, "read the trace (with its token)");
  out << fmt::format("viewing {} ({} steps of {}) at {}\nCtrl-C stops.\n", trace_path,
                     trace->records.size(), program.name, server.page_url())
      << std::flush;
  while (!interrupted) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  server.stop();
  return 0;
}

int view_command(const Options& options) {
  auto registry = make_registry();
  int exit = kExitInvalid;
  auto program =
      program_of_run(options.file, options.trace_path, registry, load_options_of(options), "view",
                     options.diagnostic_format, std::cerr, exit);
  if (!program) return exit;
  install_interrupt_handlers();
  std::string unused;  // the option's check has parsed it already
  LiveAccess access;
  access.token = options.serve_token;
  return view_trace(*program, options.trace_path, ServeAddress::parse(options.view_serve, unused),
                    access, options.step > 0 ? std::optional(options.step) : std::nullopt,
                    interrupted, std::cout, std::cerr, options.diagnostic_format);
}

}  // namespace arbiter::cli

#include "commands/view.hpp"

#include <fmt/format.h>
#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include "arbiter/dump.hpp"
#include "arbiter/explain.hpp"
#include "arbiter/trace_diff.hpp"
#include "arbiter/trace_reader.hpp"
#include "commands/command.hpp"
#include "commands/record.hpp"

namespace arbiter::cli {

std::optional<TraceFile> read_trace_file(const std::string& path, std::string& error,
                                         const FormatOptions& format_options, bool parse) {
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
    if (parse) trace.records.push_back(nlohmann::ordered_json::parse(step.text));
    trace.steps.push_back(step.step);
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

/// A run the view serves: its trace, read whole, and the program it is explained against.
struct ServedRun {
  std::string path;
  const Program* program = nullptr;
  std::string no_program;  ///< why there is no program
  TraceFile trace;
  std::string text;  ///< the trace as the page reads it: the header, then the step records
};

ServedRun served(std::string path, const Program* program, TraceFile trace) {
  ServedRun run{std::move(path), program, {}, std::move(trace), {}};
  run.text = run.trace.header_line + "\n";
  for (const auto& line : run.trace.lines) run.text += line + "\n";
  return run;
}

/// explain() of `target` at `step` of `run`, as the page asks for it: (HTTP status, text).
std::pair<int, std::string> explain_in(const ServedRun& run, std::uint64_t step,
                                       const std::string& target) {
  if (run.program == nullptr) return {404, run.no_program + "\n"};
  const Program& program = *run.program;
  const auto& steps = run.trace.steps;
  // explain() reads a trace: give it the header and the records around the step. An
  // actuator's story goes back to the step that wrote the value it holds, a state's from the
  // step its run was planned to the step it ended: for them, up to kStoryReach steps either
  // side (fewer when the records are large), beyond which the answer says it cannot see.
  Explanation unresolved;
  const auto kind = resolve_target(program, target, unresolved);
  const bool story = kind && (kind->kind == ExplainTarget::Kind::kActuator ||
                              kind->kind == ExplainTarget::Kind::kState);
  const std::uint64_t reach = story ? kStoryReach : 1;
  const auto here =
      static_cast<std::size_t>(std::lower_bound(steps.begin(), steps.end(), step) - steps.begin());
  std::size_t begin = here;
  std::size_t bytes = 0;
  while (begin > 0 && steps[begin - 1] + reach >= step && bytes < kStoryBytes) {
    bytes += run.trace.lines[--begin].size();
  }
  std::size_t end = here;
  bytes = 0;
  const std::uint64_t after =
      kind && kind->kind == ExplainTarget::Kind::kState ? reach : std::uint64_t{1};
  while (end < steps.size() && steps[end] <= step + after && bytes < kStoryBytes) {
    bytes += run.trace.lines[end++].size();
  }
  std::string excerpt = run.trace.header_line + "\n";
  for (auto i = begin; i < end; ++i) excerpt += run.trace.lines[i] + "\n";
  std::istringstream in(excerpt);
  return explanation_reply(explain(program, in, step, target));
}

/// Where two served runs differ, as `arbiter diff` compares them, step by step for the page to
/// mark: `{"a", "b", "identical", "first": {"step", "what"} | null, "steps": [[from, to], ...]`
/// (runs of steps where anything differs, or only one run has the step), `"differ": {WHAT:
/// [[from, to], ...]}` (WHAT as the diff names it: `layer/name`, `actuator:NAME`,
/// `machine:NAME`), `"summary"` (`arbiter diff`'s text)}.
std::string compare_json(const ServedRun& a, const ServedRun& b) {
  using Json = nlohmann::ordered_json;
  using Runs = std::vector<std::pair<std::uint64_t, std::uint64_t>>;
  const auto mark = [](Runs& runs, std::uint64_t step) {
    if (!runs.empty() && runs.back().second + 1 == step) {
      runs.back().second = step;
    } else {
      runs.emplace_back(step, step);
    }
  };
  TraceDiffer differ;
  Runs any;
  std::map<std::string, Runs> differ_at;
  std::uint64_t first_extra = 0;
  std::size_t i = 0;
  std::size_t j = 0;
  while (i < a.trace.steps.size() || j < b.trace.steps.size()) {
    const bool in_a = i < a.trace.steps.size();
    const bool in_b = j < b.trace.steps.size();
    if (in_a && in_b && a.trace.steps[i] == b.trace.steps[j]) {
      differ.compare(a.trace.steps[i], a.trace.lines[i], b.trace.lines[j]);
      for (const auto& what : differ.differed()) mark(differ_at[what], a.trace.steps[i]);
      if (!differ.differed().empty()) mark(any, a.trace.steps[i]);
      ++i;
      ++j;
      continue;
    }
    // A step only one run has.
    const std::uint64_t step = !in_b || (in_a && a.trace.steps[i] < b.trace.steps[j])
                                   ? a.trace.steps[i++]
                                   : b.trace.steps[j++];
    if (first_extra == 0) first_extra = step;
    differ.unmatched(step);
    mark(any, step);
  }
  const TraceDiff diff = differ.finish(a.trace.steps.size(), b.trace.steps.size(), first_extra);
  const auto runs_json = [](const Runs& runs) {
    Json out = Json::array();
    for (const auto& [from, to] : runs) out.push_back({from, to});
    return out;
  };
  Json out;
  out["a"] = a.path;
  out["b"] = b.path;
  out["identical"] = diff.identical;
  out["first"] = nullptr;
  if (diff.first_divergence) {
    out["first"] = {{"step", diff.first_divergence->step}, {"what", diff.first_divergence->what}};
  }
  out["steps"] = runs_json(any);
  out["differ"] = Json::object();
  for (const auto& [what, runs] : differ_at) out["differ"][what] = runs_json(runs);
  out["summary"] = format_text(diff, "A " + a.path, "B " + b.path);
  return out.dump();
}

/// The run a request asks for: `?run=b` the compared one, else the first.
const ServedRun& run_of(const httplib::Request& request, const ServedRun& a,
                        const std::optional<ServedRun>& b) {
  return b && request.get_param_value("run") == "b" ? *b : a;
}

/// A trace read for the view (nullopt when it cannot be read, said on `err`), and in
/// `no_program` why it cannot be explained against `program`: another config, or reloaded.
std::optional<TraceFile> trace_for_view(const Program& program, const std::string& path,
                                        std::string& no_program, std::ostream& err,
                                        const FormatOptions& format_options) {
  std::string error;
  // The page parses the records: the server serves them as they are.
  auto trace = read_trace_file(path, error, format_options, false);
  if (!trace) {
    err << error << "\n";
    return std::nullopt;
  }
  note_end(path, trace->truncated, trace->damaged, err);
  if (const auto header = check_trace_header(program, trace->header_line);
      header.status != Explanation::Status::kOk) {
    // A recording's header is a message, not a line to quote.
    no_program =
        bad_trace(path, is_recording(path) ? 0 : 1, header.text, header.notes, format_options);
    return trace;
  }
  if (!trace->reloads.empty()) {
    no_program =
        bad_trace(path, static_cast<int>(trace->reloads.front().line),
                  fmt::format("the config was reloaded during this run (a reload header); the "
                              "view shows a run of one config: 'arbiter plot {}' draws all of it",
                              path),
                  {}, format_options);
  }
  return trace;
}

}  // namespace

int view_trace(const Program& program, const std::string& trace_path, const ServeAddress& address,
               const LiveAccess& access, std::optional<std::uint64_t> open_step,
               const std::atomic<bool>& interrupted, std::ostream& out, std::ostream& err,
               const FormatOptions& format_options, const CompareRun* compare) {
  std::string refused;
  auto read = trace_for_view(program, trace_path, refused, err, format_options);
  if (!read) return 1;
  if (!refused.empty()) {
    err << refused;
    return 1;
  }
  const ServedRun trace = served(trace_path, &program, std::move(*read));
  std::optional<ServedRun> other;
  std::string compared;
  if (compare != nullptr) {
    // The compared run is shown whatever its config; only its explain answers need one.
    std::string no_program = compare->no_program;
    const Program* against = compare->program;
    auto read_b = trace_for_view(against != nullptr ? *against : program, compare->path, no_program,
                                 err, format_options);
    if (!read_b) return 1;
    if (!no_program.empty()) against = nullptr;
    other = served(compare->path, against, std::move(*read_b));
    other->no_program = no_program;
    compared = compare_json(trace, *other);
  }
  const auto& steps = trace.trace.steps;
  if (open_step && !std::binary_search(steps.begin(), steps.end(), *open_step)) {
    std::string why = fmt::format("{} has no step records", trace_path);
    if (!steps.empty() && (*open_step < steps.front() || *open_step > steps.back())) {
      why = fmt::format("{} has steps {} to {}", trace_path, steps.front(), steps.back());
    } else if (!steps.empty()) {
      // A trace edited by hand may lack steps between its first and its last.
      const auto after = std::upper_bound(steps.begin(), steps.end(), *open_step);
      why = fmt::format("{} has no step {}: it goes from step {} to step {}", trace_path,
                        *open_step, *(after - 1), *after);
    }
    err << fmt::format("arbiter view: --step {}: {}\n", *open_step, why);
    return 2;
  }
  // Without --step the page opens at the last step: the end of the run, with the timelines of
  // the steps before it.
  nlohmann::ordered_json about;
  about["mode"] = "trace";
  about["step"] = open_step ? *open_step : (steps.empty() ? 0 : steps.back());
  if (other) about["compare"] = {{"a", trace_path}, {"b", other->path}};
  const std::string info = about.dump();
  const std::string graph = dump_json(program);

  WebServer server;
  auto& http = server.http();
  http.Get("/info", [&info](const httplib::Request&, httplib::Response& response) {
    response.set_content(info, "application/json");
  });
  http.Get("/graph", [&graph](const httplib::Request&, httplib::Response& response) {
    response.set_content(graph, "application/json");
  });
  http.Get("/trace", [&](const httplib::Request& request, httplib::Response& response) {
    response.set_content(run_of(request, trace, other).text, "application/x-ndjson");
  });
  if (other) {
    http.Get("/compare", [&compared](const httplib::Request&, httplib::Response& response) {
      response.set_content(compared, "application/json");
    });
  }
  // The programs are only read here, never stepped: every server thread may explain at once.
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
    const auto [status, answer] =
        explain_in(run_of(request, trace, other), std::stoull(step_text), target);
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
    std::istringstream in(trace.text);
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

  std::string error;
  if (!server.start(address, access, error)) {
    err << fmt::format("arbiter view: {}\n", error);
    return 2;
  }
  err << web_app_note();
  err << exposure_warning(address, "read the trace (with its token)");
  if (other) {
    out << fmt::format("viewing {} ({} steps of {}) compared with {} ({} steps) at {}\n",
                       trace_path, trace.trace.steps.size(), program.name, other->path,
                       other->trace.steps.size(), server.page_url());
  } else {
    out << fmt::format("viewing {} ({} steps of {}) at {}\n", trace_path, trace.trace.steps.size(),
                       program.name, server.page_url());
  }
  out << "Ctrl-C stops.\n" << std::flush;
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
  // The compared run is explained against the config it holds (a recording), else against the
  // first run's (a trace holds none), when its header says it was written by that one.
  CompareRun compare;
  RecordedProgram recorded;
  if (!options.compare_path.empty()) {
    compare.path = options.compare_path;
    if (is_recording(compare.path)) {
      recorded = load_recorded_program(compare.path, registry, load_options_of(options));
      if (recorded.program) {
        compare.program = &*recorded.program;
      } else {
        compare.no_program =
            fmt::format("{}: its config cannot be read or does not load{}", compare.path,
                        recorded.error.empty() ? "" : ": " + recorded.error);
      }
    } else {
      compare.program = &*program;
    }
  }
  install_interrupt_handlers();
  std::string unused;  // the option's check has parsed it already
  LiveAccess access;
  access.token = options.serve_token;
  return view_trace(*program, options.trace_path, ServeAddress::parse(options.view_serve, unused),
                    access, options.step > 0 ? std::optional(options.step) : std::nullopt,
                    interrupted, std::cout, std::cerr, options.diagnostic_format,
                    options.compare_path.empty() ? nullptr : &compare);
}

}  // namespace arbiter::cli

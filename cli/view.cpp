#include "view.hpp"

#include <fmt/format.h>
#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "arbiter/dump.hpp"
#include "arbiter/explain.hpp"

namespace arbiter::cli {

namespace {

/// nlohmann's message without its own prefix and position, which the caller gives as file:line:col.
std::string parse_message(const nlohmann::ordered_json::parse_error& error) {
  std::string text = error.what();
  if (const auto column = text.find(", column "); column != std::string::npos) {
    if (const auto colon = text.find(": ", column); colon != std::string::npos) {
      return text.substr(colon + 2);
    }
  }
  return text;
}

}  // namespace

std::optional<TraceFile> read_trace_file(const std::string& path, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = fmt::format("{}: error: cannot read the trace", path);
    return std::nullopt;
  }
  TraceFile trace;
  std::string line;
  std::size_t number = 0;
  std::uint64_t last_step = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    nlohmann::ordered_json parsed;
    try {
      parsed = nlohmann::ordered_json::parse(line);
    } catch (const nlohmann::ordered_json::parse_error& bad) {
      error = fmt::format("{}:{}:{}: error: not JSON: {}", path, number,
                          std::max<std::size_t>(bad.byte, 1), parse_message(bad));
      return std::nullopt;
    }
    if (!trace.header_line.empty() && parsed.is_object() && parsed.contains("reload") &&
        parsed.value("arbiter_trace", nlohmann::ordered_json()) == 1) {
      trace.reloads.push_back({number, trace.records.size(), std::move(parsed)});
      continue;
    }
    if (trace.header_line.empty()) {
      if (!parsed.is_object() || parsed.value("arbiter_trace", nlohmann::ordered_json()) != 1 ||
          !parsed.value("layers", nlohmann::ordered_json()).is_array()) {
        error = fmt::format(
            "{}:{}:1: error: a trace starts with a header {{\"arbiter_trace\": 1, \"name\": ..., "
            "\"layers\": [...]}}; write one with 'arbiter run CONFIG --trace FILE.jsonl'",
            path, number);
        return std::nullopt;
      }
      trace.header_line = line;
      trace.header = std::move(parsed);
      continue;
    }
    if (!parsed.is_object() || !parsed.contains("step") || !parsed["step"].is_number_unsigned() ||
        !parsed.contains("layers") || !parsed["layers"].is_object()) {
      error =
          fmt::format("{}:{}:1: error: not a step record (an object with \"step\" and \"layers\")",
                      path, number);
      return std::nullopt;
    }
    const auto step = parsed["step"].get<std::uint64_t>();
    // The safe-value pass of a stopping engine repeats its last step's number: no step to draw.
    if (step == last_step && parsed.value("safe", false) == true) continue;
    if (step <= last_step) {
      error = fmt::format("{}:{}:1: error: step {} follows step {}; steps must increase", path,
                          number, step, last_step);
      return std::nullopt;
    }
    last_step = step;
    trace.lines.push_back(line);
    trace.records.push_back(std::move(parsed));
  }
  if (trace.header_line.empty()) {
    error = fmt::format("{}: error: the trace is empty", path);
    return std::nullopt;
  }
  return trace;
}

int view_trace(const Program& program, const std::string& trace_path, const ServeAddress& address,
               const std::atomic<bool>& interrupted, std::ostream& out, std::ostream& err) {
  std::string error;
  const auto trace = read_trace_file(trace_path, error);
  if (!trace) {
    err << error << "\n";
    return 1;
  }
  if (const auto header = check_trace_header(program, trace->header_line);
      header.status != Explanation::Status::kOk) {
    err << fmt::format("{}:1:1: error: {}\n", trace_path, header.text);
    for (const auto& note : header.notes) err << fmt::format("  note: {}\n", note);
    return 1;
  }
  if (!trace->reloads.empty()) {
    err << fmt::format(
        "{}:{}:1: error: the config was reloaded during this run (a reload header); the view "
        "shows a run of one config: 'arbiter plot {}' draws all of it\n",
        trace_path, trace->reloads.front().line, trace_path);
    return 1;
  }
  std::vector<std::uint64_t> steps;
  for (const auto& record : trace->records) steps.push_back(record["step"].get<std::uint64_t>());
  const std::string graph = dump_json(program);
  std::string text = trace->header_line + "\n";
  for (const auto& line : trace->lines) text += line + "\n";

  WebServer server;
  auto& http = server.http();
  http.Get("/info", [](const httplib::Request&, httplib::Response& response) {
    response.set_content(R"({"mode": "trace"})", "application/json");
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
    // explain() reads a trace: give it the header and the records around the step.
    const auto at = std::lower_bound(steps.begin(), steps.end(), step > 0 ? step - 1 : 0);
    std::string excerpt = trace->header_line + "\n";
    for (auto i = static_cast<std::size_t>(at - steps.begin());
         i < steps.size() && steps[i] <= step + 1; ++i) {
      excerpt += trace->lines[i] + "\n";
    }
    std::istringstream in(excerpt);
    const auto [status, answer] = explanation_reply(explain(program, in, step, target));
    response.status = status;
    response.set_content(answer, "text/plain; charset=utf-8");
  });

  if (!server.start(address, error)) {
    err << fmt::format("arbiter view: {}\n", error);
    return 2;
  }
  err << exposure_warning(address, "read the trace");
  out << fmt::format("viewing {} ({} steps of {}) at {}\nCtrl-C stops.\n", trace_path,
                     trace->records.size(), program.name, server.url())
      << std::flush;
  while (!interrupted) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  server.stop();
  return 0;
}

}  // namespace arbiter::cli

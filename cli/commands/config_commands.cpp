// The subcommands that read configs and print what they find (validate, dump, plugins, schema,
// explain), and the language server, which does the same for an editor.

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <set>

#include "arbiter/breakpoint.hpp"
#include "arbiter/catalog.hpp"
#include "arbiter/dump.hpp"
#include "arbiter/explain.hpp"
#include "arbiter/schema.hpp"
#include "arbiter/trace_reader.hpp"
#include "commands/command.hpp"
#include "commands/record.hpp"
#include "lsp/server.hpp"

namespace arbiter::cli {

namespace {

/// False (after telling why) when `--layer` names no layer of the program.
bool check_layer(const arbiter::Program& program, const Options& options) {
  if (options.layer.empty()) return true;
  std::vector<std::string> names;
  for (const auto& layer : program.layers) {
    if (layer.name == options.layer) return true;
    names.push_back(layer.name);
  }
  std::cerr << fmt::format("arbiter dump: no layer '{}' in {}; {}\n",
                           arbiter::printable(options.layer), arbiter::printable(options.file),
                           arbiter::suggest(options.layer, names));
  return false;
}

/// The built-ins, plus the plugins named with --load, or else every plugin on the path (none
/// with --builtin). A plugin that fails to load is reported; false then.
bool registry_for_listing(const Options& options, const char* command,
                          arbiter::Registry& registry) {
  if (options.builtin_only) return true;
  const auto plugin_options = load_options_of(options).plugins;
  const auto names = options.load.empty() ? arbiter::plugins_on_path(plugin_options) : options.load;
  arbiter::Diagnostics diagnostics;
  const arbiter::SourceLocation where{fmt::format("arbiter {}", command), 0, 0};
  bool ok = true;
  for (const auto& name : names) {
    ok = arbiter::load_plugin(name, where, "", plugin_options, registry, diagnostics) && ok;
  }
  if (!diagnostics.empty()) std::cerr << arbiter::format(diagnostics, options.diagnostic_format);
  return ok;
}

}  // namespace

int validate_command(const Options& options) {
  auto registry = make_registry();
  arbiter::Diagnostics all;
  bool ok = true;
  for (const auto& file : options.files) {
    arbiter::Diagnostics diagnostics;
    ok = arbiter::load(file, registry, diagnostics, load_options_of(options)).has_value() && ok;
    all.append(diagnostics);
    if (options.format == "text" && diagnostics.empty()) {
      std::cerr << fmt::format("{}: ok\n", file);
    }
  }
  print_diagnostics(all, options);
  if (options.format == "text" && !all.empty()) {
    std::cerr << fmt::format("{} error(s), {} warning(s)\n", all.error_count(),
                             all.warning_count());
  }
  return ok ? kExitOk : kExitInvalid;
}

int dump_command(const Options& options) {
  auto registry = make_registry();
  auto program = load_or_report(options.file, registry, options);
  if (!program) return kExitInvalid;
  if (!check_layer(*program, options)) return kExitUsage;
  if (options.format == "dot") {
    std::cout << arbiter::dump_dot(*program, options.layer);
  } else if (options.format == "json") {
    std::cout << arbiter::dump_json(*program, options.layer);
  } else {
    std::cout << arbiter::dump_text(*program, options.layer);
  }
  return kExitOk;
}

int plugins_command(const Options& options) {
  auto registry = make_registry();
  const bool ok = registry_for_listing(options, "plugins", registry);
  std::cout << (options.format == "json" ? arbiter::catalog_json(registry)
                                         : arbiter::catalog_text(registry));
  return ok ? kExitOk : kExitInvalid;
}

int schema_command(const Options& options) {
  auto registry = make_registry();
  const bool ok = registry_for_listing(options, "schema", registry);
  std::cout << arbiter::config_schema(registry);
  return ok ? kExitOk : kExitInvalid;
}

namespace {

// What explain and seek ask of a run: the program its config compiles to and the question's
// subject (what to explain, the condition to seek). With one positional the config is left out
// (a recording carries its own): the positional is the subject. A config file given alone is not
// a subject: the subject was forgotten, and `missing` says what to give.
std::optional<Program> program_for_question(const Options& options, const char* command,
                                            const char* missing, Registry& registry,
                                            std::string& subject, int& exit) {
  std::string config = options.file;
  subject = options.target;
  if (subject.empty()) std::swap(config, subject);
  if (subject.empty() || std::filesystem::is_regular_file(subject)) {
    std::cerr << fmt::format("arbiter {}: {}\n", command, missing);
    exit = kExitUsage;
    return std::nullopt;
  }
  exit = kExitInvalid;
  return program_of_run(config, options.trace_path, registry, load_options_of(options), command,
                        options.diagnostic_format, std::cerr, exit);
}

}  // namespace

int explain_command(const Options& options) {
  auto registry = make_registry();
  std::string target;
  int exit = kExitInvalid;
  auto program = program_for_question(
      options, "explain", "name the behaviour, state machine, actuator or state to explain",
      registry, target, exit);
  if (!program) return exit;
  const auto trace = arbiter::open_trace(options.trace_path);
  const auto explanation = arbiter::explain(*program, *trace, options.step, target);
  if (explanation.status == arbiter::Explanation::Status::kOk) {
    // Its states, events and values are the trace's: escaped like every quote of input.
    std::cout << arbiter::printable(explanation.text, true);
    return kExitOk;
  }
  if (explanation.where) {
    std::cerr << arbiter::format(
        arbiter::Diagnostic{*explanation.where, arbiter::Severity::kError, "bad-trace",
                            explanation.text, explanation.notes},
        options.diagnostic_format);
    return kExitInvalid;
  }
  std::cerr << fmt::format("arbiter explain: {}\n", arbiter::printable(explanation.text));
  for (const auto& note : explanation.notes) {
    std::cerr << fmt::format("  note: {}\n", arbiter::printable(note.text));
  }
  return explanation.status == arbiter::Explanation::Status::kNotFound ? kExitUsage : kExitInvalid;
}

bool set_breakpoints(const std::vector<std::string>& conditions, const Program& program,
                     std::string_view option, const FormatOptions& format, std::ostream& err,
                     std::vector<Breakpoint>& out) {
  bool ok = true;
  for (const auto& text : conditions) {
    std::string error;
    auto breakpoint = arbiter::make_breakpoint(program, text, option, format, error);
    if (!breakpoint) {
      err << error;
      ok = false;
      continue;
    }
    out.push_back(std::move(*breakpoint));
  }
  return ok;
}

int seek_command(const Options& options) {
  auto registry = make_registry();
  std::string condition;
  int exit = kExitInvalid;
  auto program = program_for_question(options, "seek",
                                      "give the condition to seek, e.g. 'kick_ball activates'",
                                      registry, condition, exit);
  if (!program) return exit;
  std::vector<arbiter::Breakpoint> breakpoints;
  if (!set_breakpoints({condition}, *program, "CONDITION", options.diagnostic_format, std::cerr,
                       breakpoints)) {
    return kExitUsage;
  }
  const auto trace = arbiter::open_trace(options.trace_path);
  std::optional<arbiter::Diagnostic> error;
  const auto hit = arbiter::seek(*trace, breakpoints, options.step, error);
  if (error) {
    std::cerr << arbiter::format(*error, options.diagnostic_format);
    return kExitInvalid;
  }
  if (!hit) {
    std::cerr << fmt::format("arbiter seek: no step{} where {}\n",
                             options.step > 0 ? fmt::format(" after step {}", options.step) : "",
                             arbiter::printable(breakpoints.front().condition.text));
    return kExitInvalid;
  }
  std::cout << hit->step << "\n";
  return kExitOk;
}

int lsp_command(const Options& options) {
  // stdout carries the protocol: nothing else may write to it.
  std::ios::sync_with_stdio(false);
  return arbiter::lsp::run(std::cin, std::cout, make_registry, load_options_of(options));
}

}  // namespace arbiter::cli

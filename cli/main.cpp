// The `arbiter` command: a thin client of the engine library.

#include <fmt/format.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <unistd.h>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <thread>

#include "arbiter/catalog.hpp"
#include "arbiter/dump.hpp"
#include "arbiter/explain.hpp"
#include "arbiter/lint.hpp"
#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/program.hpp"
#include "arbiter/schema.hpp"
#include "arbiter/trace.hpp"
#include "arbiter/trace_reader.hpp"
#include "builtins.hpp"
#include "lsp/server.hpp"
#include "plot.hpp"
#include "record.hpp"
#include "run_report.hpp"
#include "serve.hpp"
#include "test_command.hpp"
#include "timing.hpp"
#include "view.hpp"
#include "watch.hpp"

namespace {

constexpr int kExitOk = 0;
constexpr int kExitInvalid = 1;
constexpr int kExitUsage = 2;

struct Options {
  std::vector<std::string> files;
  std::string file;
  std::vector<std::string> plugin_path;
  bool realtime = false;
  bool full_speed = false;  ///< `run --full-speed`: unpaced even with --serve
  std::string format = "text";
  bool strict = false;
  std::uint64_t steps = 100;
  bool steps_given = false;  ///< `--steps` was on the command line: it overrides the config's
  std::string trace_path;
  std::string layer;
  bool quiet = false;
  std::string log_level = "warn";
  std::optional<std::size_t> max_file_bytes;  ///< unset: the library's default
  std::vector<std::string> load;  ///< plugins to list (`plugins`, `schema`); empty: all found
  bool builtin_only = false;
  std::uint64_t step = 0;
  std::string target;
  bool watch = false;                         ///< `run --watch`
  std::string serve;                          ///< `run --serve`: [ADDR:]PORT
  std::string view_serve = "127.0.0.1:8080";  ///< `view --serve`
  std::string output;                         ///< `plot -o`
  bool actuators = false;
  bool paused = false;             ///< `run --paused`
  arbiter::cli::TestCommand test;  ///< `test`
  int rt_priority = 0;             ///< `run --rt-priority`; 0: normal scheduling
  std::string serve_token;  ///< `run --serve-token` (or ARBITER_SERVE_TOKEN); empty: a random one
  bool serve_readonly = false;
  std::string record_path;                                  ///< `run --record`, `replay --record`
  double record_flush = arbiter::Recorder::kFlushInterval;  ///< `--record-flush` (seconds)
  std::string config;                                       ///< `replay --config`
  std::string recording;                                    ///< `replay RUN.mcap`
  std::string diff_a;                                       ///< `diff A B`
  std::string diff_b;
  double tolerance = 1e-9;     ///< `diff --tolerance`
  std::string compare_path;    ///< `plot --compare`
  std::string color = "auto";  ///< `--color`
  arbiter::FormatOptions diagnostic_format = arbiter::FormatOptions::readable();
};

constexpr const char* kVersion = "0.1.0";

/// `--color auto` colours diagnostics when stderr is a terminal (and NO_COLOR is not set).
bool use_color(const std::string& choice) {
  if (choice != "auto") return choice == "always";
  const char* term = std::getenv("TERM");
  return isatty(fileno(stderr)) != 0 && std::getenv("NO_COLOR") == nullptr && term != nullptr &&
         std::string_view(term) != "dumb";
}

arbiter::Registry make_registry() {
  arbiter::Registry registry;
  arbiter::register_builtin_behaviours(registry);
  return registry;
}

void print_diagnostics(const arbiter::Diagnostics& diagnostics, const Options& options) {
  if (options.format == "json") {
    std::cout << arbiter::format_json(diagnostics);
  } else {
    std::cerr << arbiter::format(diagnostics, options.diagnostic_format);
  }
}

arbiter::LoadOptions load_options_of(const Options& options) {
  arbiter::LoadOptions load_options;
  load_options.strict = options.strict;
  load_options.lint = arbiter::lint;
  load_options.plugins.path = options.plugin_path;
  if (options.max_file_bytes) load_options.limits.max_file_bytes = *options.max_file_bytes;
  return load_options;
}

std::optional<arbiter::Program> load_or_report(const std::string& path, arbiter::Registry& registry,
                                               const Options& options) {
  arbiter::Diagnostics diagnostics;
  auto program = arbiter::load(path, registry, diagnostics, load_options_of(options));
  if (!diagnostics.empty()) std::cerr << arbiter::format(diagnostics, options.diagnostic_format);
  return program;
}

int validate(const Options& options) {
  auto registry = make_registry();
  arbiter::Diagnostics all;
  bool ok = true;
  for (const auto& file : options.files) {
    arbiter::Diagnostics diagnostics;
    ok = arbiter::load(file, registry, diagnostics, load_options_of(options)).has_value() && ok;
    for (const auto& item : diagnostics.items()) {
      if (item.severity == arbiter::Severity::kError) {
        all.error(item.location, item.code, item.message).notes = item.notes;
      } else {
        all.warning(item.location, item.code, item.message).notes = item.notes;
      }
    }
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

/// False (after telling why) when `--layer` names no layer of the program.
bool check_layer(const arbiter::Program& program, const Options& options) {
  if (options.layer.empty()) return true;
  std::vector<std::string> names;
  for (const auto& layer : program.layers) {
    if (layer.name == options.layer) return true;
    names.push_back(layer.name);
  }
  std::cerr << fmt::format("arbiter dump: no layer '{}' in {}; {}\n", options.layer, options.file,
                           arbiter::suggest(options.layer, names));
  return false;
}

int dump(const Options& options) {
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

/// The names of the plugins on the search path (`arbiter_NAME.so`), each once: the first
/// directory that has it wins, as when a config names it.
std::vector<std::string> plugins_on_path(const arbiter::PluginOptions& plugin_options) {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  std::set<std::string> seen;
  for (const auto& dir : arbiter::plugin_search_path(plugin_options)) {
    std::error_code error;
    std::vector<std::string> here;
    for (const auto& entry : fs::directory_iterator(dir, error)) {
      const std::string file = entry.path().filename().string();
      constexpr std::string_view kPrefix = "arbiter_";
      constexpr std::string_view kSuffix = ".so";
      if (!entry.is_regular_file(error) || file.size() <= kPrefix.size() + kSuffix.size() ||
          file.compare(0, kPrefix.size(), kPrefix) != 0 ||
          file.compare(file.size() - kSuffix.size(), kSuffix.size(), kSuffix) != 0) {
        continue;
      }
      here.push_back(file.substr(kPrefix.size(), file.size() - kPrefix.size() - kSuffix.size()));
    }
    std::sort(here.begin(), here.end());
    for (auto& name : here) {
      if (seen.insert(name).second) names.push_back(std::move(name));
    }
  }
  return names;
}

/// The built-ins, plus the plugins named with --load, or else every plugin on the path (none
/// with --builtin). A plugin that fails to load is reported; false then.
bool registry_for_listing(const Options& options, const char* command,
                          arbiter::Registry& registry) {
  if (options.builtin_only) return true;
  const auto plugin_options = load_options_of(options).plugins;
  const auto names = options.load.empty() ? plugins_on_path(plugin_options) : options.load;
  arbiter::Diagnostics diagnostics;
  const arbiter::SourceLocation where{fmt::format("arbiter {}", command), 0, 0};
  bool ok = true;
  for (const auto& name : names) {
    ok = arbiter::load_plugin(name, where, "", plugin_options, registry, diagnostics) && ok;
  }
  if (!diagnostics.empty()) std::cerr << arbiter::format(diagnostics, options.diagnostic_format);
  return ok;
}

int plugins(const Options& options) {
  auto registry = make_registry();
  const bool ok = registry_for_listing(options, "plugins", registry);
  std::cout << (options.format == "json" ? arbiter::catalog_json(registry)
                                         : arbiter::catalog_text(registry));
  return ok ? kExitOk : kExitInvalid;
}

int schema(const Options& options) {
  auto registry = make_registry();
  const bool ok = registry_for_listing(options, "schema", registry);
  std::cout << arbiter::config_schema(registry);
  return ok ? kExitOk : kExitInvalid;
}

int lsp(const Options& options) {
  // stdout carries the protocol: nothing else may write to it.
  std::ios::sync_with_stdio(false);
  return arbiter::lsp::run(std::cin, std::cout, make_registry, load_options_of(options));
}

int explain(const Options& options) {
  auto registry = make_registry();
  auto program = load_or_report(options.file, registry, options);
  if (!program) return kExitInvalid;
  if (!std::ifstream(options.trace_path, std::ios::binary)) {
    std::cerr << fmt::format("arbiter explain: cannot read trace '{}'\n", options.trace_path);
    return kExitUsage;
  }
  const auto trace = arbiter::open_trace(options.trace_path);
  const auto explanation = arbiter::explain(*program, *trace, options.step, options.target);
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

int test(Options& options) {
  auto registry = make_registry();
  options.test.options.plugins = load_options_of(options).plugins;
  options.test.options.limits = load_options_of(options).limits;
  return arbiter::cli::run_tests(options.test, registry, std::cout, std::cerr);
}

std::atomic<bool> interrupted{false};

extern "C" void on_interrupt(int) {
  interrupted = true;
}

int run(const Options& options) {
  auto registry = make_registry();
  arbiter::Reloader reloader(registry, load_options_of(options));  // --watch
  auto program = options.watch ? arbiter::cli::load_watched(reloader, options.file, std::cerr,
                                                            options.diagnostic_format)
                               : load_or_report(options.file, registry, options);
  if (!program) return kExitInvalid;
  const double rate_hz = program->rate_hz;
  const std::uint64_t steps =
      options.steps_given || options.watch || program->steps == 0 ? options.steps : program->steps;

  std::ofstream trace_file;
  if (!options.trace_path.empty()) {
    trace_file.open(options.trace_path, std::ios::binary | std::ios::trunc);
    if (!trace_file) {
      std::cerr << fmt::format("arbiter run: cannot write trace '{}'\n", options.trace_path);
      return kExitUsage;
    }
  }
  arbiter::Manager manager(std::move(*program), spdlog::default_logger());
  arbiter::TraceWriter trace(trace_file);
  if (trace_file.is_open()) manager.add_observer(trace);
  arbiter::cli::RunReport report(std::cout, options.quiet);
  manager.add_observer(report);
  // In a terminal, a watched run keeps a status line on stderr: it shows an idle run is alive.
  std::optional<arbiter::cli::StatusLine> status;
  std::optional<arbiter::cli::StatusClearer> clear_out, clear_err;
  if (options.watch && !options.quiet && ::isatty(STDERR_FILENO) == 1) {
    status.emplace(STDERR_FILENO);
    clear_out.emplace(std::cout, *status);
    clear_err.emplace(std::cerr, *status);
  }
  // The log goes through std::cerr meanwhile, so that it too takes the status line away first.
  std::vector<spdlog::sink_ptr> log_sinks;
  if (status) {
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(std::cerr, true);
    sink->set_pattern("%l: %v");
    log_sinks.swap(spdlog::default_logger()->sinks());
    spdlog::default_logger()->sinks().push_back(std::move(sink));
  }
  std::unique_ptr<arbiter::Recorder> recorder;  // --record
  if (!options.record_path.empty()) {
    // Paced, a step the writer has no room for is dropped rather than the pace lost; flat out,
    // the run waits for the writer and the recording loses nothing.
    recorder = std::make_unique<arbiter::Recorder>(
        options.record_path,
        arbiter::cli::recording_info(options.file, registry, load_options_of(options), kVersion),
        arbiter::Recorder::kSlots,
        options.realtime ? arbiter::RingFull::kDropStep : arbiter::RingFull::kWaitForWriter);
    if (!recorder->ok()) {
      std::cerr << fmt::format("arbiter run: cannot write recording '{}'\n", options.record_path);
      return kExitUsage;
    }
    recorder->set_flush_interval(options.record_flush);
    manager.add_observer(*recorder);
    // A reload's files go into the recording, for replay to reload them too.
    reloader.set_on_staging(
        [&recorder](const arbiter::Reloader::FileTexts& files) { recorder->stage_files(files); });
  }
  // After the recorder: a reload staged by the watcher is recorded with its files.
  std::optional<arbiter::cli::Watcher> watcher;
  if (options.watch)
    watcher.emplace(reloader, manager, std::cout, std::cerr, options.quiet,
                    options.diagnostic_format, status ? &*status : nullptr);
  std::unique_ptr<arbiter::cli::LiveView> live;  // --serve
  if (!options.serve.empty()) {
    arbiter::cli::LiveAccess access;
    access.token = options.serve_token;
    access.readonly = options.serve_readonly;
    live =
        arbiter::cli::LiveView::open(options.serve, options.paused, access, std::cout, std::cerr);
    if (!live) return kExitUsage;
    manager.add_observer(*live);
  }
  arbiter::cli::SteadyStepClock clock;
  manager.set_clock(&clock);
  arbiter::cli::RunTiming timing(1.0 / rate_hz);
  if (live) live->set_timing(&timing, options.realtime);
  if (options.rt_priority > 0) {
    std::string error;
    if (!arbiter::cli::enter_realtime(options.rt_priority, error)) {
      std::cerr << fmt::format("arbiter run: {}\n", error);
      return kExitUsage;
    }
  }

  // Ctrl-C ends the run between two steps, so the trace and the summary are still complete.
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  using Clock = std::chrono::steady_clock;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate_hz));
  const auto started = Clock::now();
  // Absolute deadlines: step i starts at started + i periods. A step that overruns never brings
  // a burst of catch-up steps: the next one waits for the next period boundary, and the periods
  // skipped are counted.
  auto next = started;
  for (std::uint64_t i = 0; i < steps && !interrupted; ++i) {
    if (live && live->will_hold()) manager.safe_pass();  // paused from the page: make it safe
    if (live && live->hold(manager, interrupted)) {
      if (interrupted) break;
      next = Clock::now();
    }
    if (options.realtime) {
      std::this_thread::sleep_until(next);
      timing.record_lateness(std::chrono::duration<double>(Clock::now() - next).count());
    }
    manager.step();
    if (watcher) watcher->set_step(manager.steps());
    timing.record_step(manager.step_duration());
    if (manager.stopped()) break;  // on_exception: stop — the run ends with this step
    if (options.realtime) {
      next += period;
      if (const auto now = Clock::now(); now > next) {
        const auto missed = (now - next) / period + 1;
        next += missed * period;
        timing.record_missed(static_cast<std::uint64_t>(missed));
      }
    }
  }
  watcher.reset();
  if (status) spdlog::default_logger()->sinks().swap(log_sinks);
  clear_err.reset();
  clear_out.reset();
  status.reset();
  manager.finish();  // outputs the safe values, whatever ended the run
  if (recorder && recorder->dropped() > 0) {
    std::cerr << fmt::format(
        "arbiter run: the recording dropped {} steps (its writer fell behind the paced "
        "steps); each gap is recorded\n",
        recorder->dropped());
  }
  if (!options.quiet) {
    const double wall = std::chrono::duration<double>(Clock::now() - started).count();
    std::cout << fmt::format("{}simulated {:.2f} s at {} Hz in {:.3f} s of wall time{}\n",
                             interrupted ? "interrupted: " : "",
                             static_cast<double>(manager.steps()) / rate_hz, rate_hz, wall,
                             options.realtime ? " (real time)" : "");
    std::cout << timing.text(options.realtime) << std::flush;
  }
  if (live) live->serve_until(manager, interrupted);
  if (trace_file.is_open() && !trace_file) {
    std::cerr << fmt::format("arbiter run: writing trace '{}' failed\n", options.trace_path);
    return kExitInvalid;
  }
  if (recorder && recorder->failed()) {
    std::cerr << arbiter::cli::recording_failed("run", options.record_path, recorder->error());
    return kExitInvalid;
  }
  if (manager.stopped()) {
    std::cerr << fmt::format("arbiter run: stopped after step {}: {}\n", manager.steps(),
                             manager.stop_reason());
    return kExitInvalid;
  }
  return kExitOk;
}

int view(const Options& options) {
  auto registry = make_registry();
  auto program = load_or_report(options.file, registry, options);
  if (!program) return kExitInvalid;
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  std::string unused;  // the option's check has parsed it already
  arbiter::cli::LiveAccess access;
  access.token = options.serve_token;
  return arbiter::cli::view_trace(
      *program, options.trace_path, arbiter::cli::ServeAddress::parse(options.view_serve, unused),
      access, options.step > 0 ? std::optional(options.step) : std::nullopt, interrupted, std::cout,
      std::cerr, options.diagnostic_format);
}

int plot(const Options& options) {
  std::string error;
  const auto trace =
      arbiter::cli::read_trace_file(options.trace_path, error, options.diagnostic_format);
  if (!trace) {
    std::cerr << error << "\n";
    return kExitInvalid;
  }
  arbiter::cli::note_end(options.trace_path, trace->truncated, trace->damaged, std::cerr);
  arbiter::cli::PlotOptions plot_options;
  plot_options.actuators = options.actuators;
  std::optional<arbiter::cli::TraceFile> compare;  // --compare
  if (!options.compare_path.empty()) {
    compare = arbiter::cli::read_trace_file(options.compare_path, error, options.diagnostic_format);
    if (!compare) {
      std::cerr << error << "\n";
      return kExitInvalid;
    }
    arbiter::cli::note_end(options.compare_path, compare->truncated, compare->damaged, std::cerr);
    plot_options.compare = &*compare;
  }
  const std::string svg = arbiter::cli::plot_svg(*trace, plot_options);
  if (options.output.empty() || options.output == "-") {
    std::cout << svg;
    return kExitOk;
  }
  std::ofstream out(options.output, std::ios::binary | std::ios::trunc);
  if (!(out << svg << std::flush)) {
    std::cerr << fmt::format("arbiter plot: cannot write '{}'\n", options.output);
    return kExitUsage;
  }
  return kExitOk;
}

/// CLI11 check of `--serve-token`: it travels in URLs and cookies.
std::string check_serve_token(const std::string& text) {
  return arbiter::cli::token_error(text);
}

/// CLI11 check of `--serve [ADDR:]PORT`.
std::string check_serve_address(const std::string& text) {
  std::string error;
  arbiter::cli::ServeAddress::parse(text, error);
  return error;
}

/// CLI11 check of `--record-flush SECONDS`.
std::string check_record_flush(const std::string& text) {
  char* end = nullptr;
  const double seconds = std::strtod(text.c_str(), &end);
  if (end != text.c_str() && *end == '\0' && seconds >= 0.0 &&
      seconds <= arbiter::Recorder::kMaxFlushInterval) {
    return {};
  }
  return fmt::format("must be a number of seconds from 0 to {:g}, found '{}'",
                     arbiter::Recorder::kMaxFlushInterval, text);
}

constexpr const char* kExitCodes =
    "Exit codes: 0 ok, 1 invalid config (or failed run), 2 usage error.";
constexpr const char* kExitCodesTrace =
    "Exit codes: 0 ok, 1 invalid config or trace, 2 usage error.";

std::string lint_list() {
  std::string out =
      "Lints (warnings; silence one with 'lint: {ignore: [CODE]}' at the top level of "
      "a config or in a layer):\n";
  for (const auto& lint : arbiter::lint_codes()) {
    out += fmt::format("  {:<22} {}\n", lint.code, lint.summary);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "arbiter: a data-driven behaviour engine for robots.\n"
      "Behaviour layers, inhibitions and state controllers are declared in YAML or JSON configs,\n"
      "validated with file:line:column diagnostics, and bound to C++ classes.\n",
      "arbiter"};
  app.footer(fmt::format(
      "Examples:\n"
      "  arbiter validate configs/paper/walk_and_kick.yaml\n"
      "  arbiter run configs/paper/walk_and_kick.yaml --steps 20 --trace out.jsonl\n"
      "  arbiter explain configs/paper/walk_and_kick.yaml --trace out.jsonl --step 8 "
      "search_for_ball\n"
      "  arbiter dump configs/paper/walk_and_kick.yaml --format dot | dot -Tsvg -o graph.svg\n"
      "  arbiter test tests/scenarios/soccer/\n"
      "  arbiter plugins\n"
      "  arbiter schema > arbiter.schema.json\n\n"
      "{}\n"
      "Run 'arbiter COMMAND --help' for a command's options and examples.",
      kExitCodes));
  app.require_subcommand(1);
  // Global options also work after the command: `arbiter run FILE --plugin-path DIR`.
  app.fallthrough();
  app.set_version_flag("--version", std::string("arbiter ") + kVersion);
  Options options;
  app.add_option("--log-level", options.log_level,
                 "run-time log level: trace, debug, info, warn, error, off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->capture_default_str();
  app.add_option("--plugin-path", options.plugin_path,
                 "a directory to look for plugins in (repeatable); searched before "
                 "ARBITER_PLUGIN_PATH and the plugins that come with arbiter")
      ->type_name("DIR");
  app.add_option("--max-file-bytes", options.max_file_bytes,
                 "refuse config files (and included files) larger than this; default 16777216 "
                 "(16 MiB)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 40))
      ->type_name("BYTES");
  app.add_option("--color", options.color,
                 "colour the diagnostics: auto (when stderr is a terminal and NO_COLOR is unset), "
                 "always or never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->capture_default_str();

  auto* validate_cmd = app.add_subcommand(
      "validate",
      "Load and compile configs; print every problem as file:line:col: error|warning: message.\n"
      "Exit 0 when all are valid, 1 when any is invalid, 2 on a usage error.");
  // No existence check on config files: a missing one is reported like any other unreadable
  // config (exit 1), and validate still checks the other files.
  validate_cmd->add_option("FILE", options.files, "config files (.yaml, .yml, .json)")->required();
  validate_cmd
      ->add_option("--format", options.format,
                   "diagnostics as text (stderr) or json (stdout: an array of {file, line, "
                   "column, severity, code, message, notes}, with note_locations where a note "
                   "names a place)")
      ->check(CLI::IsMember({"text", "json"}))
      ->capture_default_str();
  validate_cmd->add_flag("--strict", options.strict, "treat warnings (and lints) as errors");
  validate_cmd->footer(
      "Examples:\n"
      "  arbiter validate configs/paper/*.yaml\n"
      "  arbiter validate --strict robot.yaml          # a warning fails the check too\n"
      "  arbiter validate --format json robot.yaml     # for editors and CI\n"
      "  arbiter --plugin-path build/plugins validate configs/soccer/walk_and_kick.yaml\n\n" +
      lint_list() + "\n" + kExitCodes);

  auto* run_cmd = app.add_subcommand(
      "run", "Run a config's behaviour manager for a number of steps and report what happened.");
  run_cmd->add_option("FILE", options.file, "the config to run")->required();
  run_cmd
      ->add_option("--steps", options.steps,
                   "number of steps to run (default: the config's 'steps:', else 100)")
      ->check(CLI::Range(std::uint64_t{0}, std::uint64_t{1} << 40))
      ->capture_default_str();
  run_cmd->add_option("--trace", options.trace_path,
                      "write a JSON-lines trace of every step to this file");
  run_cmd
      ->add_option("--record", options.record_path,
                   "record the run as MCAP (steps, interface inputs, the config) for "
                   "'arbiter replay', 'arbiter diff' and Foxglove; flat out, the run waits "
                   "for the recording's writer; paced (--realtime, --serve), a step it has no "
                   "room for is dropped and the gap recorded. A write that fails (a full disk) "
                   "is reported at once and ends the recording, not the run, which then exits 1")
      ->type_name("RUN.mcap");
  run_cmd
      ->add_option("--record-flush", options.record_flush,
                   "with --record: write the recording out to the disk at least every SECONDS, "
                   "so that a crash or a power cut loses at most about that much; 0: only every "
                   "256 KiB of steps (smaller files)")
      ->check(check_record_flush, "")
      ->type_name("SECONDS")
      ->capture_default_str()
      ->needs("--record");
  run_cmd->add_flag("--quiet,-q", options.quiet, "print nothing but errors");
  run_cmd->add_flag("--realtime", options.realtime,
                    "pace the steps at the config's rate_hz instead of running flat out");
  run_cmd->add_flag("--strict", options.strict, "treat config warnings as errors");
  run_cmd
      ->add_flag("--full-speed", options.full_speed,
                 "run flat out even with --serve (which otherwise paces at rate_hz), e.g. for a "
                 "soak test")
      ->excludes("--realtime");
  run_cmd->add_flag("--watch", options.watch,
                    "reload the config whenever it or a file it includes changes, without "
                    "stopping the run (a broken edit is reported and the previous config runs "
                    "on); without --steps, runs until Ctrl-C");
  run_cmd
      ->add_option("--serve", options.serve,
                   "serve the live view (a web page) on [ADDR:]PORT (ADDR defaults to 127.0.0.1, "
                   "PORT 0 picks a free one) and pace the steps at rate_hz; the server stays up "
                   "after the last step until Ctrl-C")
      ->check(check_serve_address, "")
      ->type_name("[ADDR:]PORT");
  run_cmd
      ->add_flag("--paused", options.paused,
                 "with --serve: wait for the page's Step or Resume before the first step")
      ->needs("--serve");
  run_cmd
      ->add_option("--serve-token", options.serve_token,
                   "with --serve: the token the page and every request must carry (default: a "
                   "random one per run, printed in the URL; also ARBITER_SERVE_TOKEN)")
      ->envname("ARBITER_SERVE_TOKEN")
      ->type_name("TOKEN")
      ->check(check_serve_token, "");
  run_cmd
      ->add_flag("--serve-readonly", options.serve_readonly,
                 "with --serve: watch only; the page cannot pause, step or resume the run")
      ->needs("--serve");
  run_cmd
      ->add_option("--rt-priority", options.rt_priority,
                   "run the stepping thread under SCHED_FIFO at this priority (1-99) with memory "
                   "locked; needs CAP_SYS_NICE or RLIMIT_RTPRIO, and CAP_IPC_LOCK or "
                   "RLIMIT_MEMLOCK (exit 2 when not permitted)")
      ->check(CLI::Range(1, 99))
      ->type_name("N");
  run_cmd->footer(
      std::string("Examples:\n"
                  "  arbiter run configs/paper/walk_and_kick.yaml --steps 20\n"
                  "  arbiter run configs/paper/walk_and_kick.yaml --trace out.jsonl -q\n"
                  "  arbiter run configs/soccer/walk_and_kick.yaml --realtime   # Ctrl-C "
                  "stops cleanly\n"
                  "  arbiter run configs/soccer/walk_and_kick.yaml --steps 300 --serve 8080   "
                  "# then open the printed URL (it carries the token)\n"
                  "  arbiter run configs/soccer/walk_and_kick.yaml --realtime --rt-priority 50   "
                  "# SCHED_FIFO\n\n"
                  "Actuators with a 'safe:' value carry it in a last output pass when the run "
                  "pauses or ends\n(Ctrl-C, SIGTERM, --steps, on_exception: stop). With "
                  "--realtime the summary gives the period\njitter and step durations (p50, "
                  "p99, max) and the overruns.\n"
                  "Then 'arbiter explain FILE --trace out.jsonl --step N BEHAVIOUR' tells why "
                  "a behaviour had its level.\n") +
      kExitCodes);

  auto* dump_cmd = app.add_subcommand(
      "dump",
      "Print the compiled graph: layers in order, behaviours in execution (topological) order,\n"
      "declared and implicit inhibitions, actuator → sensor wiring, state machines.");
  dump_cmd->add_option("FILE", options.file, "the config to dump")->required();
  dump_cmd->add_option("--layer", options.layer, "only this layer");
  dump_cmd
      ->add_option("--format", options.format,
                   "text (for people), dot (Graphviz: chaining inhibitions double, non-chaining "
                   "single, implicit dashed) or json (for tools)")
      ->check(CLI::IsMember({"text", "dot", "json"}))
      ->capture_default_str();
  dump_cmd->footer(
      std::string("Examples:\n"
                  "  arbiter dump configs/paper/walk_and_kick.yaml\n"
                  "  arbiter dump configs/paper/walk_and_kick.yaml --format dot | dot -Tsvg "
                  "-o walk_and_kick.svg\n"
                  "  arbiter dump configs/soccer/walk_and_kick.yaml --layer control --format "
                  "json\n\n") +
      kExitCodes);

  auto* explain_cmd = app.add_subcommand(
      "explain",
      "Explain, from a trace of 'arbiter run', why a behaviour had its activation level at one\n"
      "step: its requested level, each inhibitor's level and factor (1 - a), the chain behind an\n"
      "implicit inhibition, the product and the normalisation. Naming a state machine instead\n"
      "tells which state ran, what was queued and the events.");
  explain_cmd->add_option("FILE", options.file, "the config the trace was written with")
      ->required();
  explain_cmd
      ->add_option("BEHAVIOUR", options.target,
                   "a behaviour ('name', or 'layer/name' when several layers have one of that "
                   "name) or a state machine ('name' or 'state_machines/name')")
      ->required();
  explain_cmd
      ->add_option("--trace", options.trace_path, "the JSON-lines trace (arbiter run --trace)")
      ->required()
      ->check(CLI::ExistingFile);
  explain_cmd->add_option("--step", options.step, "the step, counting from 1")
      ->required()
      ->check(CLI::PositiveNumber);
  explain_cmd->footer(
      std::string("Examples:\n"
                  "  arbiter run configs/paper/walk_and_kick.yaml --steps 20 --trace out.jsonl -q\n"
                  "  arbiter explain configs/paper/walk_and_kick.yaml --trace out.jsonl --step 8 "
                  "search_for_ball\n"
                  "  arbiter explain configs/paper/hierarchical.yaml --trace h.jsonl --step 6 "
                  "match\n\n"
                  "Exit codes: 0 ok, 1 invalid config or trace, 2 usage error (no such behaviour "
                  "or step)."));

  auto* test_cmd = app.add_subcommand(
      "test",
      "Run scenario tests: a behaviour graph stepped without a robot, its interface layers or\n"
      "classes substituted and its inputs scripted, checked step by step against what the test\n"
      "expects (docs/testing.md). Prints one line per test and, for each failed expectation,\n"
      "file:line:col: error: expected ..., got ... followed by the explanation of that\n"
      "behaviour or state machine at that step.");
  test_cmd
      ->add_option("PATH", options.test.paths,
                   "test files (arbiter_test: 1), or directories: every *.test.yaml, "
                   "*.test.yml and *.test.json in them")
      ->required();
  test_cmd
      ->add_option("--tolerance", options.test.options.tolerance,
                   "how far a level or number may be from one expected as a single number")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  test_cmd
      ->add_option("--junit", options.test.junit,
                   "also write JUnit XML to FILE (one testcase per test file, one failure "
                   "per failed expectation), for CI systems")
      ->type_name("FILE");
  test_cmd->footer(
      "Examples:\n"
      "  arbiter test tests/scenarios/soccer/kick_needs_a_close_ball.test.yaml\n"
      "  arbiter test tests/scenarios/ --junit results.xml   # every test under a directory\n"
      "  arbiter test --tolerance 0.01 my_tests/\n\n"
      "A test file:\n"
      "  arbiter_test: 1\n"
      "  config: ../walk_and_kick.yaml        # relative to the test file\n"
      "  substitute:\n"
      "    world: inputs                      # this interface layer is fed from inputs: below\n"
      "    control/kick_ball: {type: scripted, params: {activation: 0}}\n"
      "  inputs:\n"
      "    - {step: 1, ball_visible: false}\n"
      "    - {step: 10, ball_visible: true, ball_position: [1.0, 0.2]}\n"
      "  expect:\n"
      "    - {step: 5, active: [search_for_ball], inactive: [go_behind_ball]}\n"
      "    - {steps: [12, 40], actuators: {kick: false}}\n"
      "  steps: 40\n\n"
      "A regression test from a recording (arbiter run --record):\n"
      "  arbiter_test: 1\n"
      "  config: ../walk_and_kick.yaml        # may be an edited one\n"
      "  replay: run.mcap                     # the recording's inputs feed the interface layers\n"
      "  expect: identical                    # or expect_trace: run.jsonl\n\n"
      "Exit codes: 0 all passed, 1 a test failed, 2 usage error or invalid test file.");

  auto* view_cmd = app.add_subcommand(
      "view",
      "Serve the web view of a trace of 'arbiter run': the graph, each behaviour coloured by its\n"
      "activation, the state machines, timelines, and a slider to scrub through the steps.");
  view_cmd->add_option("FILE", options.file, "the config the trace was written with")->required();
  view_cmd->add_option("--trace", options.trace_path, "the JSON-lines trace (arbiter run --trace)")
      ->required()
      ->check(CLI::ExistingFile);
  view_cmd
      ->add_option("--serve", options.view_serve,
                   "serve on [ADDR:]PORT (ADDR defaults to 127.0.0.1, PORT 0 picks a free one)")
      ->check(check_serve_address, "")
      ->type_name("[ADDR:]PORT")
      ->capture_default_str();
  view_cmd
      ->add_option("--serve-token", options.serve_token,
                   "the token the page and every request must carry (default: a random one, "
                   "printed in the URL; also ARBITER_SERVE_TOKEN)")
      ->envname("ARBITER_SERVE_TOKEN")
      ->type_name("TOKEN")
      ->check(check_serve_token, "");
  view_cmd
      ->add_option("--step", options.step,
                   "the step the page opens at, counting from 1 (default: the last step)")
      ->check(CLI::PositiveNumber);
  view_cmd->footer(
      std::string(
          "Examples:\n"
          "  arbiter run configs/soccer/walk_and_kick.yaml --steps 220 --trace run.jsonl -q\n"
          "  arbiter view configs/soccer/walk_and_kick.yaml --trace run.jsonl\n"
          "  arbiter view configs/soccer/walk_and_kick.yaml --trace run.jsonl --serve 0\n"
          "  arbiter view configs/soccer/walk_and_kick.yaml --trace run.jsonl --step 171\n\n"
          "Ctrl-C stops the server.\n") +
      kExitCodesTrace);

  auto* plot_cmd = app.add_subcommand(
      "plot",
      "Draw a trace of 'arbiter run' as an SVG timeline: a row per behaviour with its activation,\n"
      "requested level and active steps, a row per state machine with its states and events.");
  plot_cmd->add_option("TRACE", options.trace_path, "the JSON-lines trace (arbiter run --trace)")
      ->required()
      ->check(CLI::ExistingFile);
  plot_cmd->add_option("--output,-o", options.output, "the SVG file to write (default: stdout)")
      ->type_name("FILE");
  plot_cmd->add_flag("--actuators", options.actuators, "add a row per actuator with its value");
  plot_cmd
      ->add_option("--compare", options.compare_path,
                   "a second run (trace or recording): its row of each behaviour under the "
                   "first's, the steps where they differ shaded")
      ->check(CLI::ExistingFile)
      ->type_name("B");
  plot_cmd->footer(
      std::string(
          "Examples:\n"
          "  arbiter run configs/soccer/walk_and_kick.yaml --steps 220 --trace run.jsonl -q\n"
          "  arbiter plot run.jsonl -o timeline.svg\n"
          "  arbiter plot run.jsonl --actuators > timeline.svg\n"
          "  arbiter plot run.mcap --compare what_if.mcap -o compare.svg\n\n") +
      kExitCodesTrace);

  auto* replay_cmd = app.add_subcommand(
      "replay",
      "Run a recorded behaviour system again, as fast as it can, with every interface layer\n"
      "replaced by the recorded inputs. Without --config it checks that the run repeats itself\n"
      "(determinism); with --config it runs an edited graph on the same inputs (what if).");
  replay_cmd->add_option("RUN", options.recording, "the recording (arbiter run --record)")
      ->required()
      ->check(CLI::ExistingFile);
  replay_cmd->add_option("--config", options.config, "an edited config to run instead")
      ->check(CLI::ExistingPath)
      ->type_name("FILE");
  replay_cmd->add_option("--trace", options.trace_path, "write the replay's JSON-lines trace")
      ->type_name("OUT.jsonl");
  replay_cmd
      ->add_option("--record", options.record_path,
                   "record the replay as MCAP; a write that fails is reported at once and ends "
                   "the recording, not the replay, which then exits 2")
      ->type_name("OUT.mcap");
  replay_cmd
      ->add_option("--record-flush", options.record_flush,
                   "with --record: write the recording out to the disk at least every SECONDS; "
                   "0: only every 256 KiB of steps")
      ->check(check_record_flush, "")
      ->type_name("SECONDS")
      ->capture_default_str()
      ->needs("--record");
  replay_cmd
      ->add_option("--steps", options.steps,
                   "replay at most this many steps (the recording is read that far only)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40));
  replay_cmd->footer(
      "Examples:\n"
      "  arbiter run configs/soccer/walk_and_kick.yaml --steps 220 --record run.mcap -q\n"
      "  arbiter replay run.mcap                      # repeats the run exactly?\n"
      "  arbiter replay run.mcap --config edited.yaml --record what_if.mcap\n"
      "  arbiter diff run.mcap what_if.mcap\n\n"
      "Exit codes: 0 ok (the replay matched, or the what-if ran), 1 the replay differs from the "
      "recording or a config or recording is invalid, 2 usage error or an output (--trace, "
      "--record) could not be written.");

  auto* diff_cmd = app.add_subcommand(
      "diff",
      "Compare two runs, traces (.jsonl) or recordings (.mcap) in any mix, step by step: where\n"
      "they first diverge, and per behaviour, actuator and state machine in how many steps.");
  diff_cmd->add_option("A", options.diff_a, "the first run")->required()->check(CLI::ExistingFile);
  diff_cmd->add_option("B", options.diff_b, "the second run")->required()->check(CLI::ExistingFile);
  diff_cmd->add_option("--tolerance", options.tolerance, "numbers this close are equal")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  diff_cmd->add_option("--format", options.format, "text or json")
      ->check(CLI::IsMember({"text", "json"}))
      ->capture_default_str();
  diff_cmd->footer(
      "Examples:\n"
      "  arbiter diff run.mcap what_if.mcap\n"
      "  arbiter diff run.jsonl replay.jsonl --format json\n"
      "  arbiter diff a.mcap b.mcap --tolerance 1e-6\n\n"
      "Exit codes: 0 identical, 1 different, 2 usage error or unreadable input.");

  auto* plugins_cmd = app.add_subcommand(
      "plugins",
      "List the registered classes (the built-ins, and the plugins on the plugin path) with\n"
      "their kind, origin, params (type, default, range, description) and ports.");
  plugins_cmd
      ->add_option("--load", options.load,
                   "list the built-ins and this plugin (repeatable) instead of every plugin on "
                   "the path")
      ->type_name("NAME");
  plugins_cmd->add_flag("--builtin", options.builtin_only, "list the built-in classes only");
  plugins_cmd->add_option("--format", options.format, "text or json")
      ->check(CLI::IsMember({"text", "json"}))
      ->capture_default_str();
  plugins_cmd->footer(
      "Examples:\n"
      "  arbiter plugins\n"
      "  arbiter plugins --load soccer --format json\n"
      "  arbiter --plugin-path ~/robot/plugins plugins\n\n"
      "Exit codes: 0 ok, 1 a plugin failed to load, 2 usage error.");

  auto* schema_cmd = app.add_subcommand(
      "schema",
      "Print the JSON Schema (draft-07) of the config format, extended with the registered\n"
      "classes: 'type:' completes in editors and each class's params and ports are checked.");
  schema_cmd
      ->add_option("--load", options.load,
                   "include the built-ins and this plugin (repeatable) instead of every plugin on "
                   "the path")
      ->type_name("NAME");
  schema_cmd->add_flag("--builtin", options.builtin_only, "include the built-in classes only");
  schema_cmd->footer(
      "Examples:\n"
      "  arbiter schema > arbiter.schema.json\n"
      "  arbiter schema --load soccer > soccer.schema.json\n"
      "Then start a YAML config with\n"
      "  # yaml-language-server: $schema=arbiter.schema.json\n"
      "or give a JSON config a top-level \"$schema\": \"arbiter.schema.json\".\n"
      "schema/arbiter.schema.json in the sources is the same schema without the classes.\n\n"
      "Exit codes: 0 ok, 1 a plugin failed to load, 2 usage error.");

  auto* lsp_cmd = app.add_subcommand(
      "lsp",
      "Serve the Language Server Protocol over stdin/stdout for editors: every error, warning\n"
      "and lint of 'validate' as the config is typed, completion, hover, go to definition,\n"
      "references, rename, outline and quick fixes, on YAML and JSON configs and their includes.");
  lsp_cmd->footer(
      "An editor starts it; an open file's unsaved text wins over the file on disk.\n"
      "Plugins the configs name are found as for the other commands (--plugin-path,\n"
      "ARBITER_PLUGIN_PATH). Logs go to stderr. docs/editors.md shows each editor's setup.\n\n"
      "Examples:\n"
      "  arbiter lsp\n"
      "  arbiter --plugin-path ~/robot/plugins lsp\n"
      "  Neovim 0.7 and later, in a config's buffer (docs/editors.md has an init.lua set-up):\n"
      "    :lua local c = {name = 'arbiter', cmd = {'arbiter', 'lsp'}} if vim.lsp.start then "
      "vim.lsp.start(c) else vim.lsp.buf_attach_client(0, vim.lsp.start_client(c)) end\n\n"
      "Exit codes: 0 after 'shutdown' and 'exit', 1 when the input ends or 'exit' comes first.");

  try {
    app.parse(argc, argv);
    if (run_cmd->parsed() && !options.serve.empty() && !options.full_speed) {
      options.realtime = true;
    }
    // Checked here rather than by the option, so that `lsp` can start and show it in the editor.
    for (const auto& dir : options.plugin_path) {
      if (lsp_cmd->parsed()) continue;
      // The overload that reports, not throws: a path that cannot be looked at (no permission,
      // too long, a link loop) is a usage error as a missing one is.
      std::error_code looked;
      if (!std::filesystem::is_directory(dir, looked)) {
        throw CLI::ValidationError(
            "--plugin-path", looked && looked != std::errc::no_such_file_or_directory
                                 ? fmt::format("cannot look at '{}': {}", dir, looked.message())
                                 : "Directory does not exist: " + dir);
      }
    }
  } catch (const CLI::ParseError& error) {
    // --help and --version exit 0 through app.exit; every real parse error is a usage error.
    const int code = app.exit(error);
    return code == 0 ? kExitOk : kExitUsage;
  }
  try {
    auto logger = spdlog::stderr_color_mt("arbiter");
    logger->set_pattern("%^%l%$: %v");
    logger->set_level(spdlog::level::from_str(options.log_level));
    spdlog::set_default_logger(logger);
    // Past a file size limit (RLIMIT_FSIZE) a write then fails with EFBIG, which the command
    // reports, instead of killing the process: a robot's run goes on without its recording.
    std::signal(SIGXFSZ, SIG_IGN);
    options.diagnostic_format = arbiter::FormatOptions::readable(use_color(options.color));
    if (validate_cmd->parsed()) return validate(options);
    if (run_cmd->parsed()) {
      options.steps_given = run_cmd->count("--steps") > 0;
      if (options.watch && !options.steps_given) options.steps = std::uint64_t{1} << 40;
      return run(options);
    }
    if (dump_cmd->parsed()) return dump(options);
    if (explain_cmd->parsed()) return explain(options);
    if (test_cmd->parsed()) return test(options);
    if (view_cmd->parsed()) return view(options);
    if (plot_cmd->parsed()) return plot(options);
    if (replay_cmd->parsed()) {
      auto registry = make_registry();
      arbiter::cli::ReplayOptions replay;
      replay.recording = options.recording;
      replay.config = options.config;
      replay.trace = options.trace_path;
      replay.record = options.record_path;
      replay.record_flush = options.record_flush;
      replay.steps = replay_cmd->count("--steps") > 0 ? options.steps : 0;
      replay.load = load_options_of(options);
      replay.version = kVersion;
      return arbiter::cli::replay(replay, registry, std::cout, std::cerr);
    }
    if (diff_cmd->parsed()) {
      return arbiter::cli::diff(options.diff_a, options.diff_b, options.tolerance, options.format,
                                std::cout, std::cerr);
    }
    if (plugins_cmd->parsed()) return plugins(options);
    if (schema_cmd->parsed()) return schema(options);
    if (lsp_cmd->parsed()) return lsp(options);
  } catch (const std::exception& error) {
    std::cerr << fmt::format("arbiter: {}\n", arbiter::printable(error.what()));
    return kExitInvalid;
  }
  return kExitUsage;
}

// The `arbiter` command: its subcommands and options, declared with CLI11; each subcommand's
// work is a function in commands/ (commands/command.hpp).

#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>

#include "arbiter/lint.hpp"
#include "commands/command.hpp"
#include "commands/new_project.hpp"
#include "commands/output_file.hpp"
#include "commands/record.hpp"
#include "server/foxglove.hpp"
#include "server/serve.hpp"

namespace {

// `--foxglove-scene-rate`'s largest: far beyond any screen, and the server's thread polls the
// steps 200 times a second.
constexpr double kMaxSceneRate = 1000.0;

using namespace arbiter::cli;

/// CLI11 check of `--serve [ADDR:]PORT`.
std::string check_serve_address(const std::string& text) {
  std::string error;
  ServeAddress::parse(text, error);
  return error;
}

/// Whether the whole of `text` is a number from `low` to `high` (NaN never is): what the checks
/// of the numeric options below accept.
bool number_within(const std::string& text, double low, double high) {
  char* end = nullptr;
  const double number = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0' && number >= low && number <= high;
}

/// CLI11 check of `--record-flush SECONDS`.
std::string check_record_flush(const std::string& text) {
  if (number_within(text, 0.0, arbiter::Recorder::kMaxFlushInterval)) return {};
  return fmt::format("must be a number of seconds from 0 to {:g}, found '{}'",
                     arbiter::Recorder::kMaxFlushInterval, text);
}

/// CLI11 check of `--foxglove-scene-rate HZ`.
std::string check_scene_rate(const std::string& text) {
  if (number_within(text, 0.0, kMaxSceneRate)) return {};
  return fmt::format(
      "must be a number of pictures a second from 0 (every step's) to {:g}, found '{}'",
      kMaxSceneRate, arbiter::printable(text));
}

/// CLI11 check of `--tolerance X` (test, diff): CLI11's NonNegativeNumber lets `nan` through, which
/// no difference is within, and names the largest double in full.
std::string check_tolerance(const std::string& text) {
  if (number_within(text, 0.0, std::numeric_limits<double>::max())) return {};
  return fmt::format("must be a finite number from 0, found '{}'", arbiter::printable(text));
}

/// CLI11 check of an option that names a file: empty, it is how "not given" is held, and the
/// file would be left out without a word.
std::string refuse_empty_file(const std::string& text) {
  return text.empty() ? "an empty name names no file: give a file, or leave the option out"
                      : std::string();
}

/// CLI11 check of a step number (`--step`, `--from`): CLI11's PositiveNumber refuses 0 as "not in
/// range 0 to" the largest double, and a number past 2^64 was taken as 2^64 - 1.
std::function<std::string(const std::string&)> step_check(std::uint64_t lowest) {
  return [lowest](const std::string& text) {
    errno = 0;
    char* end = nullptr;
    const unsigned long long step = std::strtoull(text.c_str(), &end, 10);
    const bool digits = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
      return std::isdigit(static_cast<unsigned char>(c)) != 0;
    });
    if (digits && errno != ERANGE && *end == '\0' && step >= lowest) return std::string();
    if (digits && errno == ERANGE) {
      return fmt::format("must be a step number, at most {}, found '{}'",
                         std::numeric_limits<std::uint64_t>::max(), text);
    }
    return fmt::format("must be a step number, {} or more, found '{}'", lowest,
                       arbiter::printable(text));
  };
}

/// `--serve-token TOKEN`, also ARBITER_SERVE_TOKEN; checked, as it travels in URLs and cookies.
CLI::Option* add_serve_token_option(CLI::App& command, Options& options, const std::string& help) {
  return command.add_option("--serve-token", options.serve_token, help)
      ->envname("ARBITER_SERVE_TOKEN")
      ->type_name("TOKEN")
      ->check(token_error, "");
}

/// The innermost command given (`arbiter new plugin` is two deep), and its words.
std::pair<const CLI::App*, std::string> command_given(const CLI::App& app) {
  const CLI::App* command = &app;
  std::string words = "arbiter";
  for (auto given = app.get_subcommands(); !given.empty(); given = command->get_subcommands()) {
    command = given.back();
    words += " " + command->get_name();
  }
  return {command, words};
}

/// A usage error, said by the command given, with the help that command has.
int report_usage(const CLI::App& app, std::string_view what) {
  const auto words = command_given(app).second;
  std::cerr << fmt::format("{}: {}\nRun '{} --help' for more information.\n", words, what, words);
  return kExitUsage;
}

// Words the command line has left over, in the order they were written (CLI11 lists them
// backwards), each option among them with the closest option the command takes.
int report_extras(const CLI::App& app) {
  const auto [command, prefix] = command_given(app);
  std::vector<std::string> names;
  std::vector<std::string> commands;
  for (const CLI::App* sub : command->get_subcommands({})) commands.push_back(sub->get_name());
  for (const CLI::App* scope : {&app, command}) {
    for (const CLI::Option* option : scope->get_options()) {
      for (const auto& name : option->get_lnames()) names.push_back("--" + name);
      for (const auto& name : option->get_snames()) names.push_back("-" + name);
    }
  }
  const std::vector<std::string> words = app.remaining(true);
  std::string listed;
  for (const auto& word : words) listed += (listed.empty() ? "" : " ") + arbiter::printable(word);
  std::cerr << fmt::format("{}: {} not expected: {}\n", prefix,
                           words.size() > 1 ? "these arguments were" : "this argument was", listed);
  for (const auto& word : words) {
    if (word.empty() || (word[0] != '-' && (commands.empty() || &word != &words.front()))) {
      continue;
    }
    const std::string name = word.substr(0, word.find('='));
    if (auto best = arbiter::closest(name, word[0] == '-' ? names : commands)) {
      std::cerr << fmt::format("  note: '{}': did you mean '{}'?\n", arbiter::printable(name),
                               *best);
    }
  }
  std::cerr << fmt::format("Run '{} --help' for more information.\n", prefix);
  return kExitUsage;
}

/// `--load NAME` and `--builtin`, which classes `plugins` and `schema` take (`verb` them: "list",
/// "include"); exclusive, as together one of them would be dropped without a word.
void add_class_choice_options(CLI::App& command, Options& options, const std::string& verb) {
  auto* load = command
                   .add_option("--load", options.load,
                               verb +
                                   " the built-ins and this plugin (repeatable) instead of "
                                   "every plugin on the path")
                   ->type_name("NAME");
  command.add_flag("--builtin", options.builtin_only, verb + " the built-in classes only")
      ->excludes(load);
}

/// `--record FILE` and `--record-flush SECONDS` (which needs it), as run and replay share them.
void add_record_options(CLI::App& command, Options& options, const std::string& record_help,
                        const std::string& record_type, const std::string& flush_help) {
  command.add_option("--record", options.record_path, record_help)
      ->type_name(record_type)
      ->check(refuse_empty_file, "");
  command.add_option("--record-flush", options.record_flush, flush_help)
      ->check(check_record_flush, "")
      ->type_name("SECONDS")
      ->capture_default_str()
      ->needs("--record");
}

/// `--foxglove-scene-rate HZ` (which needs --foxglove), as run and replay share it.
void add_scene_rate_option(CLI::App& command, Options& options) {
  command
      .add_option("--foxglove-scene-rate", options.foxglove_scene_rate,
                  "with --foxglove: send the picture on /arbiter/scene at most HZ times a second "
                  "(the next step's after each period; a viewer draws no faster than its screen), "
                  "or every step's with 0 or when the config's rate_hz is no faster; the other "
                  "channels carry every step")
      ->check(check_scene_rate, "")
      ->type_name("HZ")
      ->capture_default_str()
      ->needs("--foxglove");
}

// What every option that reads a run takes.
constexpr const char* kTraceHelp =
    "the run: a JSON-lines trace (arbiter run --trace) or a recording (.mcap, arbiter run "
    "--record)";

// `--steps 0` would run nothing and print an empty summary: refused with what to give instead.
std::string refuse_zero_steps(const std::string& text) {
  return text == "0" ? "0 steps would run nothing: give 1 or more, or leave --steps out to run "
                       "the config's 'steps:'"
                     : std::string();
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

// "Examples" and where the files they name are: installed beside the binary
// (PREFIX/share/arbiter), else in the source tree the binary was built from.
std::string examples_heading() {
  std::error_code failed;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", failed);
  const auto installed = exe.parent_path().parent_path() / ARBITER_DATADIR / "arbiter";
  if (!failed && std::filesystem::is_directory(installed / "configs", failed)) {
    return fmt::format("Examples (run them in {}, where their files are installed):\n",
                       installed.string());
  }
  return "Examples (run them at the top of the source tree, where their files are):\n";
}

}  // namespace

int main(int argc, char** argv) {
  using namespace arbiter::cli;
  const std::string examples = examples_heading();
  CLI::App app{
      "arbiter: a data-driven behaviour engine for robots.\n"
      "Behaviour layers, inhibitions and state controllers are declared in YAML or JSON configs,\n"
      "validated with file:line:column diagnostics, and bound to C++ classes.\n",
      "arbiter"};
  app.footer(fmt::format(
      "{}"
      "  arbiter validate configs/paper/walk_and_kick.yaml\n"
      "  arbiter run configs/paper/walk_and_kick.yaml --steps 20 --trace out.jsonl\n"
      "  arbiter explain configs/paper/walk_and_kick.yaml --trace out.jsonl --step 8 "
      "search_for_ball\n"
      "  arbiter dump configs/paper/walk_and_kick.yaml --format dot | dot -Tsvg -o graph.svg\n"
      "  arbiter test tests/scenarios/soccer/\n"
      "  arbiter plugins\n"
      "  arbiter schema > arbiter.schema.json\n"
      "  arbiter new plugin rover          # a plugin project of your own (docs/tutorial.md)\n\n"
      "{}\n"
      "Run 'arbiter COMMAND --help' for a command's options and examples.",
      examples, kExitCodes));
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
                 "a directory to look for plugins in, one per option: '--plugin-path A "
                 "--plugin-path B'; searched before ARBITER_PLUGIN_PATH (colon-separated) and "
                 "the plugins that come with arbiter")
      ->type_name("DIR")
      ->allow_extra_args(false);
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
      examples +
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
                   "number of steps to run; default: the config's 'steps:' (100 when it has "
                   "none; with --watch, until Ctrl-C)")
      ->check(refuse_zero_steps)
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40).description(""))
      ->type_name("N");
  run_cmd
      ->add_option("--trace", options.trace_path,
                   "write a JSON-lines trace of every step to this file")
      ->check(refuse_empty_file, "");
  run_cmd
      ->add_option("--inputs", options.inputs_path,
                   "feed the config's layers of the built-in class 'interface: inputs' from this "
                   "file: a list of {step: N, ACTUATOR: VALUE, ...}, each value held until a "
                   "later entry changes it (as a test's 'inputs:')")
      ->type_name("FILE")
      ->check(refuse_empty_file, "");
  add_record_options(*run_cmd, options,
                     "record the run as MCAP (steps, interface inputs, the config) for "
                     "'arbiter replay', 'arbiter diff' and Foxglove; flat out, the run waits "
                     "for the recording's writer; paced (--realtime, --serve), a step it has no "
                     "room for is dropped and the gap recorded. Messages are logged at the run's "
                     "own time: simulated (step / rate_hz) flat out, the wall clock paced. A "
                     "write that fails (a full disk) "
                     "is reported at once and ends the recording, not the run, which then exits 1",
                     "RUN.mcap",
                     "with --record: write the recording out to the disk at least every SECONDS, "
                     "so that a crash or a power cut loses at most about that much; 0: only every "
                     "256 KiB of steps (smaller files)");
  run_cmd->add_flag("--quiet,-q", options.quiet, "print nothing but errors");
  run_cmd->add_flag("--realtime", options.realtime,
                    "pace the steps at the config's rate_hz instead of running flat out");
  run_cmd->add_flag("--strict", options.strict, "treat config warnings as errors");
  run_cmd
      ->add_flag("--full-speed", options.full_speed,
                 "run flat out even with --serve or --foxglove (which otherwise pace at rate_hz), "
                 "e.g. for a soak test")
      ->excludes("--realtime");
  run_cmd
      ->add_flag("--watch", options.watch,
                 "reload the config whenever it or a file it includes changes, without "
                 "stopping the run (a broken edit is reported and the previous config runs "
                 "on); without --steps, runs until Ctrl-C")
      ->excludes("--inputs");
  run_cmd
      ->add_option("--serve", options.serve,
                   "serve the live view (a web page) on [ADDR:]PORT (ADDR defaults to 127.0.0.1, "
                   "PORT 0 picks a free one) and pace the steps at rate_hz; the server stays up "
                   "after the last step until Ctrl-C")
      ->check(check_serve_address, "")
      ->type_name("[ADDR:]PORT");
  run_cmd
      ->add_option("--foxglove", options.foxglove,
                   "serve the run live over the Foxglove WebSocket protocol on [ADDR:]PORT, for "
                   "Foxglove and Lichtblick (ADDR defaults to 127.0.0.1: the protocol has no "
                   "authentication, so give another address only on a trusted network; PORT 0 "
                   "picks a free one) and pace the steps at rate_hz; the server stays up after "
                   "the last step until Ctrl-C")
      ->check(check_serve_address, "")
      ->type_name("[ADDR:]PORT");
  add_scene_rate_option(*run_cmd, options);
  run_cmd
      ->add_flag("--paused", options.paused,
                 "with --serve: wait for the page's Step or Resume before the first step")
      ->needs("--serve");
  add_serve_token_option(*run_cmd, options,
                         "with --serve: the token the page and every request must carry "
                         "(default: a random one per run, printed in the URL; also "
                         "ARBITER_SERVE_TOKEN)");
  run_cmd
      ->add_flag("--serve-readonly", options.serve_readonly,
                 "with --serve: watch only; the page cannot pause, step or resume the run")
      ->needs("--serve");
  run_cmd
      ->add_flag("--edit", options.edit,
                 "with --serve: the page is the studio (docs/studio.md), and saving an edit "
                 "reloads the running graph as --watch does (a rejected edit leaves the previous "
                 "graph running, and the page says why); without --steps, runs until Ctrl-C")
      ->needs("--serve")
      ->excludes("--serve-readonly")
      ->excludes("--watch")
      ->excludes("--inputs");
  run_cmd
      ->add_option("--break", options.breaks,
                   "stop at the step after which CONDITION becomes true, repeatable "
                   "(docs/cli.md, \"Breakpoints\"): 'NAME activates', 'NAME deactivates', "
                   "'MACHINE/STATE starts', 'MACHINE/STATE ends', 'NAME[i] > X', 'NAME[i] < X', "
                   "'event ~ \"TEXT\"', 'step N', 'step >= N'. The step's record carries the "
                   "break as an event reported by 'break'. With --serve the run pauses there as "
                   "the page's Pause does (safe values out); without it the run ends with that "
                   "step")
      ->type_name("CONDITION");
  run_cmd
      ->add_option("--rt-priority", options.rt_priority,
                   "run the stepping thread under SCHED_FIFO at this priority (1-99) with memory "
                   "locked; needs CAP_SYS_NICE or RLIMIT_RTPRIO, and CAP_IPC_LOCK or "
                   "RLIMIT_MEMLOCK (exit 2 when not permitted)")
      ->check(CLI::Range(1, 99))
      ->type_name("N");
  run_cmd->footer(
      std::string(examples +
                  "  arbiter run configs/paper/walk_and_kick.yaml --steps 20\n"
                  "  arbiter run configs/paper/walk_and_kick.yaml --trace out.jsonl -q\n"
                  "  arbiter run configs/soccer/walk_and_kick.yaml --realtime   # Ctrl-C "
                  "stops cleanly\n"
                  "  arbiter run configs/soccer/walk_and_kick.yaml --steps 400 --break "
                  "'kick_ball activates' --trace kick.jsonl   # ends at the kick's step\n"
                  "  arbiter run configs/soccer/walk_and_kick.yaml --steps 300 --serve 8080   "
                  "# then open the printed URL (it carries the token)\n"
                  "  arbiter run configs/soccer/walk_and_kick.yaml --foxglove 8765   "
                  "# then connect Foxglove to ws://127.0.0.1:8765\n"
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
  dump_cmd->add_option("--layer", options.layer, "only this layer")
      ->check(
          [](const std::string& name) {
            // An empty name is how "no --layer" is held: it would dump every layer unasked.
            return name.empty() ? std::string(
                                      "a layer's name cannot be empty: leave --layer out "
                                      "to dump every layer")
                                : std::string();
          },
          "");
  dump_cmd
      ->add_option("--format", options.format,
                   "text (for people), dot (Graphviz: chaining inhibitions double, non-chaining "
                   "single, implicit dashed) or json (for tools)")
      ->check(CLI::IsMember({"text", "dot", "json"}))
      ->capture_default_str();
  dump_cmd->footer(
      std::string(examples +
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
      "tells which state ran, what was queued and the events; an actuator, who wrote it with\n"
      "which weight or which step's value it holds; a state, when and why it started and ended.");
  explain_cmd->add_option("FILE", options.file,
                          "the config the trace was written with; left out, a recording's own "
                          "(a recording given one says how it differs from its own)");
  explain_cmd->add_option("NAME", options.target,
                          "a behaviour ('name', or 'layer/name' when several layers have one of "
                          "that name), a state machine ('name' or 'state_machines/name'), an "
                          "actuator ('name' or 'actuators/name') or a state ('machine/state')");
  explain_cmd->add_option("--trace", options.trace_path, kTraceHelp)
      ->required()
      ->check(CLI::ExistingFile);
  explain_cmd->add_option("--step", options.step, "the step, counting from 1")
      ->required()
      ->check(step_check(1), "");
  explain_cmd->footer(
      std::string(examples +
                  "  arbiter run configs/paper/walk_and_kick.yaml --steps 20 --trace out.jsonl -q\n"
                  "  arbiter explain configs/paper/walk_and_kick.yaml --trace out.jsonl --step 8 "
                  "search_for_ball\n"
                  "  arbiter explain configs/paper/hierarchical.yaml --trace h.jsonl --step 6 "
                  "match\n"
                  "  arbiter explain configs/paper/walk_and_kick.yaml --trace out.jsonl --step 16 "
                  "kick   # held\n"
                  "  arbiter run configs/paper/goalie_plan.yaml --steps 50 --trace g.jsonl -q\n"
                  "  arbiter explain configs/paper/goalie_plan.yaml --trace g.jsonl --step 41 "
                  "goalie/wait_for_button\n"
                  "  arbiter explain --trace run.mcap --step 171 kick_ball   # the recorded "
                  "config\n\n"
                  "Exit codes: 0 ok, 1 invalid config or trace, 2 usage error (no such name "
                  "or step)."));

  auto* seek_cmd = app.add_subcommand(
      "seek",
      "Find, in a trace or recording, the first step after --from at which a breakpoint's\n"
      "condition becomes true (as 'arbiter run --break' would have stopped there), and print\n"
      "its number.");
  seek_cmd->add_option("FILE", options.file,
                       "the config the trace was written with; left out, a recording's own");
  seek_cmd->add_option("CONDITION", options.target,
                       "a condition as 'arbiter run --break' takes it (docs/cli.md, "
                       "\"Breakpoints\")");
  seek_cmd->add_option("--trace", options.trace_path, kTraceHelp)
      ->required()
      ->check(CLI::ExistingFile);
  seek_cmd
      ->add_option("--from", options.step,
                   "seek after this step (default 0: from the start); the steps before it "
                   "still count for a crossing")
      ->type_name("N")
      ->check(step_check(0), "");
  seek_cmd->footer(
      std::string(examples +
                  "  arbiter run configs/soccer/walk_and_kick.yaml --steps 400 --record run.mcap "
                  "-q\n"
                  "  arbiter seek --trace run.mcap 'kick_ball activates'              # 171\n"
                  "  arbiter seek --trace run.mcap 'kick_ball activates' --from 171   # 356\n"
                  "  arbiter seek configs/paper/goalie_plan.yaml --trace g.jsonl "
                  "'goalie/monitor_ball ends'\n\n"
                  "Exit codes: 0 found, 1 no such step (or an invalid config or trace), 2 usage "
                  "error (a condition that names nothing)."));

  auto* test_cmd = app.add_subcommand(
      "test",
      "Run scenario tests: a behaviour graph stepped without a robot, its interface layers or\n"
      "classes substituted and its inputs scripted, checked step by step against what the test\n"
      "expects (docs/testing.md). Prints one line per test and, for each failed expectation,\n"
      "file:line:col: error[expectation]: expected ..., got ... followed by the explanation of\n"
      "that behaviour or state machine at that step; every problem of an invalid test file in\n"
      "one run, as validate prints them. The counts come last.");
  test_cmd
      ->add_option("PATH", options.test.paths,
                   "test files (arbiter_test: 1), or directories: every *.test.yaml, "
                   "*.test.yml and *.test.json in them")
      ->required();
  test_cmd
      ->add_option("--tolerance", options.test.options.tolerance,
                   "how far a level or number may be from one expected as a single number")
      ->check(check_tolerance, "")
      ->capture_default_str();
  test_cmd
      ->add_option("--junit", options.test.junit,
                   "also write JUnit XML to FILE (one timed testcase per test file, its "
                   "classname the file; one failure per failed expectation), for CI systems")
      ->type_name("FILE")
      ->check(refuse_empty_file, "");
  test_cmd->footer(
      examples +
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
  view_cmd->add_option("FILE", options.file,
                       "the config the trace was written with; left out, a recording's own (a "
                       "recording given one says how it differs from its own)");
  view_cmd->add_option("--trace", options.trace_path, kTraceHelp)
      ->required()
      ->check(CLI::ExistingFile);
  view_cmd
      ->add_option("--serve", options.view_serve,
                   "serve on [ADDR:]PORT (ADDR defaults to 127.0.0.1, PORT 0 picks a free one)")
      ->check(check_serve_address, "")
      ->type_name("[ADDR:]PORT")
      ->capture_default_str();
  add_serve_token_option(*view_cmd, options,
                         "the token the page and every request must carry (default: a random "
                         "one, printed in the URL; also ARBITER_SERVE_TOKEN)");
  view_cmd
      ->add_option("--step", options.step,
                   "the step the page opens at, counting from 1 (default: the last step)")
      ->check(step_check(1), "");
  view_cmd
      ->add_option("--compare", options.compare_path,
                   "a second run (trace or recording) shown over the first: its row of each "
                   "behaviour, state machine and plotted value beside the first's, the steps "
                   "where they differ marked (as 'arbiter diff' finds them)")
      ->check(CLI::ExistingFile)
      ->type_name("B");
  view_cmd->footer(
      std::string(
          examples +
          "  arbiter run configs/soccer/walk_and_kick.yaml --steps 220 --trace run.jsonl -q\n"
          "  arbiter view configs/soccer/walk_and_kick.yaml --trace run.jsonl\n"
          "  arbiter view configs/soccer/walk_and_kick.yaml --trace run.jsonl --serve 0\n"
          "  arbiter view configs/soccer/walk_and_kick.yaml --trace run.jsonl --step 171\n"
          "  arbiter view --trace run.mcap                 # with the config it recorded\n"
          "  arbiter view --trace run.mcap --compare what_if.mcap\n\n"
          "Ctrl-C stops the server.\n") +
      kExitCodesTrace);

  auto* edit_cmd = app.add_subcommand(
      "edit",
      "Serve the studio, a browser editor of a config: its graph beside its text, edited by\n"
      "mouse or keyboard, every problem 'arbiter validate' finds shown as you edit, saved on\n"
      "request (docs/studio.md). Its edits: add, remove, rename and move a behaviour; add, flip\n"
      "and delete an inhibition; set a param; move a layer; add and remove an actuator; wire a\n"
      "port; add and remove a layer, a sensor, a state machine and a state; name a plugin; plan,\n"
      "remove and reorder a state machine's queue; or type in the text. A FILE that does not\n"
      "exist yet, or is empty, opens as a new config (arbiter: 1, its name from the file's,\n"
      "layers: []), written on the first Save.");
  edit_cmd
      ->add_option("FILE", options.file,
                   "the config to edit (a new one when it does not exist yet or is empty)")
      ->required()
      ->check(
          [](const std::string& file) -> std::string {
            // A new config may be named: its directory must exist for Save to write it there.
            namespace fs = std::filesystem;
            std::error_code error;
            if (fs::exists(file, error))
              return fs::is_directory(file, error) ? "'" + file + "' is a directory" : "";
            const fs::path dir = fs::path(file).parent_path();
            if (!dir.empty() && !fs::is_directory(dir, error))
              return "'" + file + "' does not exist, and neither does its directory '" +
                     dir.string() + "'";
            return "";
          },
          "FILE");
  edit_cmd
      ->add_option("--serve", options.edit_serve,
                   "serve on [ADDR:]PORT (ADDR defaults to 127.0.0.1, PORT 0 picks a free one)")
      ->check(check_serve_address, "")
      ->type_name("[ADDR:]PORT")
      ->capture_default_str();
  add_serve_token_option(*edit_cmd, options,
                         "the token the page and every request must carry (default: a random "
                         "one, printed in the URL; also ARBITER_SERVE_TOKEN)");
  edit_cmd->footer(
      examples +
      "  arbiter edit configs/soccer/walk_and_kick.yaml\n"
      "  arbiter edit robot.yaml --serve 0\n"
      "  arbiter edit new_robot.yaml                   # a new config, built in the studio\n"
      "  arbiter run robot.yaml --serve 8080 --edit   # edit the running graph\n\n"
      "Ctrl-C stops the server. Nothing is written until Save.\n");

  auto* plot_cmd = app.add_subcommand(
      "plot",
      "Draw a trace of 'arbiter run' as an SVG timeline: a row per behaviour with its activation,\n"
      "requested level and active steps, a row per state machine with its states and events.");
  plot_cmd->add_option("TRACE", options.trace_path, kTraceHelp)
      ->required()
      ->check(CLI::ExistingFile);
  plot_cmd->add_option("--output,-o", options.output, "the SVG file to write (default: stdout)")
      ->type_name("FILE")
      ->check(refuse_empty_file, "");
  plot_cmd->add_flag("--actuators", options.actuators, "add a row per actuator with its value");
  plot_cmd
      ->add_option("--compare", options.compare_path,
                   "a second run (trace or recording): its row of each behaviour under the "
                   "first's, the steps where they differ shaded")
      ->check(CLI::ExistingFile)
      ->type_name("B");
  plot_cmd->footer(
      std::string(
          examples +
          "  arbiter run configs/soccer/walk_and_kick.yaml --steps 220 --trace run.jsonl -q\n"
          "  arbiter plot run.jsonl -o timeline.svg\n"
          "  arbiter plot run.jsonl --actuators > timeline.svg\n"
          "  arbiter plot run.mcap --compare what_if.mcap -o compare.svg\n\n") +
      kExitCodesTrace);

  auto* replay_cmd = app.add_subcommand(
      "replay",
      "Run a recorded behaviour system again, as fast as it can, with every interface layer\n"
      "replaced by the recorded inputs. Without --config it checks that the run repeats itself\n"
      "(determinism); with --config it runs an edited graph on the same inputs (what if).\n"
      "The world is not simulated again: --record and --foxglove show the recorded picture\n"
      "(/arbiter/scene), a what-if's behaviours drawing beside it.");
  replay_cmd->add_option("RUN", options.recording, "the recording (arbiter run --record)")
      ->required()
      ->check(CLI::ExistingFile);
  replay_cmd->add_option("--config", options.config, "an edited config to run instead")
      ->check(CLI::ExistingPath)
      ->type_name("FILE");
  replay_cmd
      ->add_option("--trace", options.trace_path,
                   "write the replay's JSON-lines trace, put in place once the replay has run")
      ->type_name("OUT.jsonl")
      ->check(refuse_empty_file, "");
  add_record_options(*replay_cmd, options,
                     "record the replay as MCAP, put in place once the replay has run; a write "
                     "that fails is reported at once and ends the recording, not the replay, "
                     "which then exits 2",
                     "OUT.mcap",
                     "with --record: write the recording out to the disk at least every SECONDS; "
                     "0: only every 256 KiB of steps");
  replay_cmd
      ->add_option("--foxglove", options.foxglove,
                   "serve the replay live over the Foxglove WebSocket protocol on [ADDR:]PORT "
                   "(ADDR defaults to 127.0.0.1: the protocol has no authentication; PORT 0 picks "
                   "a free one), stepping at the recorded rate_hz; the server stays up after the "
                   "last step until Ctrl-C")
      ->check(check_serve_address, "")
      ->type_name("[ADDR:]PORT");
  add_scene_rate_option(*replay_cmd, options);
  replay_cmd
      ->add_option("--steps", options.steps,
                   "replay at most this many steps (the recording is read that far only)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40));
  replay_cmd->footer(
      examples +
      "  arbiter run configs/soccer/walk_and_kick.yaml --steps 220 --record run.mcap -q\n"
      "  arbiter replay run.mcap                      # repeats the run exactly?\n"
      "  arbiter replay run.mcap --config edited.yaml --record what_if.mcap\n"
      "  arbiter replay run.mcap --foxglove 8765      # watch it in Foxglove or Lichtblick\n"
      "  arbiter diff run.mcap what_if.mcap\n\n"
      "Exit codes: 0 ok (the replay matched, or the what-if ran), 1 the replay differs from the "
      "recording or a config or recording is invalid, 2 usage error or an output (--trace, "
      "--record) could not be written.");

  auto* diff_cmd = app.add_subcommand(
      "diff",
      "Compare two runs, traces (.jsonl) or recordings (.mcap) in any mix, step by step: where\n"
      "they first diverge, and per behaviour, actuator and state machine in how many steps. At\n"
      "the first divergence it says why: the values of A and B, whether the inputs differed\n"
      "first (recordings keep them), how the configs the recordings hold differ, and the\n"
      "explanation of what first differs in each run, against its own config.");
  diff_cmd->add_option("A", options.diff_a, "the first run")->required()->check(CLI::ExistingFile);
  diff_cmd->add_option("B", options.diff_b, "the second run")->required()->check(CLI::ExistingFile);
  diff_cmd->add_option("--tolerance", options.tolerance, "numbers this close are equal")
      ->check(check_tolerance, "")
      ->capture_default_str();
  diff_cmd->add_option("--format", options.format, "text or json")
      ->check(CLI::IsMember({"text", "json"}))
      ->capture_default_str();
  diff_cmd->footer(examples +
                   "  arbiter diff run.mcap what_if.mcap\n"
                   "  arbiter diff run.jsonl replay.jsonl --format json\n"
                   "  arbiter diff a.mcap b.mcap --tolerance 1e-6\n\n"
                   "Exit codes: 0 identical, 1 different, 2 usage error or unreadable input.");

  auto* plugins_cmd = app.add_subcommand(
      "plugins",
      "List the registered classes (the built-ins, and the plugins on the plugin path) with\n"
      "their kind, origin, params (type, default, range, description) and ports.");
  add_class_choice_options(*plugins_cmd, options, "list");
  plugins_cmd->add_option("--format", options.format, "text or json")
      ->check(CLI::IsMember({"text", "json"}))
      ->capture_default_str();
  plugins_cmd->footer(examples +
                      "  arbiter plugins\n"
                      "  arbiter plugins --load soccer --format json\n"
                      "  arbiter --plugin-path ~/robot/plugins plugins\n\n"
                      "Exit codes: 0 ok, 1 a plugin failed to load, 2 usage error.");

  auto* schema_cmd = app.add_subcommand(
      "schema",
      "Print the JSON Schema (draft-07) of the config format, extended with the registered\n"
      "classes: 'type:' completes in editors and each class's params and ports are checked.");
  add_class_choice_options(*schema_cmd, options, "include");
  schema_cmd->footer(
      examples +
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
      std::string("An editor starts it; an open file's unsaved text wins over the file on disk.\n"
                  "Plugins the configs name are found as for the other commands (--plugin-path,\n"
                  "ARBITER_PLUGIN_PATH). Logs go to stderr. docs/editors.md shows each editor's "
                  "setup.\n\n") +
      examples +
      "  arbiter lsp\n"
      "  arbiter --plugin-path ~/robot/plugins lsp\n"
      "  Neovim 0.7 and later, in a config's buffer (docs/editors.md has an init.lua set-up):\n"
      "    :lua local c = {name = 'arbiter', cmd = {'arbiter', 'lsp'}} if vim.lsp.start then "
      "vim.lsp.start(c) else vim.lsp.buf_attach_client(0, vim.lsp.start_client(c)) end\n\n"
      "Exit codes: 0 after 'shutdown' and 'exit', 1 when the input ends or 'exit' comes first.");

  auto* new_cmd = app.add_subcommand(
      "new", "Start a project from a template: 'arbiter new plugin NAME [DIR]'.");
  new_cmd->require_subcommand(1);
  new_cmd->footer(
      "Examples:\n"
      "  arbiter new plugin rover\n\n"
      "Run 'arbiter new plugin --help' for its arguments and what to run next.");
  auto* new_plugin_cmd = new_cmd->add_subcommand(
      "plugin",
      "Write a starter plugin project into DIR: a CMakeLists.txt that builds against the\n"
      "installed Arbiter SDK, a behaviour class (NAME.Stop), a state class (NAME.Drive), a config\n"
      "that uses them, a scenario test and a README. It builds and its test passes as written.");
  new_plugin_cmd
      ->add_option("NAME", options.new_name,
                   "the plugin's name: letters, digits and '_', starting with a letter; it names "
                   "the library (arbiter_NAME.so), the C++ namespace and the classes (NAME.Stop)")
      ->required();
  new_plugin_cmd->add_option(
      "DIR", options.new_dir,
      "where to write it (default: NAME); must not exist or be empty: nothing is overwritten");
  new_plugin_cmd->footer(
      "Examples:\n"
      "  arbiter new plugin rover\n"
      "  arbiter new plugin rover plugins/rover\n"
      "  cmake -S rover -B rover/build && cmake --build rover/build && ctest --test-dir "
      "rover/build\n"
      "  arbiter --plugin-path rover/build run rover/rover.yaml\n\n"
      "docs/tutorial.md builds a behaviour graph and then extends it with such a plugin.\n\n"
      "Exit codes: 0 written, 1 a file could not be written, 2 usage error (a bad NAME, a DIR "
      "that is not empty).");

  try {
    app.parse(argc, argv);
    if (run_cmd->parsed() && (!options.serve.empty() || !options.foxglove.empty()) &&
        !options.full_speed) {
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
  } catch (const CLI::ExtrasError&) {
    return report_extras(app);
  } catch (const CLI::CallForHelp& error) {
    // `arbiter xml --help`: help for a command there is not; the word is what needs telling.
    if (app.get_subcommands().empty() && !app.remaining(true).empty()) return report_extras(app);
    return app.exit(error) == 0 ? kExitOk : kExitUsage;
  } catch (const CLI::RequiredError& error) {
    // No command (or no kind of project after `new`), but words: a misspelt command, told as the
    // words it left over.
    const bool no_kind = new_cmd->parsed() && !new_plugin_cmd->parsed();
    if ((app.get_subcommands().empty() || no_kind) && !app.remaining(true).empty()) {
      return report_extras(app);
    }
    if (no_kind) return report_usage(app, "say what to start: 'arbiter new plugin NAME [DIR]'");
    return report_usage(app,
                        app.get_subcommands().empty() ? "say which command to run" : error.what());
  } catch (const CLI::ParseError& error) {
    // --help and --version exit 0 through app.exit; every real parse error is a usage error.
    if (error.get_exit_code() == 0) return app.exit(error) == 0 ? kExitOk : kExitUsage;
    return report_usage(app, error.what());
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
    if (validate_cmd->parsed()) return validate_command(options);
    if (run_cmd->parsed()) {
      options.steps_given = run_cmd->count("--steps") > 0;
      if ((options.watch || options.edit) && !options.steps_given) {
        options.steps = std::uint64_t{1} << 40;
      }
      return run_command(options);
    }
    if (dump_cmd->parsed()) return dump_command(options);
    if (explain_cmd->parsed()) return explain_command(options);
    if (seek_cmd->parsed()) return seek_command(options);
    if (test_cmd->parsed()) return test_command(options);
    if (view_cmd->parsed()) return view_command(options);
    if (edit_cmd->parsed()) return edit_command(options);
    if (plot_cmd->parsed()) return plot_command(options);
    if (replay_cmd->parsed()) {
      auto registry = make_registry();
      ReplayOptions replay;
      replay.recording = options.recording;
      replay.config = options.config;
      replay.trace = options.trace_path;
      replay.record = options.record_path;
      replay.record_flush = options.record_flush;
      replay.steps = replay_cmd->count("--steps") > 0 ? options.steps : 0;
      replay.load = load_options_of(options);
      replay.version = kVersion;
      // What the replay says, on standard error when standard output is taken by an output.
      std::ostream& out =
          writes_standard_output({replay.trace, replay.record}) ? std::cerr : std::cout;
      std::unique_ptr<FoxgloveServer> foxglove;
      if (!options.foxglove.empty()) {
        foxglove = open_foxglove(options, "replay", out, std::cerr);
        if (!foxglove) return kExitUsage;
        replay.observers.push_back(&foxglove->observer());
        replay.paced = true;
        replay.stop = &interrupted;
        install_interrupt_handlers();
      }
      const int code = arbiter::cli::replay(replay, registry, out, std::cerr);
      if (foxglove) foxglove_after_run(*foxglove, "replay", out, std::cerr);
      return code;
    }
    if (diff_cmd->parsed()) {
      return diff(options.diff_a, options.diff_b, options.tolerance, options.format,
                  load_options_of(options), std::cout, std::cerr);
    }
    if (plugins_cmd->parsed()) return plugins_command(options);
    if (schema_cmd->parsed()) return schema_command(options);
    if (lsp_cmd->parsed()) return lsp_command(options);
    if (new_plugin_cmd->parsed()) {
      return new_plugin(options.new_name, options.new_dir, std::cout, std::cerr);
    }
  } catch (const std::exception& error) {
    std::cerr << fmt::format("arbiter: {}\n", arbiter::printable(error.what()));
    return kExitInvalid;
  }
  return kExitUsage;
}

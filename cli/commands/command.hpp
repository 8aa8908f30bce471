#pragma once
// The `arbiter` command's subcommands: main.cpp declares their options with CLI11 and fills one
// Options; each subcommand is a function of it that returns the exit code.

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/breakpoint.hpp"
#include "arbiter/diagnostics.hpp"
#include "arbiter/load.hpp"
#include "arbiter/program.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/registry.hpp"
#include "commands/test_command.hpp"
#include "server/foxglove.hpp"

namespace arbiter::cli {

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
  std::string inputs_path;  ///< `run --inputs`
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
  std::string foxglove;                       ///< `run --foxglove`, `replay --foxglove`
  std::string view_serve = "127.0.0.1:8080";  ///< `view --serve`
  std::string edit_serve = "127.0.0.1:8080";  ///< `edit --serve`
  bool edit = false;                          ///< `run --serve --edit`
  std::string output;                         ///< `plot -o`
  /// `--foxglove-scene-rate`: pictures a second on `/arbiter/scene`
  double foxglove_scene_rate = FoxgloveServer::kSceneRate;
  bool actuators = false;
  bool paused = false;              ///< `run --paused`
  std::vector<std::string> breaks;  ///< `run --break`
  TestCommand test;                 ///< `test`
  int rt_priority = 0;              ///< `run --rt-priority`; 0: normal scheduling
  std::string serve_token;  ///< `run --serve-token` (or ARBITER_SERVE_TOKEN); empty: a random one
  bool serve_readonly = false;
  std::string record_path;                                  ///< `run --record`, `replay --record`
  double record_flush = arbiter::Recorder::kFlushInterval;  ///< `--record-flush` (seconds)
  std::string config;                                       ///< `replay --config`
  std::string recording;                                    ///< `replay RUN.mcap`
  std::string diff_a;                                       ///< `diff A B`
  std::string diff_b;
  double tolerance = 1e-9;     ///< `diff --tolerance`
  std::string compare_path;    ///< `plot --compare`, `view --compare`
  std::string color = "auto";  ///< `--color`
  std::string new_name;        ///< `new plugin NAME [DIR]`
  std::string new_dir;
  arbiter::FormatOptions diagnostic_format = arbiter::FormatOptions::readable();
};

constexpr const char* kVersion = "0.1.0";

/// `--color auto` colours diagnostics when `stream` is a terminal (and NO_COLOR is not set).
bool use_color(const std::string& choice, std::FILE* stream = stderr);
/// The registry every command starts from: the built-in classes (plugins add theirs at load).
Registry make_registry();
/// Diagnostics as `--format` asks: text on stderr, or JSON on stdout.
void print_diagnostics(const Diagnostics& diagnostics, const Options& options);
LoadOptions load_options_of(const Options& options);
/// The program of `path`, or nothing; its diagnostics, if any, printed on stderr either way, and
/// kept in `kept` if given.
std::optional<Program> load_or_report(const std::string& path, Registry& registry,
                                      const Options& options, Diagnostics* kept = nullptr);

/// Set by SIGINT and SIGTERM once install_interrupt_handlers() ran: a run or a server stops
/// between two steps or requests, so that what it writes is complete.
extern std::atomic<bool> interrupted;
void install_interrupt_handlers();

/// The Foxglove WebSocket server of `--foxglove [ADDR:]PORT` (server/foxglove.hpp), sending the
/// picture at `--foxglove-scene-rate`, warning on `err` when it can be reached from other
/// machines; nullptr when it cannot serve (said on `err`, as `command`).
std::unique_ptr<FoxgloveServer> open_foxglove(const Options& options, std::string_view command,
                                              std::ostream& out, std::ostream& err);
/// After a run or replay with `--foxglove`: says what was dropped, then serves on until
/// interrupted, so that a viewer keeps its connection and what it received.
void foxglove_after_run(FoxgloveServer& server, std::string_view command, std::ostream& out,
                        std::ostream& err);

int validate_command(const Options& options);
int dump_command(const Options& options);
int plugins_command(const Options& options);
int schema_command(const Options& options);
int explain_command(const Options& options);
int lsp_command(const Options& options);
int test_command(Options& options);
int run_command(const Options& options);
int seek_command(const Options& options);

/// The conditions of `option` (`--break`) set on `program`'s run: false, each error printed on
/// `err` located in its argument, when one cannot be set.
bool set_breakpoints(const std::vector<std::string>& conditions, const Program& program,
                     std::string_view option, const FormatOptions& format, std::ostream& err,
                     std::vector<Breakpoint>& out);
int view_command(const Options& options);
int edit_command(const Options& options);
int plot_command(const Options& options);

}  // namespace arbiter::cli

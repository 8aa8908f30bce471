#pragma once
// `arbiter run --record`, `arbiter replay` and `arbiter diff` (docs/replay.md).

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/document.hpp"
#include "arbiter/load.hpp"
#include "arbiter/program.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/registry.hpp"

namespace arbiter::cli {

/// The files `config` reads (itself and its includes) with their text, and its plugins, for a
/// recording. `registry` has the config's plugins loaded.
RecordingInfo recording_info(const std::string& config, const Registry& registry,
                             const LoadOptions& options, const std::string& version);

struct ReplayOptions {
  std::string recording;
  std::string config;  ///< empty: the recorded config
  std::string trace;
  std::string record;
  double record_flush = Recorder::kFlushInterval;  ///< Recorder::set_flush_interval()
  std::uint64_t steps = 0;                         ///< 0: all recorded
  LoadOptions load;
  std::string version;
  /// Observers of the replay besides its own (`--foxglove`'s server).
  std::vector<Observer*> observers;
  /// Steps at the recorded config's rate_hz, not flat out, and stops between two steps when
  /// `stop` (if any) becomes true: for a viewer that watches the replay.
  bool paced = false;
  const std::atomic<bool>* stop = nullptr;
};

/// Runs the recorded system again on its recorded inputs; returns the exit code.
int replay(const ReplayOptions& options, Registry& registry, std::ostream& out, std::ostream& err);

/// Warns of what a trace or recording read to its end lacks there (TraceSource::truncated() and
/// damaged()): every tool that reads one says it the same way.
void note_end(const std::string& path, const std::string& truncated, const std::string& damaged,
              std::ostream& err);

/// The end-of-run line of `command` (run, replay) for a recording to `path` that failed with
/// `error`, ending in a newline: both commands say it the same way.
std::string recording_failed(std::string_view command, const std::string& path,
                             const std::string& error);

/// Whether a run can be read more than once: a file, not a pipe (`<(...)`, /dev/stdin), which
/// only the command's own reading may read.
bool readable_again(const std::string& path);

/// The config a recording holds (its `arbiter.config` metadata), loaded: what explain, view and
/// diff read a recording against. The files are read from the recording, under the names the run
/// read them by, so that locations name them as the run did.
struct RecordedProgram {
  /// The recorded files, in front of the disk; the program was loaded through them.
  std::shared_ptr<Overlay> files;
  std::string config;  ///< the recorded config's path (its first file)
  std::optional<Program> program;
  Diagnostics diagnostics;  ///< of the load: why there is no program
  std::string error;        ///< set when the recording cannot be read or holds no config
};
RecordedProgram load_recorded_program(const std::string& recording, Registry& registry,
                                      LoadOptions options);

/// The program a run (trace or recording) is read against by `command` (explain, view): `config`
/// when given, checked against the config a recording holds; else the one the recording holds.
/// nullopt when the run cannot be read (exit 2), when there is no config, or the given config is
/// not the recording's: said on `err`, with the exit code in `exit`.
std::optional<Program> program_of_run(const std::string& config, const std::string& run,
                                      Registry& registry, const LoadOptions& options,
                                      std::string_view command, const FormatOptions& format,
                                      std::ostream& err, int& exit);

/// Compares two traces or recordings; `format` is "text" or "json". At the first divergence it
/// also says why, from the configs the recordings hold (loaded with `load`). Returns the exit
/// code.
int diff(const std::string& a, const std::string& b, double tolerance, const std::string& format,
         const LoadOptions& load, std::ostream& out, std::ostream& err);

}  // namespace arbiter::cli

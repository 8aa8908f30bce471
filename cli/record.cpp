#include "record.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "arbiter/document.hpp"
#include "arbiter/model.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/recorded_inputs.hpp"
#include "arbiter/reload.hpp"
#include "arbiter/trace.hpp"
#include "arbiter/trace_diff.hpp"
#include "arbiter/trace_reader.hpp"

namespace arbiter::cli {

namespace fs = std::filesystem;

namespace {

/// A replay runs as fast as it can: its steps are timed as the recorded run paced them, at the
/// config's rate, so that a recording of a replay reads like one of a run.
class SimulatedClock : public StepClock {
 public:
  double now() override { return t; }
  double t = 0.0;
};

std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// The recorded config's files, in memory under a directory that does not exist, with their
/// recorded relative layout, so that includes resolve as they did and nothing on disk is read in
/// their place. A recorded hot reload puts its files over them.
class RecordedConfig {
 public:
  explicit RecordedConfig(const RecordingInfo& info)
      : dir_(fs::temp_directory_path() / fmt::format("arbiter_replay_{}", ::getpid())) {
    set(info.files);
    root_ = path_of(info.files.front().first);
  }
  void set(const std::vector<std::pair<std::string, std::string>>& files) {
    for (const auto& [name, text] : files) overlay_.set(path_of(name), text);
  }
  const std::string& root() const { return root_; }
  const FileSource& source() const { return overlay_; }

 private:
  std::string path_of(const std::string& name) const {
    return (dir_ / fs::path(name).relative_path()).lexically_normal().string();
  }
  fs::path dir_;
  std::string root_;
  Overlay overlay_;
};

/// A recording cut off while written is read up to there: say so, once per file.
void note_truncated(const std::string& path, const std::string& truncated, std::ostream& err) {
  if (!truncated.empty()) err << fmt::format("{}: warning: {}\n", path, truncated);
}

}  // namespace

RecordingInfo recording_info(const std::string& config, const Registry& registry,
                             const LoadOptions& options, const std::string& version) {
  RecordingInfo info;
  info.version = version;
  Diagnostics ignored;  // the config has loaded already: this reads which files it used
  const auto document = read_document(config, ignored, options.limits);
  if (!document) return info;
  const Model model = build_model(*document, registry, ignored, options.limits);
  for (const auto& file : model.files) info.files.emplace_back(file, file_text(file));
  if (info.files.empty()) info.files.emplace_back(config, file_text(config));
  for (const auto& plugin : model.plugins) info.plugins.push_back(plugin.text);
  return info;
}

int replay(const ReplayOptions& options, Registry& registry, std::ostream& out, std::ostream& err) {
  Diagnostic error;
  const auto run = read_recorded_run(options.recording, error);
  if (!run) {
    err << format(error);
    return 1;
  }
  auto recorded = read_trace(options.recording, error);
  if (!recorded) {
    err << format(error);
    return 1;
  }
  note_truncated(options.recording, recorded->truncated, err);

  std::optional<RecordedConfig> written;
  std::string config = options.config;
  if (config.empty()) {
    written.emplace(run->info);
    config = written->root();
  }
  const RecordedInputs inputs(run->inputs);
  LoadOptions load = options.load;
  load.lint = nullptr;  // a replay reports whether the run repeats, not how the config reads
  if (written) load.source = &written->source();
  load.edit_model = [&](Model& model, Diagnostics& reported) {
    inputs.replace_interfaces(model, reported);
    return !reported.has_errors();
  };
  // The recorded config reloads as the run did, at the same steps; an edited one runs alone.
  Reloader reloader(registry, load);
  Diagnostics diagnostics;
  auto program = reloader.load(config, diagnostics);
  if (!diagnostics.empty()) err << format(diagnostics);
  if (!program) return 1;

  std::uint64_t steps = inputs.steps();
  std::size_t next_reload = 0;  // of run->reloads, applied when its step is done
  if (!run->reloads.empty() && !written) {
    err << fmt::format(
        "{}: note: the config was reloaded after step {}; with --config the recorded reloads "
        "are not applied\n",
        options.recording, run->reloads.front().after_step);
    next_reload = run->reloads.size();
  }
  for (std::size_t r = next_reload; r < run->reloads.size(); ++r) {
    if (!run->reloads[r].files.empty()) continue;
    // A recording that did not keep a reload's files: the replay ends where it cannot follow.
    steps = std::min(steps, run->reloads[r].after_step);
    err << fmt::format(
        "{}: warning: the config was reloaded after step {} and the recording does not hold "
        "its files; replay runs up to there\n",
        options.recording, run->reloads[r].after_step);
    break;
  }
  if (run->first_gap) {
    // The inputs of dropped steps are lost: the run cannot be repeated past them.
    steps = std::min(steps, *run->first_gap);
    err << fmt::format(
        "{}: warning: the recording dropped {} steps, the first after step {}; "
        "replay runs up to there\n",
        options.recording, run->dropped, *run->first_gap);
  }
  if (options.steps > 0) steps = std::min(steps, options.steps);

  Manager manager(std::move(*program), spdlog::default_logger());
  std::ostringstream trace_text;
  TraceWriter trace(trace_text);
  manager.add_observer(trace);
  std::unique_ptr<Recorder> recorder;
  if (!options.record.empty()) {
    recorder = std::make_unique<Recorder>(
        options.record,
        options.config.empty() ? run->info
                               : recording_info(config, registry, options.load, options.version),
        Recorder::kSlots, RingFull::kWaitForWriter);  // a replay keeps no pace: it loses nothing
    if (!recorder->ok()) {
      err << fmt::format("arbiter replay: cannot write '{}'\n", options.record);
      return 2;
    }
    recorder->set_flush_interval(options.record_flush);
    manager.add_observer(*recorder);
  }
  SimulatedClock clock;
  manager.set_clock(&clock);
  for (std::uint64_t i = 0; i < steps && !manager.stopped(); ++i) {
    clock.t = static_cast<double>(i) / manager.program().rate_hz;
    manager.step();
    // Staged now, swapped in at the start of the next step, as in the recorded run.
    while (next_reload < run->reloads.size() &&
           run->reloads[next_reload].after_step == manager.steps()) {
      written->set(run->reloads[next_reload].files);
      if (recorder) recorder->stage_files(run->reloads[next_reload].files);
      const auto reloaded = reloader.reload(manager);
      if (!reloaded.diagnostics.empty()) err << format(reloaded.diagnostics);
      if (!reloaded.staged) {
        err << fmt::format("{}: error: the config reloaded after step {} does not load\n",
                           options.recording, manager.steps());
        return 1;
      }
      ++next_reload;
    }
  }
  manager.finish();
  // A recording that failed was reported at once and ended there: the replay's verdict still
  // follows, and the exit status says that an output was not written.
  const auto outputs_written = [&](int code) {
    if (!recorder || !recorder->failed()) return code;
    err << fmt::format(
        "arbiter replay: writing recording '{}' failed: {}; it holds the steps written before\n",
        options.record, recorder->error());
    return 2;
  };
  if (!options.trace.empty()) {
    std::ofstream file(options.trace, std::ios::binary | std::ios::trunc);
    if (!(file << trace_text.str() << std::flush)) {
      err << fmt::format("arbiter replay: cannot write '{}'\n", options.trace);
      return 2;
    }
  }

  std::istringstream replayed_text(trace_text.str());
  const auto source = jsonl_trace_source(replayed_text, "replay");
  auto replayed = read_trace(*source, error);
  if (!replayed) {
    err << format(error);
    return outputs_written(1);
  }
  while (!recorded->steps.empty() && recorded->steps.back().step > steps) {
    recorded->steps.pop_back();
  }
  if (!options.config.empty()) {
    out << fmt::format("replayed {} steps of {} with {}\n", replayed->steps.size(),
                       options.recording, options.config);
    out << format_text(diff_traces(*recorded, *replayed), "the recording", "the replay");
    return outputs_written(0);
  }
  // Determinism: every field of every record but the timing, bit for bit.
  const auto diff = diff_traces(*recorded, *replayed, 0.0, true);
  if (diff.identical) {
    out << fmt::format("replayed {} steps of {}: identical to the recording\n",
                       replayed->steps.size(), options.recording);
    return outputs_written(0);
  }
  const auto& first = *diff.first_divergence;
  std::string what;
  for (const auto& item : first.what) what += (what.empty() ? "" : ", ") + item;
  err << fmt::format("{}: error: the replay differs from the recording at step {}: {}\n",
                     options.recording, first.step,
                     what.empty() ? "in a field of its record" : what);
  err << fmt::format(
      "{}: note: with the recorded config and inputs, a run repeats itself unless a behaviour, "
      "state or plugin is not deterministic (a wall clock, unseeded randomness: "
      "docs/plugins.md)\n",
      options.recording);
  return outputs_written(1);
}

int diff(const std::string& a, const std::string& b, double tolerance, const std::string& format,
         std::ostream& out, std::ostream& err) {
  Diagnostic error;
  const auto first = read_trace(a, error);
  if (!first) {
    err << arbiter::format(error);
    return 2;
  }
  const auto second = read_trace(b, error);
  if (!second) {
    err << arbiter::format(error);
    return 2;
  }
  note_truncated(a, first->truncated, err);
  note_truncated(b, second->truncated, err);
  const auto result = diff_traces(*first, *second, tolerance);
  out << (format == "json" ? format_json(result) : format_text(result, a, b));
  return result.identical ? 0 : 1;
}

}  // namespace arbiter::cli

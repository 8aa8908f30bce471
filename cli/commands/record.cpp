#include "commands/record.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "arbiter/document.hpp"
#include "arbiter/model.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/recorded_inputs.hpp"
#include "arbiter/reload.hpp"
#include "arbiter/trace.hpp"
#include "arbiter/trace_diff.hpp"
#include "arbiter/trace_reader.hpp"
#include "commands/output_file.hpp"

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
  RecordedConfig(const RecordingInfo& info, std::string recording)
      : dir_(fs::temp_directory_path() / fmt::format("arbiter_replay_{}", ::getpid())),
        recording_(std::move(recording)) {
    set(info.files);
    root_ = path_of(info.files.front().first);
  }
  void set(const std::vector<std::pair<std::string, std::string>>& files) {
    for (const auto& [name, text] : files) {
      overlay_.set(path_of(name), text);
      names_[path_of(name)] = name;
    }
  }
  const std::string& root() const { return root_; }
  const FileSource& source() const { return overlay_; }
  /// `diagnostics` as format() writes them, but with the recorded config's files named as the
  /// user knows them, the recording's and their recorded names ("run.mcap: robot.yaml:11:7:"),
  /// rather than by their paths here, under a directory that does not exist.
  std::string format(const Diagnostics& diagnostics) const {
    std::string out;
    for (Diagnostic item : diagnostics.items()) {
      const auto name = names_.find(fs::path(item.location.file).lexically_normal().string());
      if (name != names_.end()) {
        item.location.file = fmt::format("{}: {}", recording_, name->second);
      }
      // A message or a note may name a file too ("included from ...").
      for (const auto& [path, recorded] : names_) {
        replace_all(item.message, path, recorded);
        for (auto& note : item.notes) replace_all(note.text, path, recorded);
      }
      out += arbiter::format(item);
    }
    return out;
  }

 private:
  std::string path_of(const std::string& name) const {
    return (dir_ / fs::path(name).relative_path()).lexically_normal().string();
  }
  static void replace_all(std::string& text, const std::string& from, const std::string& to) {
    for (auto at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
      text.replace(at, from.size(), to);
    }
  }
  fs::path dir_;
  std::string recording_;
  std::string root_;
  Overlay overlay_;
  std::map<std::string, std::string> names_;  // path here -> recorded name
};

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
  if (!outputs_allowed("replay", {{options.trace, "--trace"}, {options.record, "--record"}},
                       {{options.recording, "the recording being replayed"},
                        {options.config, "the config replayed (--config)"}},
                       err)) {
    return 2;
  }
  // The recording is read as the replay goes, twice over (its inputs, and its steps to compare
  // with), never whole: a replay's memory does not grow with the recording.
  RecordingReader run(options.recording);
  if (run.error()) {
    err << format(*run.error());
    return 1;
  }
  const auto recorded_source = open_trace(options.recording);
  const bool exact = options.config.empty();
  // Determinism: every field of every record but the timing, bit for bit.
  TraceDiffer differ(exact ? 0.0 : 1e-9, exact);
  // The recorded run's step records, read as the replay needs them and compared with the
  // replay's: both runs are held a step at a time.
  StepAligner recorded(*recorded_source, differ);
  if (!recorded.start()) {
    err << format(*recorded_source->error());
    return 1;
  }

  std::optional<RecordedConfig> written;
  std::string config = options.config;
  if (config.empty()) {
    written.emplace(run.info(), options.recording);
    config = written->root();
  }
  // The first step's inputs are held before the config compiles, so that its interface layers
  // check them (and check_places() sees the recorded inputs' names).
  // A recording whose first steps were dropped holds a gap record before them: the first inputs
  // are read on to all the same, and what comes before them is kept for the step loop.
  RecordedInputs inputs;
  // The recorded picture is drawn for whoever shows or records it: a replay that only checks
  // that the run repeats itself does not parse it.
  const bool draws = !options.record.empty() || !options.observers.empty();
  static const std::string kNoScene;
  const auto scene_of = [&](const RecordingReader::Event& event) -> const std::string& {
    return draws ? event.scene : kNoScene;
  };
  // Diagnostics that may be located in the recorded config.
  const auto described = [&](const Diagnostics& diagnostics) {
    return written ? written->format(diagnostics) : format(diagnostics);
  };
  std::uint64_t loaded = 0;  // the step whose inputs are held
  Diagnostics diagnostics;
  std::deque<RecordingReader::Event> ahead;
  for (RecordingReader::Event first; run.next(first);) {
    const bool step_inputs = first.kind == RecordingReader::Event::Kind::kInputs;
    if (step_inputs) {
      if (!inputs.load(first.step, first.text, diagnostics, scene_of(first), {options.recording})) {
        err << format(diagnostics);
        return 1;
      }
      loaded = first.step;
    }
    ahead.push_back(std::move(first));
    if (step_inputs) break;
  }
  const auto next_event = [&](RecordingReader::Event& event) {
    if (ahead.empty()) return run.next(event);
    event = std::move(ahead.front());
    ahead.pop_front();
    return true;
  };
  RecordingReader::Event event;
  bool have_event = next_event(event);
  std::uint64_t last = options.steps > 0 ? options.steps : ~std::uint64_t{0};
  bool noted_reloads = false;
  LoadOptions load = options.load;
  load.lint = nullptr;  // a replay reports whether the run repeats, not how the config reads
  if (written) load.source = &written->source();
  load.edit_model = [&](Model& model, Diagnostics& reported) {
    inputs.replace_interfaces(model, reported);
    return !reported.has_errors();
  };
  // The recorded config reloads as the run did, at the same steps; an edited one runs alone.
  Reloader reloader(registry, load);
  auto program = reloader.load(config, diagnostics);
  if (!diagnostics.empty()) err << described(diagnostics);
  if (!program) return 1;

  Manager manager(std::move(*program), spdlog::default_logger());
  // The recorded picture holds what the recorded behaviours drew: drawn again alike, it would be
  // there twice. A what-if's behaviours draw beside it.
  manager.keep_input_pass_scene_only(exact);
  manager.add_observer(inputs);   // for the recorded reloads: only the running layers are fed
  std::ostringstream trace_text;  // what the trace writer wrote in the last step, then emptied
  TraceWriter trace(trace_text);
  manager.add_observer(trace);
  // Each output is put in place once the replay has run: a replay that fails part way leaves the
  // file as it was, as when it wrote its trace only at its end.
  std::optional<AtomicFile> trace_file;
  if (!options.trace.empty()) {
    trace_file.emplace(options.trace);
    if (!trace_file->open()) {
      err << fmt::format("arbiter replay: {}\n", trace_file->error());
      return 2;
    }
  }
  std::optional<AtomicFile> record_file;
  std::unique_ptr<Recorder> recorder;
  if (!options.record.empty()) {
    record_file.emplace(options.record);
    if (!record_file->open()) {
      err << fmt::format("arbiter replay: {}\n", record_file->error());
      return 2;
    }
    recorder = std::make_unique<Recorder>(
        record_file->duplicate(), options.record,
        options.config.empty() ? run.info()
                               : recording_info(config, registry, options.load, options.version),
        Recorder::kSlots, RingFull::kWaitForWriter);  // a replay keeps no pace: it loses nothing
    if (!recorder->ok()) {
      err << fmt::format("arbiter replay: cannot write '{}': {}\n", options.record,
                         recorder->error());
      return 2;
    }
    recorder->set_flush_interval(options.record_flush);
    manager.add_observer(*recorder);
  }
  for (Observer* observer : options.observers) manager.add_observer(*observer);
  SimulatedClock clock;
  manager.set_clock(&clock);
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(1.0 / manager.program().rate_hz));
  auto next_step = std::chrono::steady_clock::now();
  const auto written_out = [&] {
    const std::string text = trace_text.str();
    trace_text.str(std::string());
    if (trace_file) trace_file->write(text);
    return text;
  };
  while (!manager.stopped()) {
    const std::uint64_t step = manager.steps() + 1;
    // What the recording holds before this step's inputs: reloads, staged now to be swapped in
    // at the start of this step as in the recorded run, and dropped steps.
    while (have_event && step <= last && event.kind != RecordingReader::Event::Kind::kInputs) {
      if (event.kind == RecordingReader::Event::Kind::kGap) {
        // The inputs of dropped steps are lost: the run cannot be repeated past them.
        last = std::min(last, event.step);
        err << fmt::format(
            "{}: warning: {}\n", options.recording,
            replay_cut(ReplayCut::kDropped, event.step, event.dropped, "the replay"));
      } else if (!written) {
        if (!noted_reloads) {
          err << fmt::format(
              "{}: note: the config was reloaded after step {}; with --config the recorded "
              "reloads are not applied\n",
              options.recording, event.step);
        }
        noted_reloads = true;
      } else if (event.files.empty()) {
        // A recording that did not keep a reload's files: the replay ends where it cannot
        // follow.
        last = std::min(last, event.step);
        err << fmt::format("{}: warning: {}\n", options.recording,
                           replay_cut(ReplayCut::kReloadNotKept, event.step, 0, "the replay"));
      } else {
        written->set(event.files);
        if (recorder) recorder->stage_files(event.files);
        const auto reloaded = reloader.reload(manager);
        if (!reloaded.diagnostics.empty()) err << described(reloaded.diagnostics);
        if (!reloaded.staged) {
          err << fmt::format("{}: error: the config reloaded after step {} does not load\n",
                             options.recording, manager.steps());
          return 1;
        }
      }
      have_event = next_event(event);
    }
    if (step > last || !have_event) break;
    if (event.step < step) {
      // Inputs of a step replayed already (no recorder writes a step's twice): ignored.
      have_event = next_event(event);
      continue;
    }
    const bool now = event.step == step;  // else the recording holds no inputs for the step
    if (loaded != step) {
      Diagnostics bad;
      if (!inputs.load(step, now ? event.text : std::string(), bad,
                       now ? scene_of(event) : kNoScene, {options.recording})) {
        err << described(bad);
        return 1;
      }
      loaded = step;
    }
    if (now) have_event = next_event(event);
    if (options.paced) {
      std::this_thread::sleep_until(next_step);
      next_step = std::max(next_step + period, std::chrono::steady_clock::now());
      if (options.stop != nullptr && *options.stop) {
        last = manager.steps();  // the verdict is on the steps replayed
        break;
      }
    }
    clock.t = static_cast<double>(step - 1) / manager.program().rate_hz;
    manager.step();
    // The trace writer wrote the step's record last (after a reload's header, if any).
    std::string text = written_out();
    if (!text.empty() && text.back() == '\n') text.pop_back();
    const auto end = text.rfind('\n');
    recorded.compare(manager.steps(), end == std::string::npos ? text : text.substr(end + 1));
  }
  // A recording that failed was reported at once and ended there: the replay's verdict still
  // follows, and the exit status says that an output was not written.
  const auto outputs_written = [&](int code) {
    if (!recorder || !recorder->failed()) return code;
    err << recording_failed("replay", options.record, recorder->error());
    return 2;
  };
  if (run.error()) {
    err << format(*run.error());
    return outputs_written(1);
  }
  manager.finish();
  written_out();
  if (trace_file && !trace_file->commit()) {
    err << fmt::format("arbiter replay: {}\n", trace_file->error());
    return 2;
  }
  // A recording that failed part way is put in place too: it keeps what was written before.
  if (record_file && !record_file->commit()) {
    err << fmt::format("arbiter replay: {}\n", record_file->error());
    return 2;
  }
  const std::uint64_t steps = manager.steps();
  // The recorded steps up to where the replay was to end count against it when it ended early;
  // those the recording holds no inputs for (it was cut off between a step and its inputs)
  // cannot be replayed.
  const auto diff = recorded.finish(have_event ? last : steps);
  if (!have_event) recorded.drain();  // to its end, which may not be whole
  if (recorded_source->error()) {
    err << format(*recorded_source->error());
    return outputs_written(1);
  }
  if (!have_event) {
    note_end(options.recording, recorded_source->truncated(), recorded_source->damaged(), err);
  }
  if (!options.config.empty()) {
    out << fmt::format("replayed {} steps of {} with {}\n", steps, options.recording,
                       options.config);
    out << format_text(diff, "the recording", "the replay");
    return outputs_written(0);
  }
  if (diff.identical) {
    out << fmt::format("replayed {} steps of {}: identical to the recording\n", steps,
                       options.recording);
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

std::string recording_failed(std::string_view command, const std::string& path,
                             const std::string& error) {
  return fmt::format(
      "arbiter {}: writing recording '{}' failed: {}; it holds the steps written "
      "before\n",
      command, path, error);
}

void note_end(const std::string& path, const std::string& truncated, const std::string& damaged,
              std::ostream& err) {
  if (!truncated.empty()) err << fmt::format("{}: warning: {}\n", path, truncated);
  if (!damaged.empty()) err << fmt::format("{}: warning: {}\n", path, damaged);
}

bool readable_again(const std::string& path) {
  std::error_code error;
  return fs::is_regular_file(path, error);
}

RecordedProgram load_recorded_program(const std::string& recording, Registry& registry,
                                      LoadOptions options) {
  RecordedProgram out;
  RecordingReader reader(recording);
  if (reader.error()) {
    out.error = format(*reader.error());
    return out;
  }
  const auto& files = reader.info().files;
  if (files.empty()) {
    out.error = fmt::format("{}: error: the recording holds no config (no arbiter.config record)\n",
                            recording);
    return out;
  }
  // Unlike a replay's (RecordedConfig), these files keep their recorded names: nothing runs them,
  // and an explanation's locations must name the files the run read.
  out.files = std::make_shared<Overlay>();
  for (const auto& [name, text] : files) out.files->set(name, text);
  out.config = files.front().first;
  options.source = out.files.get();
  options.lint = nullptr;  // the run's config, read back: how it reads was said when it ran
  Loaded loaded = load_config(out.config, registry, options);
  out.diagnostics = std::move(loaded.diagnostics);
  out.program = std::move(loaded.program);
  return out;
}

std::optional<Program> program_of_run(const std::string& config, const std::string& run,
                                      Registry& registry, const LoadOptions& options,
                                      std::string_view command, const FormatOptions& format_options,
                                      std::ostream& err, int& exit) {
  exit = 1;
  if (!std::ifstream(run, std::ios::binary)) {
    err << fmt::format("arbiter {}: cannot read trace '{}'\n", command, run);
    exit = 2;
    return std::nullopt;
  }
  // A pipe is read once, by the command itself: its config is not read first.
  const bool again = readable_again(run);
  const bool recording = again && is_recording(run);
  if (config.empty() && !again) {
    err << fmt::format(
        "arbiter {}: {} is not a file (a pipe?): a recording's config is read from it before its "
        "steps, so it must be a file; or give the config ('arbiter {} CONFIG --trace {}')\n",
        command, run, command, run);
    exit = 2;
    return std::nullopt;
  }
  if (config.empty()) {
    if (!recording) {
      err << fmt::format(
          "arbiter {}: {} is a trace, which holds no config: give the config it was written "
          "with ('arbiter {} CONFIG --trace {}'); a recording (.mcap) holds its own\n",
          command, run, command, run);
      exit = 2;
      return std::nullopt;
    }
    auto recorded = load_recorded_program(run, registry, options);
    if (!recorded.error.empty()) {
      err << recorded.error;
      return std::nullopt;
    }
    if (!recorded.program) {
      err << fmt::format(
          "{}: error: the config the recording holds ({}) does not load here; give one with "
          "'arbiter {} CONFIG --trace {}'\n",
          run, recorded.config, command, run);
      err << format(recorded.diagnostics, format_options);
      return std::nullopt;
    }
    return std::move(recorded.program);
  }
  Diagnostics diagnostics;
  auto program = load(config, registry, diagnostics, options);
  if (!diagnostics.empty()) err << format(diagnostics, format_options);
  if (!program) return std::nullopt;
  if (!recording) return program;
  auto recorded = load_recorded_program(run, registry, options);
  // A recording that cannot be read is reported where its steps are read.
  if (!recorded.error.empty()) return program;
  if (!recorded.program) {
    const auto& items = recorded.diagnostics.items();
    const auto error = std::find_if(items.begin(), items.end(), [](const Diagnostic& item) {
      return item.severity == Severity::kError;
    });
    err << fmt::format(
        "{}: warning: the config the recording holds ({}) does not load here, so {} is not "
        "checked against it{}\n",
        run, recorded.config, config,
        error == items.end() ? std::string() : ": " + printable(error->message));
    return program;
  }
  const ProgramDiff changes = config_diff(*recorded.program, *program);
  if (changes.empty()) return program;
  Diagnostic mismatch;
  mismatch.location.file = run;
  mismatch.code = "config-mismatch";
  mismatch.message = fmt::format("the recording was made with another config than {}", config);
  mismatch.notes.emplace_back(
      fmt::format("the recording holds {}; from it to {}:", recorded.config, config));
  // One note per change: a note is a line.
  const std::string lines = arbiter::format(changes, "");
  for (std::size_t at = 0, end = 0; at < lines.size(); at = end + 1) {
    end = lines.find('\n', at);
    mismatch.notes.emplace_back("  " + lines.substr(at, end - at));
  }
  mismatch.notes.emplace_back(fmt::format(
      "leave the config out to read the run with the one it holds ('arbiter {} --trace {} ...'), "
      "or replay the run with this one ('arbiter replay {} --config {}')",
      command, run, run, config));
  err << format(mismatch, format_options);
  return std::nullopt;
}

}  // namespace arbiter::cli

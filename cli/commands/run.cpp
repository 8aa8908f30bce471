// `arbiter run`: a config stepped, paced or flat out, with its trace, recording, report, watcher
// live view and Foxglove server attached as observers of the manager.

#include <fmt/format.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "arbiter/manager.hpp"
#include "arbiter/reload.hpp"
#include "arbiter/scenario_run.hpp"
#include "arbiter/trace.hpp"
#include "commands/command.hpp"
#include "commands/output_file.hpp"
#include "commands/record.hpp"
#include "commands/run_report.hpp"
#include "commands/timing.hpp"
#include "commands/watch.hpp"
#include "server/foxglove.hpp"
#include "server/serve.hpp"
#include "server/studio.hpp"

namespace arbiter::cli {

int run_command(const Options& options) {
  if (!outputs_allowed("run", {{options.trace_path, "--trace"}, {options.record_path, "--record"}},
                       {{options.file, "the config being run"},
                        {options.inputs_path, "the inputs being fed (--inputs)"}},
                       std::cerr)) {
    return kExitUsage;
  }
  // The command's report and summary, on standard error when standard output is taken by the
  // trace or the recording.
  std::ostream& out =
      writes_standard_output({options.trace_path, options.record_path}) ? std::cerr : std::cout;
  auto registry = make_registry();
  arbiter::Reloader reloader(registry, load_options_of(options));  // --watch
  arbiter::Diagnostics load_diagnostics;  // its warnings go into the recording's log
  arbiter::InputFeed inputs;              // --inputs
  std::optional<arbiter::Program> program;
  if (options.watch || options.edit) {
    program = load_watched(reloader, options.file, std::cerr, options.diagnostic_format);
  } else if (!options.inputs_path.empty()) {
    arbiter::LoadOptions load = load_options_of(options);
    if (inputs.read(options.inputs_path, load_diagnostics, load.limits)) {
      load.edit_model = [&](arbiter::Model& model, arbiter::Diagnostics& reported) {
        return inputs.edit(model, registry, reported);
      };
      program = arbiter::load(options.file, registry, load_diagnostics, load);
    }
    if (!load_diagnostics.empty()) {
      std::cerr << arbiter::format(load_diagnostics, options.diagnostic_format);
    }
  } else {
    program = load_or_report(options.file, registry, options, &load_diagnostics);
  }
  if (!program) return kExitInvalid;
  arbiter::Breakpoints breakpoints;  // --break
  {
    std::vector<arbiter::Breakpoint> set;
    if (!set_breakpoints(options.breaks, *program, "--break", options.diagnostic_format, std::cerr,
                         set)) {
      return kExitUsage;
    }
    for (auto& breakpoint : set) breakpoints.add(std::move(breakpoint));
  }
  const double rate_hz = program->rate_hz;
  const std::uint64_t steps =
      options.steps_given || options.watch || program->steps == 0 ? options.steps : program->steps;

  OutputStream trace_file;
  std::ostream* trace_out = nullptr;
  if (is_standard_output(options.trace_path)) {
    // Through std::cout, which a watched run's status line is cleared from before it is written.
    trace_out = &std::cout;
  } else if (!options.trace_path.empty()) {
    if (!trace_file.open(options.trace_path)) {
      std::cerr << fmt::format("arbiter run: cannot write trace '{}': {}\n", options.trace_path,
                               trace_file.error());
      return kExitUsage;
    }
    trace_out = &trace_file;
  }
  arbiter::Manager manager(std::move(*program), spdlog::default_logger());
  // First among the observers: a reload re-resolves the breakpoints before the others see it.
  // With the page, always: it may set some.
  if (!breakpoints.empty() || !options.serve.empty()) {
    manager.set_check(&breakpoints);
    manager.add_observer(breakpoints);
  }
  arbiter::TraceWriter trace(trace_out != nullptr ? *trace_out : trace_file);
  if (trace_out != nullptr) manager.add_observer(trace);
  RunReport report(out, options.quiet);
  manager.add_observer(report);
  // In a terminal, a watched run keeps a status line on stderr: it shows an idle run is alive.
  std::optional<StatusLine> status;
  std::optional<StatusClearer> clear_out, clear_err;
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
    auto info = recording_info(options.file, registry, load_options_of(options), kVersion);
    info.paced = options.realtime;  // logged on the wall clock; flat out, on the simulated one
    info.diagnostics = load_diagnostics.items();
    const auto ring_full =
        options.realtime ? arbiter::RingFull::kDropStep : arbiter::RingFull::kWaitForWriter;
    const int fd = open_output(options.record_path);
    const int open_error = errno;
    recorder = std::make_unique<arbiter::Recorder>(fd, options.record_path, std::move(info),
                                                   arbiter::Recorder::kSlots, ring_full);
    if (!recorder->ok()) {
      std::cerr << fmt::format("arbiter run: cannot write recording '{}': {}\n",
                               options.record_path,
                               fd < 0 ? std::strerror(open_error) : recorder->error());
      return kExitUsage;
    }
    recorder->set_flush_interval(options.record_flush);
    manager.add_observer(*recorder);
    // A reload's files go into the recording, for replay to reload them too.
    reloader.set_on_staging(
        [&recorder](const arbiter::Reloader::FileTexts& files) { recorder->stage_files(files); });
  }
  // After the recorder: a reload staged by the watcher is recorded with its files.
  std::optional<Watcher> watcher;
  if (options.watch)
    watcher.emplace(reloader, manager, out, std::cerr, options.quiet, options.diagnostic_format,
                    status ? &*status : nullptr);
  std::optional<Studio> studio;  // --edit
  if (options.edit) {
    studio.emplace(options.file, registry, load_options_of(options));
    // On a server thread, one save at a time: the one reloading thread a Reloader allows.
    studio->set_after_save([&reloader, &manager, &out] {
      const ReloadResult result = reloader.reload(manager);
      nlohmann::ordered_json applied;
      applied["staged"] = result.staged;
      applied["messages"] = format(result.diagnostics);
      if (result.staged) {
        applied["summary"] =
            fmt::format("reload of {}: {} change{}, swapped in at the next step", reloader.path(),
                        result.diff.changes.size(), result.diff.changes.size() == 1 ? "" : "s");
        applied["diff"] = format(result.diff, "  ");
        applied["restarted"] = result.restarted;
      } else {
        applied["summary"] =
            fmt::format("reload of {} rejected: {} error(s); still running the previous config",
                        reloader.path(), result.diagnostics.error_count());
      }
      // As --watch reports it, in one piece: the run's own lines come from the stepping thread.
      const std::string summary = applied["summary"].get<std::string>() + "\n";
      if (result.staged) {
        out << summary + applied["diff"].get<std::string>() << std::flush;
      } else {
        std::cerr << applied["messages"].get<std::string>() + summary << std::flush;
      }
      return applied.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
    });
  }
  std::unique_ptr<LiveView> live;  // --serve
  if (!options.serve.empty()) {
    LiveAccess access;
    access.token = options.serve_token;
    access.readonly = options.serve_readonly;
    live = LiveView::open(options.serve, options.paused, access, out, std::cerr,
                          studio ? &*studio : nullptr);
    if (!live) return kExitUsage;
    manager.add_observer(*live);
    live->set_breakpoints(&breakpoints);
  }
  std::unique_ptr<FoxgloveServer> foxglove;  // --foxglove
  if (!options.foxglove.empty()) {
    foxglove = open_foxglove(options, "run", out, std::cerr);
    if (!foxglove) return kExitUsage;
    foxglove->set_paced(options.realtime);  // as the recording's log times (info.paced)
    manager.add_observer(foxglove->observer());
  }
  SteadyStepClock clock;
  manager.set_clock(&clock);
  RunTiming timing(1.0 / rate_hz);
  if (live) live->set_timing(&timing, options.realtime);
  if (options.rt_priority > 0) {
    std::string error;
    if (!enter_realtime(options.rt_priority, error)) {
      std::cerr << fmt::format("arbiter run: {}\n", error);
      return kExitUsage;
    }
  }

  // Ctrl-C ends the run between two steps, so the trace and the summary are still complete.
  install_interrupt_handlers();
  using Clock = std::chrono::steady_clock;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate_hz));
  const auto started = Clock::now();
  // Absolute deadlines: step i starts at started + i periods. A step that overruns never brings
  // a burst of catch-up steps: the next one waits for the next period boundary, and the periods
  // skipped are counted.
  auto next = started;
  const char* stopped_at_break = nullptr;
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
    if (const char* hit = manager.break_text()) {
      // With the page, the run pauses as its Pause does (the next loop makes it safe); without
      // it nobody could resume the run, so the run ends with this step.
      if (!live) {
        stopped_at_break = hit;
        break;
      }
      live->pause_at_break(manager.steps(), hit);
    }
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
    out << fmt::format("{}simulated {:.2f} s at {} Hz in {} of wall time{}\n",
                       interrupted ? "interrupted: " : "",
                       static_cast<double>(manager.steps()) / rate_hz, rate_hz, wall_time(wall),
                       options.realtime ? " (real time)" : "");
    out << timing.text(options.realtime) << std::flush;
  }
  if (stopped_at_break != nullptr && !options.quiet) {
    out << fmt::format(
               "stopped at the break after step {}: {} (without --serve nothing can resume "
               "the run)\n",
               manager.steps(), arbiter::printable(stopped_at_break))
        << std::flush;
  }
  if (live) live->serve_until(manager, interrupted);
  if (foxglove) foxglove_after_run(*foxglove, "run", out, std::cerr);
  if (trace_out != nullptr && !trace_out->flush()) {
    std::cerr << fmt::format("arbiter run: writing trace '{}' failed{}\n", options.trace_path,
                             trace_out == &trace_file ? ": " + trace_file.error() : "");
    return kExitInvalid;
  }
  if (recorder && recorder->failed()) {
    std::cerr << recording_failed("run", options.record_path, recorder->error());
    return kExitInvalid;
  }
  if (manager.stopped()) {
    std::cerr << fmt::format("arbiter run: stopped after step {}: {}\n", manager.steps(),
                             manager.stop_reason());
    return kExitInvalid;
  }
  return kExitOk;
}

}  // namespace arbiter::cli

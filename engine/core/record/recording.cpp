#include "arbiter/recording.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <system_error>

#include "arbiter/channels.hpp"
#include "arbiter/trace.hpp"
#include "core/record/mcap.hpp"
#include "core/record/step_record.hpp"
#include "core/run/code_placement.hpp"

namespace arbiter {

void append_inputs_record(const Manager& manager, std::string& out) {
  const detail::StepLayout layout(manager.program());
  detail::SnapshotBlocks storage;
  detail::append_inputs_record(layout, detail::capture_growing(manager, layout, storage), out);
}

// Who the recorder's own log messages are from.
constexpr const char* kRecorderName = "recorder";

struct Recorder::Output {
  explicit Output(int fd) : writer(fd) {}
  mcap::Writer writer;
  std::uint16_t header = 0;
  std::uint16_t step = 0;
  std::uint16_t inputs = 0;
  std::uint16_t log = 0;
  std::uint16_t scene = 0;
  std::uint64_t last_step = 0;
  std::uint64_t dropped = 0;
  LogClock clock;      // made when the run starts
  std::string record;  // reused between messages
  std::string inputs_record;
  std::string log_record;
  std::string scene_record;
  SceneUpdates scene_updates;
  std::string step_schema, inputs_schema;  // of the channels written to last
};

namespace {

/// `path` opened for writing, or -1 with the reason, taken before anything else can change
/// errno.
std::pair<int, int> open_for_writing(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  return {fd, fd < 0 ? errno : 0};
}

}  // namespace

Recorder::Recorder(const std::string& path, RecordingInfo info, std::size_t slots,
                   RingFull ring_full)
    : Recorder(path, open_for_writing(path), std::move(info), slots, ring_full) {}

Recorder::Recorder(int fd, std::string name, RecordingInfo info, std::size_t slots,
                   RingFull ring_full)
    : Recorder(std::move(name), {fd, fd < 0 ? EBADF : 0}, std::move(info), slots, ring_full) {}

Recorder::Recorder(std::string name, std::pair<int, int> opened, RecordingInfo info,
                   std::size_t slots, RingFull ring_full)
    : path_(std::move(name)),
      open_errno_(opened.second),
      fd_(opened.first),
      info_(std::move(info)),
      // At least one step may wait, or every step would drop and the end could never be
      // written.
      slots_(std::max<std::size_t>(slots, 1)),
      ring_(slots_, waiter_),
      ring_full_(ring_full),
      logger_(spdlog::default_logger()) {
  if (fd_ >= 0) out_ = std::make_unique<Output>(fd_);
}

Recorder::~Recorder() {
  if (started_ && !finished_) {
    ring_.end();
    wake_writer();
  }
  if (writer_.joinable()) writer_.join();
  if (fd_ >= 0) ::close(fd_);
}

bool Recorder::ok() const {
  return out_ != nullptr && !failed();  // out_ exists once the file is open
}

std::string Recorder::error() const {
  if (out_ == nullptr) return std::generic_category().message(open_errno_);
  return failed() ? error_ : std::string();
}

void Recorder::check_written(std::uint64_t step) {
  if (out_->writer.ok() || failed_.load(std::memory_order_relaxed)) return;
  fail(out_->writer.error(), step);
}

void Recorder::fail(int error, std::uint64_t step, const char* doing) {
  if (failing_.exchange(true)) return;
  error_ = std::generic_category().message(error);
  error_ += step == 0 ? std::string(" (at the start)") : fmt::format(" ({} step {})", doing, step);
  failed_.store(true, std::memory_order_release);
  if (logger_) {
    logger_->error(
        "recording '{}': a write failed: {}; the run goes on unrecorded, the file keeps what was "
        "written before",
        path_, error_);
  }
}

void Recorder::on_start(const Manager& manager) {
  if (!out_) return;
  wall_start_ns_ = wall_clock_ns();
  auto& writer = out_->writer;
  writer.header("arbiter", "arbiter " + info_.version);
  ring_.start(manager, wall_start_ns_, false);
  const auto& channels = ring_.channels();
  out_->header = add_channel(channels[kHeaderChannel]);
  out_->step = add_channel(channels[kStepChannel]);
  out_->inputs = add_channel(channels[kInputsChannel]);
  out_->log = add_channel(channels[kLogChannel]);
  out_->clock = LogClock(info_.paced, wall_start_ns_, ring_.rate_hz());
  out_->scene = add_channel(channels[kSceneChannel]);
  out_->step_schema = channels[kStepChannel].schema;
  out_->inputs_schema = channels[kInputsChannel].schema;
  std::vector<std::pair<std::string, std::string>> config;
  config.emplace_back("name", manager.program().name);
  config.emplace_back("rate_hz", fmt::format("{}", manager.program().rate_hz));
  config.emplace_back("version", info_.version);
  std::string plugins;
  for (const auto& plugin : info_.plugins) plugins += (plugins.empty() ? "" : "\n") + plugin;
  config.emplace_back("plugins", plugins);
  for (const auto& [file, text] : info_.files) config.emplace_back("file:" + file, text);
  writer.metadata("arbiter.config", config);
  writer.message(out_->header, wall_start_ns_, ring_.header());
  for (const auto& diagnostic : info_.diagnostics) {
    // As `arbiter validate` words it, without the location, which has fields of its own.
    std::string text =
        fmt::format("{}[{}]: {}", diagnostic.severity == Severity::kError ? "error" : "warning",
                    diagnostic.code, diagnostic.message);
    for (const auto& note : diagnostic.notes) text += "\nnote: " + note.text;
    out_->log_record.clear();
    append_log_message(
        wall_start_ns_,
        diagnostic.severity == Severity::kError ? LogLevel::kError : LogLevel::kWarning, "config",
        text, diagnostic.location.file,
        static_cast<std::uint32_t>(std::max(diagnostic.location.line, 0)), out_->log_record);
    writer.message(out_->log, wall_start_ns_, out_->log_record);
  }
  check_written(0);
  set_writer_period(manager.program());
  started_ = true;
  writer_ = std::thread([this] { write_loop(); });
}

std::uint16_t Recorder::add_channel(const Channel& channel) {
  auto& writer = out_->writer;
  return writer.channel(writer.schema(channel.schema_name, kSchemaEncoding, channel.schema),
                        channel.topic, kMessageEncoding);
}

std::uint64_t Recorder::wall_time(bool timed, double step_time) const {
  return wall_start_ns_ + (timed ? static_cast<std::uint64_t>(step_time * 1e9) : 0);
}

std::uint64_t Recorder::log_time(std::uint64_t step, std::uint64_t wall_time) const {
  return out_->clock.time(step, wall_time);
}

void Recorder::set_writer_period(const Program& program) {
  // The writer wakes a few times in the while the ring takes to fill at the config's rate: a
  // robot's CPU has better to do than wake it every millisecond, and its bursts of formatting
  // and compressing then seldom meet a step. Flat out, where the stepping thread waits for it,
  // it wakes every millisecond.
  constexpr double kFewest = 1e-3, kMost = 50e-3;  // seconds
  const double fill = static_cast<double>(slots_) / program.rate_hz;
  const double period =
      ring_full_ == RingFull::kWaitForWriter ? kFewest : std::clamp(fill / 4, kFewest, kMost);
  writer_period_us_.store(static_cast<std::int64_t>(period * 1e6));
}

ARBITER_EVERY_STEP void Recorder::on_step(const Manager& manager) {
  if (!started_) return;
  ring_.capture(manager, false, ring_full_ == RingFull::kWaitForWriter);
}

void Recorder::wake_writer() {
  {
    std::lock_guard<std::mutex> lock(wake_mutex_);
    wake_requested_ = true;
  }
  wake_.notify_one();
}

void Recorder::drain() {
  if (!started_ || finished_) return;
  ring_.settle();
  wake_writer();
  while (backlog() > 0) std::this_thread::sleep_for(std::chrono::microseconds(50));
}

void Recorder::on_safe(const Manager& manager) {
  if (!started_) return;
  // The last values a stopping robot was given: not dropped for room.
  ring_.capture(manager, true, true);
}

void Recorder::stage_files(std::vector<std::pair<std::string, std::string>> files) {
  std::lock_guard<std::mutex> lock(staged_mutex_);
  staged_files_ = std::move(files);
}

std::vector<std::pair<std::string, std::string>> Recorder::take_staged_files() {
  std::lock_guard<std::mutex> lock(staged_mutex_);
  return std::exchange(staged_files_, {});
}

void Recorder::on_staged(const Program& next, std::uint64_t stage) {
  if (!out_) return;
  ring_.stage(next, stage, take_staged_files());
}

void Recorder::on_reload(const Manager& manager) {
  if (!started_) return;
  set_writer_period(manager.program());
  // A program staged without on_staged() has its files still here.
  auto files = take_staged_files();
  if (!files.empty()) ring_.stage(manager.program(), manager.stage_number(), std::move(files));
  ring_.reload(manager, wall_time(manager.timed(), manager.step_time()));
}

void Recorder::on_retiring(const Program&) {
  if (started_) ring_.wait_for_headers();
}

void Recorder::on_finish(const Manager&) {
  if (!started_ || finished_) return;
  ring_.end();
  wake_writer();
  writer_.join();
  finished_ = true;
}

void Recorder::write_loop() {
  using Clock = std::chrono::steady_clock;
  auto& out = *out_;
  // Nothing waits in the open chunk, or on its way to the storage, for longer than this: what a
  // crash or a power cut loses.
  const bool flushes = !(flush_interval_ <= 0.0);
  const auto flush_interval =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
          flush_interval_ < kMaxFlushInterval ? flush_interval_ : kMaxFlushInterval));
  bool unsynced = false;  // something was written, or put in the open chunk, since the last sync
  Clock::time_point unsynced_since;
  const auto flush_when_due = [&](Clock::time_point now) {
    if (!unsynced || now - unsynced_since < flush_interval) return;
    out.writer.close_chunk();
    check_written(out.last_step);
    request_sync(out.last_step);
    unsynced = false;
  };
  if (flushes) syncer_ = std::thread([this] { sync_loop(); });
  while (true) {
    const auto next = ring_.next();
    if (next == StepRing::Next::kNothing) {
      if (flushes && !failed()) flush_when_due(Clock::now());
      std::unique_lock<std::mutex> lock(wake_mutex_);
      wake_.wait_for(lock, std::chrono::microseconds(writer_period_us_.load()),
                     [this] { return wake_requested_; });
      wake_requested_ = false;
      continue;
    }
    if (next == StepRing::Next::kEnd) {
      ring_.release();
      break;
    }
    if (next == StepRing::Next::kHeader) {
      const auto after_step = ring_.header_step();
      const auto wall_time = ring_.header_wall_time();
      const auto header = reload_header(ring_.header(), ring_.header_reload(), after_step);
      std::vector<std::pair<std::string, std::string>> reload{
          {"after_step", std::to_string(after_step)}, {"header", header}};
      for (auto& [file, text] : ring_.take_files()) {
        reload.emplace_back("file:" + file, std::move(text));
      }
      // The steps before the reload came at the replaced program's rate, those after it at its.
      const auto time = out.clock.reload(after_step, wall_time, ring_.rate_hz());
      if (!failed()) {
        out.writer.metadata("arbiter.reload", reload);
        out.scene_updates.restart();  // the new program's picture whole, from its first step
        // A program laid out otherwise has channels of its own, on the same topics: each
        // message is checked against the schema of its program.
        const auto& channels = ring_.channels();
        if (channels[kStepChannel].schema != out.step_schema) {
          out.step = add_channel(channels[kStepChannel]);
          out.step_schema = channels[kStepChannel].schema;
        }
        if (channels[kInputsChannel].schema != out.inputs_schema) {
          out.inputs = add_channel(channels[kInputsChannel]);
          out.inputs_schema = channels[kInputsChannel].schema;
        }
        out.writer.message(out.header, time, wall_time, header);
      }
      out.last_step = after_step;
    } else if (!failed()) {
      const RingStep& step = ring_.step();
      const auto wall = wall_time(step.timed(), step.time());
      const auto time = log_time(step.step(), wall);
      out.record.clear();
      step.append_step_record(out.record);
      if (step.safe()) {
        out.writer.message(out.step, time, wall, out.record);  // no inputs: nothing was read
      } else {
        if (step.step() > out.last_step + 1) {
          const auto gap = step.step() - out.last_step - 1;
          out.dropped += gap;
          out.writer.metadata("arbiter.gap", {{"after_step", std::to_string(out.last_step)},
                                              {"dropped", std::to_string(gap)}});
          out.log_record.clear();
          append_dropped_log(time, kRecorderName, gap, out.last_step, "the writer fell behind",
                             out.log_record);
          out.writer.message(out.log, time, wall, out.log_record);
        }
        out.last_step = step.step();
        out.inputs_record.clear();
        step.append_inputs_record(out.inputs_record);
        out.writer.message(out.step, time, wall, out.record);
        out.writer.message(out.inputs, time, wall, out.inputs_record);
      }
      // Only steps that drew: a viewer keeps showing the last picture.
      if (step.drew()) {
        out.scene_record.clear();
        step.append_scene(out.scene_updates, time, out.scene_record);
        out.writer.message(out.scene, time, wall, out.scene_record);
      }
      for (std::size_t r = 0; r < step.report_count(); ++r) {
        out.log_record.clear();
        step.append_report_log(r, time, out.log_record);
        out.writer.message(out.log, time, wall, out.log_record);
      }
    }
    // After a failed write the writer only frees the slots: the run goes on, unrecorded.
    if (!failed()) {
      // A step's record and its inputs go into one chunk: a file cut off has both or neither.
      if (out.writer.chunk_full()) out.writer.close_chunk();
      check_written(out.last_step);
      if (flushes) {
        const auto now = Clock::now();
        if (!unsynced) {
          unsynced = true;
          unsynced_since = now;
        }
        flush_when_due(now);
      }
    }
    ring_.release();
  }
  if (!failed()) {
    out.writer.metadata("arbiter.summary", {{"steps", std::to_string(out.last_step)},
                                            {"dropped", std::to_string(out.dropped)}});
    out.writer.finish();
    check_written(out.last_step);
    if (flushes) request_sync(out.last_step);  // the run is over: it may wait for this one
  }
  if (syncer_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(sync_mutex_);
      sync_stop_ = true;
    }
    sync_wake_.notify_one();
    syncer_.join();
  }
  // Closed here, not by the destructor: a file system that reports a failed write only at the
  // close (NFS) is reported with the others, before on_finish() returns.
  const int closed = ::close(fd_);
  const int error = errno;
  fd_ = -1;
  if (closed != 0 && error != EINTR && !failed()) fail(error, out.last_step);
}

void Recorder::request_sync(std::uint64_t step) {
  {
    std::lock_guard<std::mutex> lock(sync_mutex_);
    sync_requested_ = true;
    sync_step_ = step;
  }
  sync_wake_.notify_one();
}

void Recorder::sync_loop() {
  std::unique_lock<std::mutex> lock(sync_mutex_);
  while (true) {
    sync_wake_.wait(lock, [this] { return sync_requested_ || sync_stop_; });
    if (!sync_requested_) return;  // stopped, with nothing left to sync
    sync_requested_ = false;
    const auto step = sync_step_;
    lock.unlock();
    // EINVAL: a pipe or a device, which keep nothing to sync. Requests made meanwhile are
    // served by the next sync, which covers them all.
    if (::fdatasync(fd_) != 0 && errno != EINVAL) fail(errno, step, "syncing");
    lock.lock();
  }
}

}  // namespace arbiter

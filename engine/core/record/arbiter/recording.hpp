#pragma once
// Stage 5 of the data path, for keeping: a run recorded as MCAP (https://mcap.dev/spec), with the
// trace's step records, the values interface layers wrote into the engine, and the config.
// docs/replay.md describes the file.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "arbiter/channels.hpp"
#include "arbiter/diagnostics.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/step_ring.hpp"

namespace arbiter {

/// What a recording keeps besides the steps, for replaying the run.
struct RecordingInfo {
  /// Each file the config read (the config first, then its includes), with its text.
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<std::string> plugins;
  std::string version;  ///< Arbiter's
  /// The run keeps to its rate in real time (`arbiter run --realtime`): its messages are logged
  /// at the wall-clock time of their step. Otherwise at the run's own, simulated, time: step /
  /// rate_hz after the run's start, however fast it went. Publish times are the wall clock.
  bool paced = false;
  /// What loading the config warned about: on `/arbiter/log` at the start.
  std::vector<Diagnostic> diagnostics = {};
};

/// What a recorder does with a step when every slot of its ring still waits for the writer.
enum class RingFull {
  /// Drops the step (dropped() counts it, the file records the gap): a paced run keeps its pace.
  kDropStep,
  /// Waits for the writer to free a slot: a run that is not paced loses nothing.
  kWaitForWriter,
};

/// Records a run into an MCAP file. The stepping thread only copies the step into a ring of
/// slots allocated when the run starts (and again for each program staged by a hot reload, on
/// the staging thread); a writer thread compresses and writes them. When the writer falls
/// behind, whole steps are dropped or waited for (RingFull). Finish the run (Manager::finish())
/// before removing a recorder from its manager.
///
/// A write that fails (a full disk, a file size limit) ends the recording, never the run: it is
/// logged at once, failed() and error() tell it, and the file keeps what was written before.
class Recorder : public Observer {
 public:
  /// The steps that may wait for the writer unless told otherwise.
  static constexpr std::size_t kSlots = 256;
  /// Seconds a step may wait in the writer's open chunk unless told otherwise.
  static constexpr double kFlushInterval = 1.0;
  /// The longest flush interval: a day.
  static constexpr double kMaxFlushInterval = 86400.0;
  /// `slots` steps (at least 1) may wait for the writer. Open fails (ok() false) when `path`
  /// cannot be opened for writing.
  Recorder(const std::string& path, RecordingInfo info, std::size_t slots = kSlots,
           RingFull ring_full = RingFull::kDropStep);
  /// Writes to `fd`, a descriptor open for writing that it takes over (and closes), naming the
  /// file `name` in its reports: for a file that must not be opened again, such as standard
  /// output's (a duplicate of it keeps its offset and O_APPEND, where opening /dev/stdout again
  /// would truncate what the shell appends to). A negative `fd` fails as an open would.
  Recorder(int fd, std::string name, RecordingInfo info, std::size_t slots = kSlots,
           RingFull ring_full = RingFull::kDropStep);
  ~Recorder() override;
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// The file is open and no write to it has failed.
  bool ok() const;
  /// The writer closes its open chunk once the oldest step in it has waited `seconds` (on the
  /// steady clock), and a thread of its own then has the system put the file on its storage
  /// (fdatasync): a crash or a power cut loses about that much at most. 0: a chunk is closed only
  /// when 256 KiB of records fill it, and the file is left to the system to sync. At most
  /// kMaxFlushInterval (more, or NaN, is taken as that). Before the run starts.
  void set_flush_interval(double seconds) { flush_interval_ = seconds; }
  /// Where a failed write is reported (default: spdlog's default logger). Before the run starts.
  void set_logger(std::shared_ptr<spdlog::logger> logger) { logger_ = std::move(logger); }
  /// True once a write to the file failed (any thread).
  bool failed() const { return failed_.load(std::memory_order_acquire); }
  /// Why the file could not be opened ("No such file or directory", ok() false from the start),
  /// or why a write failed and at which step ("No space left on device (writing step 605)");
  /// "" while neither happened.
  std::string error() const;

  void on_start(const Manager& manager) override;
  void on_step(const Manager& manager) override;
  /// Hands the writer the layout prepared by on_staged() for the program swapped in: neither
  /// allocates nor waits for the writer to catch up. It waits only for a free slot when the ring
  /// is full (a reload header is never dropped), and allocates only when the program was staged
  /// without on_staged() or raced by a later stage().
  void on_reload(const Manager& manager) override;
  /// Lays the ring out for `next`, on the staging thread.
  void on_staged(const Program& next, std::uint64_t stage) override;
  /// Waits until the writer has written the steps of the replaced program (they point into it).
  void on_retiring(const Program& replaced) override;
  /// The safe-value pass, as the trace has it, on `/arbiter/step`.
  void on_safe(const Manager& manager) override;
  void on_finish(const Manager& manager) override;

  std::uint64_t dropped() const { return ring_.dropped(); }
  /// Wakes the writer and waits until it has written every step copied so far. Between steps,
  /// not while the manager steps: it makes system calls, and publishes the last step's slot.
  void drain();
  /// Steps handed to the writer and not yet written (any thread); the last step's slot is
  /// handed over at the next call (drain() does it).
  std::size_t backlog() const { return ring_.backlog(); }

  /// The files (path, text) of a config about to be staged for a hot reload: on_staged() takes
  /// them, and the recording's reload record keeps them, so that a replay can reload it too.
  /// Any thread; call it before Manager::stage() (Reloader's on_staging does).
  void stage_files(std::vector<std::pair<std::string, std::string>> files);

 private:
  // How the ring waits for the writer: woken early, never given up on before the end.
  struct Waiter : StepRing::Waiter {
    explicit Waiter(Recorder& recorder) : recorder(recorder) {}
    void wake() override { recorder.wake_writer(); }
    bool give_up() const override { return recorder.finished_; }
    Recorder& recorder;
  };
  /// Wakes the writer before its period is up: a system call, never made in a step that finds
  /// room.
  void wake_writer();
  /// The wall-clock time of a step: the wall clock at the run's start plus the step's "t" (the
  /// manager's clock; a manager without one has every step at the start).
  std::uint64_t wall_time(bool timed, double step_time) const;
  /// The log time of step `step`, at `wall_time` on the wall clock (RecordingInfo::paced). The
  /// writer's: it keeps the simulated clock.
  std::uint64_t log_time(std::uint64_t step, std::uint64_t wall_time) const;
  /// Adds a channel to the file, with its schema. The writer's, or before it starts.
  std::uint16_t add_channel(const Channel& channel);
  /// The writer's period for a program's rate.
  void set_writer_period(const Program& program);
  /// The files stage_files() left, taken.
  std::vector<std::pair<std::string, std::string>> take_staged_files();
  void write_loop();
  /// Ends the recording if a write of the writer failed.
  void check_written(std::uint64_t step);
  /// Ends the recording: keeps the failure (an errno), logs it, and writes nothing more. The
  /// first call of any thread wins.
  void fail(int error, std::uint64_t step, const char* doing = "writing");
  /// Asks the sync thread to sync the file, without waiting for it.
  void request_sync(std::uint64_t step);
  /// The sync thread: fdatasync, whenever asked, until told to stop.
  void sync_loop();
  /// `opened`: the descriptor, and why it could not be opened when it is -1.
  Recorder(std::string name, std::pair<int, int> opened, RecordingInfo info, std::size_t slots,
           RingFull ring_full);

  std::string path_;
  int open_errno_ = 0;  // why open() failed
  int fd_ = -1;
  RecordingInfo info_;
  std::size_t slots_ = 0;
  Waiter waiter_{*this};
  // The steps on their way from the stepping thread to the writer, laid out for the running
  // program and for those still being written.
  StepRing ring_;
  std::mutex staged_mutex_;
  // By staged_mutex_: the files of the config staged next (stage_files()).
  std::vector<std::pair<std::string, std::string>> staged_files_;
  // The writer sleeps this long whenever it has caught up, unless woken (wake_writer()).
  std::atomic<std::int64_t> writer_period_us_{1000};
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool wake_requested_ = false;  // by wake_mutex_
  std::thread writer_;
  struct Output;
  std::unique_ptr<Output> out_;
  RingFull ring_full_ = RingFull::kDropStep;
  std::uint64_t wall_start_ns_ = 0;
  double flush_interval_ = kFlushInterval;
  std::shared_ptr<spdlog::logger> logger_;
  // Set once, by the first thread that fails (fail()), before failed_.
  std::string error_;
  std::atomic<bool> failing_{false};
  std::atomic<bool> failed_{false};
  // The sync thread, which waits for the storage so that the writer never does: a sync can take
  // longer than the ring takes to fill at a high rate.
  std::thread syncer_;
  std::mutex sync_mutex_;
  std::condition_variable sync_wake_;
  bool sync_requested_ = false;  // by sync_mutex_
  bool sync_stop_ = false;       // by sync_mutex_
  std::uint64_t sync_step_ = 0;  // by sync_mutex_: the last step written when it was asked
  // Read by the staging thread too.
  std::atomic<bool> started_{false};
  std::atomic<bool> finished_{false};
};

/// The message on `/arbiter/inputs`: {"step": N, "inputs": {NAME: {"value": V, "written": B}}}
/// for every actuator of an interface layer, and "reported": [TEXT, ...] when interface code
/// reported something in the step.
void append_inputs_record(const Manager& manager, std::string& out);

}  // namespace arbiter

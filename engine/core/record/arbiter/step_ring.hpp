#pragma once
// Stage 5 of the data path, the hand-over: a run's steps from the stepping thread to one reader
// thread, a recorder's writer (recording.hpp) or the live Foxglove server's. The stepping thread
// copies each step into the next slot of a ring laid out when the program was loaded: no
// allocation, no lock, no system call, no wait. When the reader falls behind, the step is
// dropped and counted (or, for what must never be lost, waited for); the reader formats each
// slot's messages on its own thread. docs/performance.md, "What the stepping thread does".

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "arbiter/channels.hpp"
#include "arbiter/manager.hpp"

namespace arbiter {

namespace detail {
struct StepLayout;
struct StepSnapshot;
}  // namespace detail

/// The log time of a run's messages, for a recorder and a live server alike: the wall clock for a
/// paced run, else the run's own simulated time, step / rate_hz after `start_ns` (docs/replay.md,
/// "Log time and publish time"). The reader's.
class LogClock {
 public:
  LogClock() = default;
  LogClock(bool paced, std::uint64_t start_ns, double rate_hz)
      : paced_(paced), start_ns_(start_ns), rate_hz_(rate_hz) {}
  /// The log time of step `step`, which was at `wall_ns` on the wall clock.
  std::uint64_t time(std::uint64_t step, std::uint64_t wall_ns) const;
  /// A hot reload after step `step` (at `wall_ns`): the steps after it come at `rate_hz`. Returns
  /// the reload's log time.
  std::uint64_t reload(std::uint64_t step, std::uint64_t wall_ns, double rate_hz);

 private:
  bool paced_ = false;
  std::uint64_t start_ns_ = 0;
  double rate_hz_ = 1.0;
  std::uint64_t clock_step_ = 0;  // the step that was at clock_ns_ after the start
  std::uint64_t clock_ns_ = 0;
};

/// The `/arbiter/log` message (from `who`) saying that `who` dropped `gap` steps after step
/// `after`, and `why`.
void append_dropped_log(std::uint64_t time, std::string_view who, std::uint64_t gap,
                        std::uint64_t after, std::string_view why, std::string& out);

/// A step as the reader has it, with the messages of the channels a step feeds (channels.hpp).
/// Valid until the reader releases its slot.
class RingStep {
 public:
  std::uint64_t step() const;
  /// The safe-value pass, not a step: it has no inputs.
  bool safe() const;
  /// The manager has a clock: time() is the step's "t".
  bool timed() const;
  double time() const;
  /// Steps dropped just before this one, for want of room (a full ring, or more than a slot
  /// holds).
  std::uint64_t dropped_before() const { return dropped_before_; }
  /// `/arbiter/step`, as the trace has it.
  void append_step_record(std::string& out) const;
  /// `/arbiter/inputs` (append_inputs_record() in recording.hpp).
  void append_inputs_record(std::string& out) const;
  /// The step drew, or dropped what it drew: only such a step has a scene message.
  bool drew() const;
  /// `/arbiter/scene`: what changed since the message `updates` made before.
  void append_scene(SceneUpdates& updates, std::uint64_t time_ns, std::string& out) const;
  /// What code reported in the step, each an `/arbiter/log` message logged at `time_ns`.
  std::size_t report_count() const;
  void append_report_log(std::size_t report, std::uint64_t time_ns, std::string& out) const;

 private:
  friend class StepRing;
  const detail::StepLayout* layout_ = nullptr;
  detail::StepSnapshot* snapshot_ = nullptr;
  std::uint64_t dropped_before_ = 0;
};

/// Whether a capture copies the step's picture. Its copy is most of a small program's capture,
/// so a reader that nobody asks for the picture leaves it out: the step then reads as one that
/// drew nothing (RingStep::drew() false).
enum class CapturePicture { kCopy, kLeaveOut };

/// The ring. One thread steps (start(), capture(), skip(), settle(), reload(), end()), one
/// reads (next(), release() and what they give), one may stage (stage()).
class StepRing {
 public:
  /// Tells the ring how to wait for the reader when it must (a reload header, the end, a step
  /// that must not be dropped), and when to stop waiting.
  class Waiter {
   public:
    virtual ~Waiter() = default;
    /// Wakes the reader before its period is up: called once, when the ring is found full.
    virtual void wake() {}
    /// The reader is gone: whatever waits for it gives up.
    virtual bool give_up() const { return false; }
  };

  /// `slots` steps (at least 1) may wait for the reader.
  explicit StepRing(std::size_t slots, Waiter& waiter);
  ~StepRing();
  StepRing(const StepRing&) = delete;
  StepRing& operator=(const StepRing&) = delete;

  // The stepping thread's.
  /// Lays the ring out for `manager`'s program. `announce`: the reader learns it from a header
  /// (next() gives kHeader, reload 0, at `wall_time`); else the reader has it at once, before
  /// its thread starts.
  void start(const Manager& manager, std::uint64_t wall_time, bool announce);
  /// Copies the manager's last step (or safe pass) into the next slot, handed over at the next
  /// call (settle()). False when it was dropped (counted): no free slot, unless `wait`, or more
  /// than a slot holds (`may_allocate`: a string value longer than its room is copied anyway).
  bool capture(const Manager& manager, bool may_allocate = false, bool wait = false,
               CapturePicture picture = CapturePicture::kCopy);
  /// A step not captured (nobody wants it): the next capture copies every part whole.
  void skip();
  /// Hands the last capture's slot over to the reader, if it waits. A step's slot goes at the
  /// next call: its streamed stores must be fenced first, and by then the fence finds them done.
  void settle();
  /// The program swapped in by a hot reload: its layout from stage() (else laid out here,
  /// allocating), and a header that the reader meets before the steps laid out by it. The header
  /// is never dropped: waits for a free slot. False when the waiter gave up (nothing published).
  bool reload(const Manager& manager, std::uint64_t wall_time);
  /// The end: the reader meets kEnd after the last step. Waits for a free slot.
  void end();

  // The staging thread's.
  /// Lays the ring out for `next`, to be taken by the reload of `stage`, with the files of its
  /// config (files()).
  void stage(const Program& next, std::uint64_t stage,
             std::vector<std::pair<std::string, std::string>> files = {});

  // Any thread.
  /// Waits until the reader has met every header published (the steps before a reload point
  /// into the replaced program), or the waiter gives up. Wakes the reader first.
  void wait_for_headers();
  std::uint64_t dropped() const;
  /// Slots handed over and not yet released.
  std::size_t backlog() const;

  // The reader's.
  enum class Next {
    kNothing,  ///< every slot handed over has been released
    kStep,     ///< step()
    kHeader,   ///< the next steps are laid out for header()'s program
    kEnd,      ///< end()
  };
  /// What the oldest slot not yet released holds: to be released (release()) once read.
  Next next();
  const RingStep& step() const;
  void release();
  /// The program the reader's steps come from (after kHeader: the header's).
  const std::string& header() const;  ///< the trace header, without a reload's number
  const std::vector<Channel>& channels() const;
  double rate_hz() const;
  /// The files of the reloaded config (stage()), taken.
  std::vector<std::pair<std::string, std::string>> take_files();
  /// kHeader: the step after which the program was swapped in, the reload's number (0: the
  /// start), and the wall time.
  std::uint64_t header_step() const;
  std::uint64_t header_reload() const;
  std::uint64_t header_wall_time() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Nanoseconds since the Unix epoch on the wall clock: the time of a ring's headers.
std::uint64_t wall_clock_ns();

/// The stepping side of a ring whose reader wants the steps only at times (the live Foxglove
/// server, whose clients subscribe and leave): the observer to add to the manager. Captures each
/// step while the reader wants steps, with its picture while it wants every step's or has asked
/// for the next one, and otherwise skips it; announces the start and every reload with a header.
/// Kept with the ring in the library so that a served step goes from the manager into the capture
/// without calling into other code: at a robot's pace each call into code elsewhere is a cold page.
/// On cache lines of its own: the stepping thread reads its flags at every step, and a neighbour
/// that another thread writes would take the line from it each time.
class alignas(64) StepFeed final : public Observer {
 public:
  explicit StepFeed(StepRing& ring) : ring_(ring) {}

  /// The reader's: what it wants of the steps from the next capture on, the picture of every
  /// step or not.
  void want(bool steps, bool picture) {
    picture_wanted_.store(picture, std::memory_order_relaxed);
    wanted_.store(steps, std::memory_order_relaxed);
  }
  /// The reader's: the next step captured carries its picture, even while the reader does not
  /// want every step's (one that shows the picture at a rate of its own). Asked again before
  /// that step, it is still one picture.
  void want_next_picture() { pictures_asked_.fetch_add(1, std::memory_order_relaxed); }
  /// The run has started: the ring has its first header.
  bool started() const { return started_.load(std::memory_order_acquire); }

  void on_start(const Manager& manager) override;
  void on_step(const Manager& manager) override;
  void on_safe(const Manager& manager) override;
  void on_staged(const Program& next, std::uint64_t stage) override;
  void on_reload(const Manager& manager) override;
  void on_retiring(const Program& replaced) override;
  void on_finish(const Manager& manager) override;

 private:
  StepRing& ring_;
  std::atomic<bool> started_{false};
  std::atomic<bool> wanted_{false};
  std::atomic<bool> picture_wanted_{false};
  std::atomic<std::uint64_t> pictures_asked_{0};
  std::uint64_t pictures_given_ = 0;  // the stepping thread's: pictures_asked_ at the last one
};

}  // namespace arbiter

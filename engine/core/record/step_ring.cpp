#include "arbiter/step_ring.hpp"

#include <fmt/format.h>

#include <chrono>
#include <mutex>
#include <optional>
#include <thread>

#include "arbiter/trace.hpp"
#include "core/record/step_record.hpp"
#include "core/run/code_placement.hpp"

namespace arbiter {

std::uint64_t LogClock::time(std::uint64_t step, std::uint64_t wall_ns) const {
  if (paced_) return wall_ns;
  const auto since = step > clock_step_ ? step - clock_step_ : 0;
  return start_ns_ + clock_ns_ +
         static_cast<std::uint64_t>(static_cast<double>(since) * 1e9 / rate_hz_);
}

std::uint64_t LogClock::reload(std::uint64_t step, std::uint64_t wall_ns, double rate_hz) {
  const auto at = time(step, wall_ns);
  clock_ns_ = at > start_ns_ ? at - start_ns_ : 0;
  clock_step_ = step;
  rate_hz_ = rate_hz;
  return at;
}

void append_dropped_log(std::uint64_t time, std::string_view who, std::uint64_t gap,
                        std::uint64_t after, std::string_view why, std::string& out) {
  append_log_message(time, LogLevel::kWarning, who,
                     fmt::format("the {} dropped {} step{} after step {}: {}", who, gap,
                                 gap == 1 ? "" : "s", after, why),
                     {}, 0, out);
}

std::uint64_t RingStep::step() const {
  return snapshot_->step;
}

bool RingStep::safe() const {
  return snapshot_->safe;
}

bool RingStep::timed() const {
  return snapshot_->timed;
}

double RingStep::time() const {
  return snapshot_->t;
}

void RingStep::append_step_record(std::string& out) const {
  detail::append_step_record(*layout_, *snapshot_, out);
}

void RingStep::append_inputs_record(std::string& out) const {
  detail::append_inputs_record(*layout_, *snapshot_, out);
}

bool RingStep::drew() const {
  return snapshot_->scene.size() > 0 || snapshot_->scene_dropped > 0;
}

void RingStep::append_scene(SceneUpdates& updates, std::uint64_t time_ns, std::string& out) const {
  updates.append(time_ns, snapshot_->picture(), out);
}

std::size_t RingStep::report_count() const {
  return snapshot_->reports.size();
}

void RingStep::append_report_log(std::size_t report, std::uint64_t time_ns,
                                 std::string& out) const {
  const auto& r = snapshot_->reports[report];
  append_log_message(time_ns, LogLevel::kInfo, detail::report_source(*layout_, r.source),
                     snapshot_->texts.substr(r.text_begin, r.text_size), {}, 0, out);
}

namespace {

using Generation = detail::SnapshotGeneration;

// A step's values are in the block of the same index of the generation it was captured with;
// the stepping thread writes nothing here for a step but after a drop, only for a header or the
// end. Cache-line aligned: the stepping thread fills one slot while the reader reads another.
struct alignas(64) Slot {
  enum class Kind { kSnapshot, kHeader, kEnd };
  Kind kind = Kind::kSnapshot;
  std::uint64_t step = 0;       // kHeader
  std::uint64_t reload = 0;     // kHeader: Manager::reloads(), 0 for the start
  std::uint64_t wall_time = 0;  // kHeader
  // kSnapshot: the steps dropped just before this one. Written by the stepping thread only after
  // a drop, and set back to 0 by the reader, so that a step writes nothing here.
  std::uint64_t dropped = 0;
  std::unique_ptr<Generation> next;  // kHeader: the slots after it are laid out by it
};

}  // namespace

struct StepRing::Impl {
  Impl(std::size_t slots, Waiter& waiter_)
      // One slot is always left empty, to tell a full ring from an empty one.
      : ring_size(std::max<std::size_t>(slots, 1) + 1),
        ring(std::make_unique<Slot[]>(ring_size)),
        waiter(waiter_) {}

  // The slot after `index`: a compare, not a modulo, whose division would cost the stepping
  // thread more than the rest of publishing a step.
  std::size_t after(std::size_t index) const { return index + 1 == ring_size ? 0 : index + 1; }
  detail::SnapshotBlock block(const Generation& generation, const Slot* slot) const {
    return generation.blocks[static_cast<std::size_t>(slot - ring.get())];
  }
  Slot* claim() {
    const auto at = head.load(std::memory_order_relaxed);
    const auto next = after(at);
    if (next == tail_seen) {
      tail_seen = tail.load(std::memory_order_acquire);
      if (next == tail_seen) return nullptr;
    }
    return &ring[at];
  }
  // claim(), waiting for the reader to free a slot: for what must never be dropped. Null when
  // the waiter gives up.
  Slot* claim_waiting() {
    Slot* slot = claim();
    if (slot != nullptr) return slot;
    waiter.wake();
    while ((slot = claim()) == nullptr) {
      if (waiter.give_up()) return nullptr;
      std::this_thread::yield();
    }
    return slot;
  }
  void publish() {
    head.store(after(head.load(std::memory_order_relaxed)), std::memory_order_release);
  }
  void publish_header(Slot* slot, std::uint64_t step, std::uint64_t reload, std::uint64_t wall_time,
                      std::unique_ptr<Generation> next) {
    slot->kind = Slot::Kind::kHeader;
    slot->step = step;
    slot->reload = reload;
    slot->wall_time = wall_time;
    slot->next = std::move(next);
    headers_published.fetch_add(1, std::memory_order_release);
    publish();
  }

  const std::size_t ring_size;
  std::unique_ptr<Slot[]> ring;
  Waiter& waiter;
  // Each on a cache line of its own, so that the two threads do not take the line from each
  // other at every step; the stepping thread reads tail only when the ring looks full.
  alignas(64) std::atomic<std::size_t> head{0};  // next slot the stepping thread fills
  std::size_t tail_seen = 0;                     // tail as the stepping thread last read it
  bool unpublished = false;                      // the last capture's slot waits for settle()
  // The last slot published is the one before the next (no step dropped since), so that the
  // next capture copies only what changed.
  bool chained = false;
  std::uint64_t pending_drops = 0;  // steps dropped since the last slot published
  Generation* stepping = nullptr;   // the running program's
  // Generations the stepping thread laid out for a reload that the reader will never meet.
  std::vector<std::unique_ptr<Generation>> orphans;
  alignas(64) std::atomic<std::size_t> tail{0};  // next slot the reader reads
  alignas(64) std::atomic<std::uint64_t> dropped{0};
  // Headers handed to the reader (by the stepping thread) and met by it: wait_for_headers()
  // waits for the second to reach the first.
  std::atomic<std::uint64_t> headers_published{0};
  alignas(64) std::atomic<std::uint64_t> headers_read{0};
  std::mutex staged_mutex;
  std::unique_ptr<Generation> staged;  // by staged_mutex

  // The reader's: the generation of the slots it reads (a header hands it the next and frees
  // the one before, every slot of which has been read by then), and the slot it looks at.
  std::unique_ptr<Generation> reading;
  std::size_t head_seen = 0;  // head is read again only once the reader has caught up with it
  Slot* current = nullptr;
  detail::StepImage image;
  std::optional<detail::StepSnapshot> snapshot;
  RingStep step;
};

StepRing::StepRing(std::size_t slots, Waiter& waiter)
    : impl_(std::make_unique<Impl>(slots, waiter)) {}

StepRing::~StepRing() = default;

void StepRing::start(const Manager& manager, std::uint64_t wall_time, bool announce) {
  auto& impl = *impl_;
  auto generation =
      std::make_unique<Generation>(manager.program(), manager.stage_number(), impl.ring_size);
  impl.stepping = generation.get();
  if (!announce) {
    impl.reading = std::move(generation);
    return;
  }
  Slot* slot = impl.claim();  // the ring is empty
  impl.publish_header(slot, manager.steps(), 0, wall_time, std::move(generation));
}

ARBITER_EVERY_STEP bool StepRing::capture(const Manager& manager, bool may_allocate, bool wait,
                                          CapturePicture picture) {
  auto& impl = *impl_;
  settle();
  Slot* slot = wait ? impl.claim_waiting() : impl.claim();
  const auto* g = impl.stepping;
  if (slot == nullptr ||
      !detail::capture_step_in_library(manager, g->layout, g->blocks.shape(), impl.block(*g, slot),
                                       may_allocate, &impl.stepping->last, impl.chained, picture)) {
    // No room, or more than a slot holds: the reader tells the gap.
    impl.dropped.fetch_add(1, std::memory_order_relaxed);
    ++impl.pending_drops;
    impl.chained = false;  // the next slot copies every tracked part whole
    return false;
  }
  if (impl.pending_drops > 0) {
    slot->dropped = impl.pending_drops;
    impl.pending_drops = 0;
  }
  impl.chained = true;
  impl.unpublished = true;
  return true;
}

void StepRing::skip() {
  settle();
  impl_->chained = false;
}

ARBITER_EVERY_STEP void StepRing::settle() {
  auto& impl = *impl_;
  if (!impl.unpublished) return;
  detail::fence_streamed_stores();
  impl.publish();
  impl.unpublished = false;
}

bool StepRing::reload(const Manager& manager, std::uint64_t wall_time) {
  auto& impl = *impl_;
  settle();
  // The slots still waiting for the reader keep the replaced program's generation (and their
  // state machines' config params point into that program: wait_for_headers() keeps it until
  // then). The steps from here on go into the next one's blocks.
  std::unique_ptr<Generation> next;
  {
    // The staging thread holds the lock only to move a pointer or two: never for long.
    std::lock_guard<std::mutex> lock(impl.staged_mutex);
    if (impl.staged && impl.staged->stage == manager.stage_number()) next = std::move(impl.staged);
  }
  if (!next) {
    // Staged without stage(), or raced by a later one: laid out here, allocating.
    next = std::make_unique<Generation>(manager.program(), manager.stage_number(), impl.ring_size);
  }
  impl.stepping = next.get();
  impl.chained = false;  // the next step copies every tracked part whole, into the new blocks
  Slot* slot = impl.claim_waiting();
  if (slot == nullptr) {
    impl.orphans.push_back(std::move(next));
    return false;
  }
  impl.publish_header(slot, manager.steps(), manager.reloads(), wall_time, std::move(next));
  return true;
}

void StepRing::end() {
  auto& impl = *impl_;
  settle();
  Slot* slot = impl.claim_waiting();
  if (slot == nullptr) return;
  slot->kind = Slot::Kind::kEnd;
  impl.publish();
}

void StepRing::stage(const Program& next, std::uint64_t stage,
                     std::vector<std::pair<std::string, std::string>> files) {
  auto generation = std::make_unique<Generation>(next, stage, impl_->ring_size);
  generation->files = std::move(files);
  {
    std::lock_guard<std::mutex> lock(impl_->staged_mutex);
    std::swap(impl_->staged, generation);
  }
  // A generation staged before and never swapped in is freed here, outside the lock.
}

void StepRing::wait_for_headers() {
  auto& impl = *impl_;
  const auto published = impl.headers_published.load(std::memory_order_acquire);
  if (impl.headers_read.load(std::memory_order_acquire) >= published) return;
  impl.waiter.wake();
  while (impl.headers_read.load(std::memory_order_acquire) < published && !impl.waiter.give_up()) {
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
}

std::uint64_t StepRing::dropped() const {
  return impl_->dropped.load();
}

std::size_t StepRing::backlog() const {
  const auto head = impl_->head.load(std::memory_order_acquire);
  const auto tail = impl_->tail.load(std::memory_order_acquire);
  return (head + impl_->ring_size - tail) % impl_->ring_size;
}

StepRing::Next StepRing::next() {
  auto& impl = *impl_;
  const auto tail = impl.tail.load(std::memory_order_relaxed);
  if (tail == impl.head_seen) {
    impl.head_seen = impl.head.load(std::memory_order_acquire);
    if (tail == impl.head_seen) return Next::kNothing;
  }
  Slot& slot = impl.ring[tail];
  impl.current = &slot;
  if (slot.kind == Slot::Kind::kEnd) return Next::kEnd;
  if (slot.kind == Slot::Kind::kHeader) {
    // Every slot of the generation before has been read: it goes, the next one comes.
    impl.reading = std::move(slot.next);
    return Next::kHeader;
  }
  // The reader only reads the block: a line it wrote would have to come back to the stepping
  // thread's core before that could fill the slot again.
  impl.snapshot.emplace(impl.reading->blocks.shape(), impl.block(*impl.reading, &slot));
  impl.snapshot->apply(impl.image);
  impl.step.layout_ = &impl.reading->layout;
  impl.step.snapshot_ = &*impl.snapshot;
  impl.step.dropped_before_ = slot.dropped;
  return Next::kStep;
}

const RingStep& StepRing::step() const {
  return impl_->step;
}

void StepRing::release() {
  auto& impl = *impl_;
  Slot& slot = *impl.current;
  impl.current = nullptr;
  // Set back before the slot goes to the stepping thread, which writes them only when it must.
  if (slot.kind == Slot::Kind::kHeader) {
    slot.kind = Slot::Kind::kSnapshot;
    impl.headers_read.fetch_add(1, std::memory_order_release);
  }
  if (slot.dropped != 0) slot.dropped = 0;
  impl.tail.store(impl.after(impl.tail.load(std::memory_order_relaxed)), std::memory_order_release);
}

const std::string& StepRing::header() const {
  return impl_->reading->header;
}

const std::vector<Channel>& StepRing::channels() const {
  return impl_->reading->channels;
}

double StepRing::rate_hz() const {
  return impl_->reading->rate_hz;
}

std::vector<std::pair<std::string, std::string>> StepRing::take_files() {
  return std::exchange(impl_->reading->files, {});
}

std::uint64_t StepRing::header_step() const {
  return impl_->current->step;
}

std::uint64_t StepRing::header_reload() const {
  return impl_->current->reload;
}

std::uint64_t StepRing::header_wall_time() const {
  return impl_->current->wall_time;
}

std::uint64_t wall_clock_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

void StepFeed::on_start(const Manager& manager) {
  // Handed to the reader as a reload would be: it learns the channels from the header.
  ring_.start(manager, wall_clock_ns(), true);
  started_.store(true, std::memory_order_release);
}

ARBITER_EVERY_STEP void StepFeed::on_step(const Manager& manager) {
  if (!started_.load(std::memory_order_relaxed)) return;
  if (wanted_.load(std::memory_order_relaxed)) {
    const auto asked = pictures_asked_.load(std::memory_order_relaxed);
    const bool picture =
        picture_wanted_.load(std::memory_order_relaxed) || asked != pictures_given_;
    const bool captured = ring_.capture(
        manager, false, false, picture ? CapturePicture::kCopy : CapturePicture::kLeaveOut);
    // A step dropped for room leaves the picture asked for to the next one.
    if (picture && captured) pictures_given_ = asked;
  } else {
    ring_.skip();
  }
}

void StepFeed::on_safe(const Manager& manager) {
  on_step(manager);  // captured as a step is
}

void StepFeed::on_staged(const Program& next, std::uint64_t stage) {
  ring_.stage(next, stage);
}

void StepFeed::on_reload(const Manager& manager) {
  // A header is never dropped: the steps after it are laid out by it.
  if (started_.load(std::memory_order_relaxed)) ring_.reload(manager, wall_clock_ns());
}

void StepFeed::on_retiring(const Program&) {
  // The reader formats steps of the replaced program until it reaches the header.
  ring_.wait_for_headers();
}

void StepFeed::on_finish(const Manager&) {
  if (started_.load(std::memory_order_relaxed)) ring_.settle();
}

}  // namespace arbiter

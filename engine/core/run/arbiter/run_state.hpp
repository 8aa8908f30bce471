#pragma once
// What the steps of one program read and write, apart from the program: actuator and port values,
// the behaviours' levels, fault bookkeeping and aggregation scratch. The Manager holds the running
// program's; a hot reload builds the next program's beside it, and the swap exchanges the two
// whole, so a buffer can be added in one place only (here) and never be forgotten by the swap.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/program.hpp"

namespace arbiter {

/// Where RunState keeps what observers copy at every step, in one allocation and in this order:
/// each behaviour's requested and activation level and active flag, each actuator's written
/// flag, and the values (actuators, then writer slots, at the program's offsets). A recorder
/// copies a small graph's in one move, and lays its snapshots out by the same offsets.
struct TrackedLayout {
  enum Part : std::size_t { kRequested, kActivation, kActive, kWritten, kValues, kParts };
  /// What the allocation, and so the values' offsets, are aligned to.
  static constexpr std::size_t kAlignment = alignof(std::max_align_t);

  TrackedLayout() = default;
  TrackedLayout(std::size_t behaviours, std::size_t actuators, std::size_t value_bytes);

  std::size_t at[kParts] = {};
  std::size_t bytes[kParts] = {};
  std::size_t total = 0;  ///< where the last part ends
  /// The allocation's bytes: `total` in whole cache lines, so that a copy may read it by lines.
  std::size_t allocated = 0;
  static constexpr std::size_t kLine = 64;
  /// Where the first `parts` parts end: the bytes a copy of them takes.
  std::size_t end_of(std::size_t parts) const {
    return parts == 0 ? 0 : at[parts - 1] + bytes[parts - 1];
  }
};

/// Bytes holding values of several types at given offsets; destroys what it constructed.
class ValueBuffer {
 public:
  ValueBuffer() = default;
  explicit ValueBuffer(std::size_t bytes);
  ~ValueBuffer();
  ValueBuffer(ValueBuffer&& other) noexcept { swap(other); }
  /// Exchanges the two, so that no value is destroyed here (a hot-reload swap runs in a step):
  /// `other` destroys them later.
  ValueBuffer& operator=(ValueBuffer&& other) noexcept {
    swap(other);
    return *this;
  }
  ValueBuffer(const ValueBuffer&) = delete;
  ValueBuffer& operator=(const ValueBuffer&) = delete;

  /// Constructs the type's zero value at `offset`.
  void construct(const ValueType& type, std::uint32_t offset);
  std::byte* at(std::uint32_t offset) { return bytes_.get() + offset; }
  const std::byte* at(std::uint32_t offset) const { return bytes_.get() + offset; }
  std::byte* data() { return bytes_.get(); }
  const std::byte* data() const { return bytes_.get(); }

 private:
  void swap(ValueBuffer& other) noexcept {
    bytes_.swap(other.bytes_);
    constructed_.swap(other.constructed_);
  }

  std::unique_ptr<std::byte[]> bytes_;
  /// What to destroy: the types outlive the buffer (the registry does).
  std::vector<std::pair<const ValueType*, std::uint32_t>> constructed_;
};

/// A pointer into a buffer that the same object owns: it moves with the buffer, and leaves the
/// object moved from null rather than pointing into what that gave away.
template <typename T>
class Into {
 public:
  Into() = default;
  Into(Into&& other) noexcept : pointer_(std::exchange(other.pointer_, nullptr)) {}
  Into& operator=(Into&& other) noexcept {
    pointer_ = std::exchange(other.pointer_, nullptr);
    return *this;
  }
  Into& operator=(T* pointer) {
    pointer_ = pointer;
    return *this;
  }
  operator T*() const { return pointer_; }

 private:
  T* pointer_ = nullptr;
};

struct RunState {
  RunState() = default;
  /// Every buffer sized for `program`, the actuators holding their defaults and the ports their
  /// type's zero value. Allocates; the steps that use it do not.
  explicit RunState(const Program& program);

  TrackedLayout tracked_layout;
  /// The tracked parts, laid out by tracked_layout; the pointers below point into it and move
  /// with it (a reload's swap exchanges two run states whole).
  ValueBuffer tracked;
  Into<double> requested;   // per behaviour
  Into<double> activation;  // per behaviour
  Into<char> active;        // per behaviour: non-zero when active
  Into<bool> actuator_written;
  /// Actuators and writer slots (ports), at the program's offsets.
  Into<std::byte> values;
  // bool vectors are bit-packed; the contexts need addressable flags.
  std::unique_ptr<bool[]> slot_written;
  // Per behaviour.
  std::vector<double> factors;        // two per behaviour: see Inhibitions::recipes()
  std::vector<Behaviour*> instances;  // the behaviours' objects, contiguous for the passes
  std::vector<char> nan_reported;
  // Faults (docs/robustness.md), per behaviour and then per layer: a behaviour whose code threw is
  // replaced in `instances` by an inert one for the step (`suspended`) or for good (`disabled`,
  // which also covers interfaces); `faulted_step` is the step in which each last threw.
  std::vector<char> exception_reported;
  std::vector<std::uint64_t> faulted_step;
  std::vector<char> disabled;
  std::vector<std::uint32_t> suspended;  // capacity: one per behaviour
  // Per writer slot: how many doubles a non-finite check looks at (double, vec2, vec3), and
  // whether a non-finite write was reported.
  std::vector<std::uint8_t> finite_components;
  std::vector<char> non_finite_reported;
  /// Per actuator; empty for one without `safe:`.
  std::vector<ValueBox> safe_values;
  // Scratch for aggregation, sized for the program's largest number of writers.
  std::vector<const void*> mean_values;
  std::vector<double> mean_weights;
};

}  // namespace arbiter

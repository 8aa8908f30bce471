#pragma once
// How well `arbiter run` keeps time: the steady clock it hands the manager, the statistics of
// each step's lateness (period jitter) and duration, kept in fixed histograms so that recording a
// step allocates nothing, and the real-time scheduling of --rt-priority.

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>

#include "arbiter/manager.hpp"

namespace arbiter::cli {

/// A span of wall time for people, in the unit that keeps three figures: "2.41 s", "13.2 ms",
/// "412 µs" (a run flat out is often over in less than a millisecond).
std::string wall_time(double seconds);

/// Seconds since construction on the steady clock.
class SteadyStepClock : public StepClock {
 public:
  SteadyStepClock() : start_(std::chrono::steady_clock::now()) {}
  double now() override {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  std::chrono::steady_clock::time_point start() const { return start_; }

 private:
  std::chrono::steady_clock::time_point start_;
};

/// Percentiles of durations in seconds from a fixed histogram of logarithmic buckets (2 % wide,
/// from 100 ns to 100 s); the maximum is exact. Counts are atomic so that another thread (the
/// live view's) may read while the stepping thread records; a reading is then approximate.
class Histogram {
 public:
  void record(double seconds);
  /// The value below which `fraction` of the recorded ones lie (a bucket's upper edge); 0 when
  /// nothing was recorded.
  double percentile(double fraction) const;
  double max() const { return max_.load(std::memory_order_relaxed); }
  std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::size_t kBuckets = 1048;
  std::array<std::atomic<std::uint32_t>, kBuckets> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<double> max_{0.0};
};

/// The timing of a run: each step's duration and, when paced, how late it started after its
/// deadline (the period's jitter) and how many periods were missed because a step overran.
class RunTiming {
 public:
  explicit RunTiming(double period) : period_(period) {}
  void record_step(double duration) { duration_.record(duration); }
  void record_lateness(double seconds) { lateness_.record(seconds); }
  void record_missed(std::uint64_t periods) {
    overruns_.fetch_add(1, std::memory_order_relaxed);
    missed_.fetch_add(periods, std::memory_order_relaxed);
  }
  const Histogram& duration() const { return duration_; }
  const Histogram& lateness() const { return lateness_; }
  std::uint64_t overruns() const { return overruns_.load(std::memory_order_relaxed); }
  std::uint64_t missed() const { return missed_.load(std::memory_order_relaxed); }
  double period() const { return period_; }

  /// The summary's lines, for people.
  std::string text(bool paced) const;
  /// `{"paced": ..., "period": s, "jitter": {"p50": s, "p99": s, "max": s}, "duration": {...},
  /// "overruns": N, "missed": N}` for the live page.
  std::string json(bool paced) const;

 private:
  double period_;
  Histogram duration_;
  Histogram lateness_;
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> missed_{0};
};

/// Runs the calling thread under SCHED_FIFO at `priority` with all memory locked; false (and
/// `error` says what to grant) when the system does not permit it.
bool enter_realtime(int priority, std::string& error);

}  // namespace arbiter::cli

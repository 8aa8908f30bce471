#include "commands/timing.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cmath>
#include <cstring>

namespace arbiter::cli {

namespace {

constexpr double kSmallest = 1e-7;
const double kLogStep = std::log(1.02);

std::string micros(double seconds) {
  return fmt::format("{:.1f} µs", seconds * 1e6);
}

}  // namespace

std::string wall_time(double seconds) {
  if (seconds >= 1.0) return fmt::format("{:.2f} s", seconds);
  const bool millis = seconds >= 1e-3;
  const double value = millis ? seconds * 1e3 : seconds * 1e6;
  const int decimals = value < 10.0 ? 2 : value < 100.0 ? 1 : 0;
  return fmt::format("{:.{}f} {}", value, decimals, millis ? "ms" : "µs");
}

void Histogram::record(double seconds) {
  std::size_t bucket = 0;
  if (seconds > kSmallest) {
    const double index = std::ceil(std::log(seconds / kSmallest) / kLogStep);
    bucket =
        index >= static_cast<double>(kBuckets - 1) ? kBuckets - 1 : static_cast<std::size_t>(index);
  }
  buckets_[bucket].fetch_add(1, std::memory_order_relaxed);
  count_.fetch_add(1, std::memory_order_relaxed);
  double seen = max_.load(std::memory_order_relaxed);
  while (seconds > seen && !max_.compare_exchange_weak(seen, seconds, std::memory_order_relaxed)) {
  }
}

double Histogram::percentile(double fraction) const {
  const std::uint64_t total = count();
  if (total == 0) return 0.0;
  const auto wanted = static_cast<std::uint64_t>(std::ceil(fraction * static_cast<double>(total)));
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < kBuckets; ++b) {
    seen += buckets_[b].load(std::memory_order_relaxed);
    if (seen >= wanted) {
      // A bucket's upper edge, but never above the largest value seen.
      return std::min(kSmallest * std::exp(kLogStep * static_cast<double>(b)), max());
    }
  }
  return max();
}

std::string RunTiming::text(bool paced) const {
  std::string out = fmt::format(
      "step duration: p50 {}, p99 {}, max {} ({} steps)\n", micros(duration_.percentile(0.5)),
      micros(duration_.percentile(0.99)), micros(duration_.max()), duration_.count());
  if (paced) {
    out += fmt::format(
        "period jitter (start after deadline, period {}): p50 {}, p99 {}, max {}; {} overrun{}, "
        "{} period{} missed\n",
        micros(period_), micros(lateness_.percentile(0.5)), micros(lateness_.percentile(0.99)),
        micros(lateness_.max()), overruns(), overruns() == 1 ? "" : "s", missed(),
        missed() == 1 ? "" : "s");
  }
  return out;
}

std::string RunTiming::json(bool paced) const {
  const auto stats = [](const Histogram& h) {
    return fmt::format(R"({{"p50": {}, "p99": {}, "max": {}, "count": {}}})", h.percentile(0.5),
                       h.percentile(0.99), h.max(), h.count());
  };
  return fmt::format(
      R"({{"paced": {}, "period": {}, "jitter": {}, "duration": {}, "overruns": {}, "missed": {}}})",
      paced ? "true" : "false", period_, stats(lateness_), stats(duration_), overruns(), missed());
}

bool enter_realtime(int priority, std::string& error) {
  sched_param param{};
  param.sched_priority = priority;
  if (const int failed = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); failed != 0) {
    error = fmt::format(
        "--rt-priority {}: cannot run under SCHED_FIFO: {}; grant CAP_SYS_NICE (e.g. `setcap "
        "cap_sys_nice,cap_ipc_lock+ep $(which arbiter)`) or raise RLIMIT_RTPRIO to at least {} "
        "(`ulimit -r`, or rtprio in /etc/security/limits.conf); memory is locked too, which "
        "needs CAP_IPC_LOCK or RLIMIT_MEMLOCK",
        priority, std::strerror(failed), priority);
    return false;
  }
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    const int failed = errno;
    param.sched_priority = 0;
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &param);
    error = fmt::format(
        "--rt-priority {}: cannot lock memory: {}; grant CAP_IPC_LOCK or raise RLIMIT_MEMLOCK "
        "(`ulimit -l unlimited`, or memlock in /etc/security/limits.conf)",
        priority, std::strerror(failed));
    return false;
  }
  return true;
}

}  // namespace arbiter::cli

// The DDS bridge in the step loop: after warm-up, a step that publishes and receives values of
// every type allocates nothing with operator new (the engine's and the bridge's code). Cyclone
// DDS is C and allocates with malloc; this binary counts that too (where no sanitizer owns
// malloc) and reports it. It replaces the global allocation functions (operator new with the
// suite's counter, support/counting_new.cpp; malloc here), so it stands apart.

#include <catch2/catch.hpp>

#include <signal.h>

#include <atomic>
#include <cstdlib>
#include <thread>

#include "counting_new.hpp"
#include "dds_support.hpp"

using arbiter::test::allocations;
using arbiter::test::counting;
using arbiter::test::only_thread;

namespace {
std::atomic<std::size_t> step_mallocs{0};   // on the stepping thread, during step()
std::atomic<std::size_t> step_reallocs{0};  // ... of which realloc
std::atomic<std::size_t> other_mallocs{0};  // on other threads (Cyclone's), meanwhile
}  // namespace

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kCountsMalloc = false;
#else
constexpr bool kCountsMalloc = true;

namespace {
void count_malloc(bool is_realloc = false) {
  if (!counting.load(std::memory_order_relaxed)) return;
  const bool stepping_thread = arbiter::test::counts_here();
  (stepping_thread ? step_mallocs : other_mallocs).fetch_add(1, std::memory_order_relaxed);
  if (is_realloc && stepping_thread) step_reallocs.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

// glibc's own functions, under their internal names: malloc is replaced by forwarding to them.
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* memory, std::size_t size);
void __libc_free(void* memory);

void* malloc(std::size_t size) {
  count_malloc();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  count_malloc();
  return __libc_calloc(count, size);
}
void* realloc(void* memory, std::size_t size) {
  count_malloc(true);
  return __libc_realloc(memory, size);
}
void free(void* memory) {
  __libc_free(memory);
}
}
#endif

using namespace arbiter;
using namespace arbiter::dds_test;
using namespace std::chrono_literals;

namespace {

// The layers of a side: publishes probe.Stamp's values of every type; receives the peer's.
constexpr const char* kSide = R"({link}
  - name: source
    sensors: [{other}_vector]
    actuators: {flag: bool, count: int, level: double, point: vec2, vector: vec3, text: string,
                held: vec3}
    behaviours:
      stamp: probe.Stamp
      hold: {type: dds.HoldVec3, ports: {from: {other}_vector, to: held}}
)";

}  // namespace

TEST_CASE("a step that publishes and receives over DDS allocates nothing with operator new",
          "[dds][alloc]") {
  Setup setup;
  Child peer(arbiter_run(setup.side(kSide, "peer", "host", 100, true), 100000, ""),
             setup.dir.file("peer.out"));
  Manager host(load_file(setup.side(kSide, "host", "peer", 100, false), setup.registry));
  const auto& bridge = bridge_of(host, "link");
  REQUIRE(step_until(
      host, [&] { return written(host, "peer_text"); }, 20s));
  // Warm-up: the first steps after discovery may still grow Cyclone's and the engine's buffers.
  REQUIRE_FALSE(step_until(
      host, [] { return false; }, 500ms));

  const auto taken_before = bridge.stats().samples_taken;
  const auto published_before = bridge.stats().published;
  constexpr int kSteps = 200;
  int steps = 0;
  allocations = 0;
  only_thread = std::this_thread::get_id();
  counting = true;
  REQUIRE(step_until(
      host,
      [&] {
        counting = false;  // the check below allocates; count step() only
        const bool done = ++steps == kSteps;
        counting = !done;
        return done;
      },
      20s));
  counting = false;
  only_thread = std::thread::id();

  const auto taken = bridge.stats().samples_taken - taken_before;
  const auto published = bridge.stats().published - published_before;
  CHECK(published == 6u * kSteps);
  CHECK(taken > 0);
  CHECK(allocations.load() == 0);
  if (kCountsMalloc) {
    WARN("over " << kSteps << " steps (" << published << " samples published, " << taken
                 << " taken): operator new " << allocations.load() << "; malloc in step() "
                 << step_mallocs.load() << " (" << static_cast<double>(step_mallocs.load()) / kSteps
                 << " per step; realloc " << step_reallocs.load()
                 << "), on Cyclone DDS's threads meanwhile " << other_mallocs.load());
  }
  CHECK(peer.stop(SIGTERM, 20s));
}

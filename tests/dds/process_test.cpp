// Two processes on loopback: `arbiter run` peers and a manager stepped by the test, each at its own
// rate, exchanging values of every type; one side killed and restarted while the other runs.

#include <catch2/catch.hpp>

#include <signal.h>

#include <cmath>
#include <memory>
#include <regex>
#include <string>
#include <thread>

#include "dds_support.hpp"
#include "probe.hpp"

using namespace arbiter;
using namespace arbiter::dds_test;
using namespace std::chrono_literals;
using nlohmann::json;

namespace {

// The layers of a side: probe.Stamp writes the values its link layer publishes.
constexpr const char* kSide = R"(  - name: source
    actuators: {flag: bool, count: int, level: double, point: vec2, vector: vec3, text: string}
    behaviours: {stamp: probe.Stamp}
{link}
)";

const char* const kNames[] = {"flag", "count", "level", "point", "vector", "text"};

struct Sides : Setup {
  std::unique_ptr<Child> start(const std::string& config, const std::string& name,
                               std::uint64_t steps = 100000) {
    return std::make_unique<Child>(arbiter_run(config, steps, dir.file(name + ".jsonl")),
                                   dir.file(name + ".out"));
  }
};

/// Checks that the values `prefix`_* hold what probe.Stamp writes in some step, with their types.
void check_stamp_values(const json& flag, const json& count, const json& level, const json& point,
                        const json& vector, const json& text) {
  REQUIRE(count.is_number_integer());
  const auto n = count.get<std::int64_t>();
  CHECK(n >= 1);
  CHECK(flag.is_boolean());
  REQUIRE(level.is_number_float());
  CHECK(std::abs(level.get<double>() * 2.0 - std::round(level.get<double>() * 2.0)) < 1e-9);
  REQUIRE(point.is_array());
  REQUIRE(point.size() == 2);
  CHECK(point[0].get<double>() == -point[1].get<double>());
  REQUIRE(vector.is_array());
  REQUIRE(vector.size() == 3);
  CHECK(vector[1].get<double>() == 2.0 * vector[0].get<double>());
  CHECK(vector[2].get<double>() == -0.5);
  REQUIRE(text.is_string());
  std::smatch match;
  const std::string words = text.get<std::string>();
  REQUIRE(std::regex_match(words, match, std::regex("step ([0-9]+)")));
  // Each topic's newest sample is taken on its own: between two takes the sender may have
  // published its next step.
  CHECK(std::abs(std::stoll(match[1]) - n) <= 2);
  CHECK(std::abs(vector[0].get<double>() - static_cast<double>(n)) <= 2.0);
}

void check_host_view(const Manager& host) {
  check_stamp_values(value_of(host, "peer_flag"), value_of(host, "peer_count"),
                     value_of(host, "peer_level"), value_of(host, "peer_point"),
                     value_of(host, "peer_vector"), value_of(host, "peer_text"));
}

bool all_written(const Manager& manager, const std::string& prefix) {
  for (const char* name : kNames) {
    if (!written(manager, prefix + name)) return false;
  }
  return true;
}

/// The value and written flag of actuator `name` in each step of a trace.
std::vector<std::pair<json, bool>> series(const std::vector<json>& trace, const std::string& name) {
  std::vector<std::pair<json, bool>> out;
  for (const auto& step : trace) {
    const auto& actuator = step.at("actuators").at(name);
    out.emplace_back(actuator.at("value"), actuator.at("written").get<bool>());
  }
  return out;
}

}  // namespace

TEST_CASE("two processes at different rates exchange values of every type", "[dds][process]") {
  Sides sides;
  // The peer steps at 50 Hz, the test's manager at 20 Hz.
  auto peer = sides.start(sides.side(kSide, "peer", "host", 50, true), "peer");
  Manager host(load_file(sides.side(kSide, "host", "peer", 20, false), sides.registry));
  REQUIRE(step_until(
      host, [&] { return all_written(host, "peer_"); }, 20s));
  check_host_view(host);

  // Two seconds of the host's steps: each one sees a new value of the peer's, which steps 2.5
  // times as often.
  std::vector<std::int64_t> counts;
  int fresh = 0;
  const double started = monotonic_seconds();
  REQUIRE_FALSE(step_until(
      host,
      [&] {
        counts.push_back(value_of(host, "peer_count").get<std::int64_t>());
        fresh += written(host, "peer_count") ? 1 : 0;
        return false;
      },
      2s));
  const double elapsed = monotonic_seconds() - started;
  check_host_view(host);
  REQUIRE(counts.size() >= 10);
  const double peer_rate = static_cast<double>(counts.back() - counts.front()) / elapsed;
  const double per_host_step =
      static_cast<double>(counts.back() - counts.front()) / static_cast<double>(counts.size() - 1);
  INFO("peer steps per second " << peer_rate << ", per host step " << per_host_step
                                << ", host steps " << counts.size() << " with " << fresh
                                << " fresh");
  // The peer is paced at 50 Hz but falls behind when other work shares the cores (21 steps a
  // second were seen under a parallel build): what must hold is that it steps more often than the
  // host, never faster than its rate, and that its values keep arriving.
  CHECK(peer_rate > 20.0);
  CHECK(peer_rate < 70.0);
  CHECK(per_host_step > 1.0);
  CHECK(fresh * 3 >= static_cast<int>(counts.size()));

  peer->signal(SIGTERM);
  check_exit(*peer, 20s);

  // The peer's trace: the host's values, each at 20 Hz, so written in about 2 steps of 5.
  const auto trace = read_trace(sides.dir.file("peer.jsonl"));
  const auto host_counts = series(trace, "host_count");
  std::size_t first = host_counts.size();
  std::size_t last = 0;
  for (std::size_t i = 0; i < host_counts.size(); ++i) {
    if (!host_counts[i].second) continue;
    first = std::min(first, i);
    last = i;
  }
  REQUIRE(first < last);
  int written_steps = 0;
  for (std::size_t i = first; i <= last; ++i) written_steps += host_counts[i].second ? 1 : 0;
  const double share = static_cast<double>(written_steps) / static_cast<double>(last - first + 1);
  INFO("the host's count was written in " << written_steps << " of " << (last - first + 1)
                                          << " peer steps");
  CHECK(share > 0.2);
  CHECK(share < 0.7);
  const auto& final_step = trace[last].at("actuators");
  check_stamp_values(
      final_step.at("host_flag").at("value"), final_step.at("host_count").at("value"),
      final_step.at("host_level").at("value"), final_step.at("host_point").at("value"),
      final_step.at("host_vector").at("value"), final_step.at("host_text").at("value"));
}

TEST_CASE("a killed peer leaves its values stale until its restart, and the other side runs on",
          "[dds][process]") {
  Sides sides;
  const std::string peer_config = sides.side(kSide, "peer", "host", 50, true);
  auto peer = sides.start(peer_config, "peer");
  Manager host(load_file(sides.side(kSide, "host", "peer", 20, false), sides.registry));
  // Long enough that the restarted peer's count starts below the killed one's.
  REQUIRE(step_until(
      host, [&] { return written(host, "peer_count") && value_of(host, "peer_count") >= 100; },
      20s));

  peer->signal(SIGKILL);
  REQUIRE(peer->wait(10s));
  host.step();  // takes what was on its way
  json last[6];
  for (int i = 0; i < 6; ++i) last[i] = value_of(host, std::string("peer_") + kNames[i]);
  const auto before = host.steps();
  bool all_stale = true;
  bool values_held = true;
  REQUIRE_FALSE(step_until(
      host,
      [&] {
        for (int i = 0; i < 6; ++i) {
          const std::string name = std::string("peer_") + kNames[i];
          all_stale = all_stale && !written(host, name);
          values_held = values_held && value_of(host, name) == last[i];
        }
        return false;
      },
      1s));
  CHECK(host.steps() - before >= 10);  // the host kept stepping
  CHECK(all_stale);
  CHECK(values_held);

  const auto killed_at = last[1].get<std::int64_t>();
  peer = sides.start(peer_config, "peer_again");
  REQUIRE(step_until(
      host, [&] { return written(host, "peer_count") && value_of(host, "peer_count") < killed_at; },
      20s));
  REQUIRE(step_until(
      host, [&] { return all_written(host, "peer_"); }, 10s));
  check_host_view(host);
}

TEST_CASE(
    "an arbiter run process keeps stepping on stale values while its peer is killed and "
    "restarted",
    "[dds][process]") {
  Sides sides;
  // The survivor, an `arbiter run` at 50 Hz for 7.5 s; the victim at 20 Hz, killed after 3 s
  // and started again 1.5 s later.
  constexpr std::size_t kSurvivorSteps = 375;
  auto survivor =
      sides.start(sides.side(kSide, "peer", "host", 50, true), "survivor", kSurvivorSteps);
  const std::string victim_config = sides.side(kSide, "host", "peer", 20, true);
  auto victim = sides.start(victim_config, "victim");
  std::this_thread::sleep_for(3s);
  victim->signal(SIGKILL);
  REQUIRE(victim->wait(10s));
  std::this_thread::sleep_for(1500ms);
  victim = sides.start(victim_config, "victim_again");
  check_exit(*survivor, 30s);
  CHECK(victim->stop(SIGTERM, 20s));

  const auto trace = read_trace(sides.dir.file("survivor.jsonl"));
  CHECK(trace.size() == kSurvivorSteps);
  // Fresh values, then the longest run of unwritten steps, holding the last value, then fresh
  // values of the restarted victim, whose count starts again.
  const auto counts = series(trace, "host_count");
  std::size_t first_fresh = 0;
  while (first_fresh < counts.size() && !counts[first_fresh].second) ++first_fresh;
  REQUIRE(first_fresh < counts.size());
  std::size_t run_begin = 0;
  std::size_t run_length = 0;
  for (std::size_t i = first_fresh; i < counts.size();) {
    std::size_t j = i;
    while (j < counts.size() && !counts[j].second) ++j;
    if (j - i > run_length) {
      run_begin = i;
      run_length = j - i;
    }
    i = j + 1;
  }
  INFO("stale for " << run_length << " steps from step " << run_begin + 1);
  CHECK(run_length >= 40);  // 1.5 s at 50 Hz, and more: the restarted victim needs time to start
  const json held = counts[run_begin - 1].first;
  for (std::size_t i = run_begin; i < run_begin + run_length; ++i) {
    CHECK(counts[i].first == held);
  }
  const std::size_t after = run_begin + run_length;
  REQUIRE(after < counts.size());
  CHECK(counts[after].first.get<std::int64_t>() < held.get<std::int64_t>());
  std::size_t fresh_after = 0;
  for (std::size_t i = after; i < counts.size(); ++i) fresh_after += counts[i].second ? 1 : 0;
  CHECK(fresh_after >= 5);
}

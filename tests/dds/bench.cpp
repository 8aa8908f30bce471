// arbiter_dds_bench: latency and throughput of dds.Bridge between two processes on loopback
// (figures in docs/performance.md). The sender is this program run again as a child (`--sender
// CONFIG SECONDS`); the receiver is stepped here.
//
//   latency:    the sender writes the monotonic clock into an actuator and publishes it in its
//               output pass; the receiver's behaviour reads it in the step in which it becomes
//               visible (the input pass of the receiver's next step) and subtracts it from the
//               clock. So it is publish to next-step visibility: transport plus the wait for the
//               receiver's next step.
//   throughput: N double actuators published every step at rate R (N × R values per second);
//               what arrives, and what a step costs on either side.
//
// Usage: arbiter_dds_bench [--quick] [--repetitions N]   (--quick: a short smoke run, for the
// test suite; N runs of each scenario, of which the median of each figure is printed, with the
// range of the latency medians)

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "arbiter/init_context.hpp"
#include "dds_support.hpp"
#include "probe.hpp"
#include "test_support.hpp"

using namespace arbiter;
using namespace arbiter::dds_test;
using Clock = std::chrono::steady_clock;

namespace {

/// Records, in each step in which its `time` sensor was written, how old that time is.
class Latency final : public Behaviour {
 public:
  void init(BehaviourInitContext&) override { ages_.reserve(1 << 20); }
  void update(const StepContext& ctx) override {
    if (recording && ctx.written(time_) && ages_.size() < ages_.capacity()) {
      ages_.push_back(monotonic_seconds() - ctx.read(time_));
    }
  }
  double activation(const StepContext& /*ctx*/) override { return 0.0; }

  bool recording = false;
  const std::vector<double>& ages() const { return ages_; }

 private:
  friend Registry bench_registry();

  Input<double> time_;
  std::vector<double> ages_;
};

Registry bench_registry() {
  Registry registry = make_registry();
  registry.set_origin("bench");
  registry.add_behaviour<Latency>("bench.Latency").port("time", &Latency::time_);
  return registry;
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(index, values.size() - 1)];
}

struct Scenario {
  int values = 1;            // double actuators besides `time`
  double sender_hz = 100;    // 0: as fast as it can
  double receiver_hz = 100;  // 0: as fast as it can
  double seconds = 2.0;
};

std::string values_list(int count, const char* format) {
  std::string out;
  for (int i = 0; i < count; ++i) {
    out += fmt::format(fmt::runtime(format), i);
  }
  return out;
}

// Filled in by scenario_values().
constexpr const char* kSender = R"(arbiter: 1
name: sender
rate_hz: {rate}
layers:
  - name: source
    actuators:
      time: double
{actuators}    behaviours:
      stamp: probe.Stamp
      values:
        type: scripted
        params:
          writes:
{writes}  - name: out
    interface: dds.Bridge
    params: {domain_id: {domain}, cyclone_config: {xml}}
    sensors: [time{sensors}]
)";

constexpr const char* kReceiver = R"(arbiter: 1
name: receiver
rate_hz: {rate}
layers:
  - name: in
    interface: dds.Bridge
    params: {domain_id: {domain}, cyclone_config: {xml}}
    actuators:
      time: double
{actuators}  - name: measure
    sensors: [time]
    actuators: {unused: double}
    behaviours: {latency: bench.Latency}
)";

/// A side's {rate} (`hz`, or as fast as 1 kHz when 0) and the scenario's extra values: their
/// {actuators}, the {writes} that give them values, and their names as further {sensors}.
Values scenario_values(const Scenario& scenario, double hz) {
  return {{"rate", fmt::format("{}", hz > 0 ? hz : 1000.0)},
          {"actuators", values_list(scenario.values, "      v{}: double\n")},
          {"writes", values_list(scenario.values, "            v{}: 1.5\n")},
          {"sensors", values_list(scenario.values, ", v{}")}};
}

/// Steps `manager` for `seconds` at `hz` (0: back to back); returns each step's duration (µs).
std::vector<double> run_steps(Manager& manager, double hz, double seconds) {
  std::vector<double> durations;
  durations.reserve(static_cast<std::size_t>(seconds * (hz > 0 ? hz : 100000.0)) + 16);
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(hz > 0 ? 1.0 / hz : 0.0));
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(seconds));
  auto next = Clock::now();
  while (Clock::now() < end) {
    const auto start = Clock::now();
    manager.step();
    const double micros = std::chrono::duration<double, std::micro>(Clock::now() - start).count();
    if (durations.size() < durations.capacity()) durations.push_back(micros);
    if (hz > 0) {
      next += period;
      std::this_thread::sleep_until(next);
    }
  }
  return durations;
}

/// The child: steps the sender for `seconds`, then prints its figures as one line.
int run_sender(const std::string& config, double seconds, bool unpaced) {
  Registry registry = bench_registry();
  Manager manager(load_file(config, registry));
  const auto& bridge = bridge_of(manager, "out");
  // Values written before the receiver is there would be lost: wait for it.
  if (!bridge.wait_for_peers(std::chrono::seconds(30))) {
    std::cerr << "sender: no receiver\n";
    return 1;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto durations = run_steps(manager, unpaced ? 0.0 : manager.program().rate_hz, seconds);
  std::cout << fmt::format(
      "steps {} published {} failed {} p50 {:.2f} p99 {:.2f} max {:.2f}\n", durations.size(),
      bridge.stats().published, bridge.stats().publish_failures, percentile(durations, 0.5),
      percentile(durations, 0.99), *std::max_element(durations.begin(), durations.end()));
  return 0;
}

struct SenderFigures {
  double steps = 0, published = 0, failed = 0, p50 = 0, p99 = 0, max = 0;
};

SenderFigures parse_sender(const std::string& text) {
  SenderFigures figures;
  std::istringstream in(text);
  std::string word;
  while (in >> word) {
    double* field = word == "steps"       ? &figures.steps
                    : word == "published" ? &figures.published
                    : word == "failed"    ? &figures.failed
                    : word == "p50"       ? &figures.p50
                    : word == "p99"       ? &figures.p99
                    : word == "max"       ? &figures.max
                                          : nullptr;
    if (field != nullptr) in >> *field;
  }
  return figures;
}

std::string rate_text(double hz) {
  return hz > 0 ? fmt::format("{:g} Hz", hz) : std::string("unpaced");
}

/// One run of a scenario.
struct Row {
  double sent_per_s = 0, taken_per_s = 0;
  double latency_p50 = 0, latency_p99 = 0, latency_max = 0;  // µs
  double sender_p50 = 0, sender_p99 = 0, receiver_p50 = 0, receiver_p99 = 0;
};

std::optional<Row> run_scenario(const Scenario& scenario, const std::string& self) {
  Setup setup(bench_registry());
  const std::string sender_file =
      setup.write("sender.yaml", kSender, scenario_values(scenario, scenario.sender_hz));
  Manager receiver(
      setup.load("receiver.yaml", kReceiver, scenario_values(scenario, scenario.receiver_hz)));
  auto& latency = test::instance<Latency>(receiver.program(), "measure", "latency");
  const auto& bridge = bridge_of(receiver, "in");

  // The sender runs a little longer than the receiver measures, so that it is sending all along.
  const double sender_seconds = scenario.seconds + 0.6;
  Child sender({self, "--sender", sender_file, fmt::format("{}", sender_seconds),
                scenario.sender_hz > 0 ? "paced" : "unpaced"},
               setup.dir.file("sender.out"));
  // Step until the first value arrives, then measure.
  if (!step_until(
          receiver, [&] { return bridge.stats().values_written > 0; }, std::chrono::seconds(60))) {
    std::cerr << "no data from the sender\n" << sender.output();
    return std::nullopt;
  }
  run_steps(receiver, scenario.receiver_hz, 0.2);
  const auto before = bridge.stats();
  latency.recording = true;
  const auto durations = run_steps(receiver, scenario.receiver_hz, scenario.seconds);
  latency.recording = false;
  const auto after = bridge.stats();
  sender.wait(std::chrono::seconds(60));
  const SenderFigures sent = parse_sender(sender.output());

  std::vector<double> ages_us;
  for (double age : latency.ages()) ages_us.push_back(age * 1e6);
  Row row;
  row.sent_per_s = sent.published / sender_seconds;
  row.taken_per_s =
      static_cast<double>(after.samples_taken - before.samples_taken) / scenario.seconds;
  row.latency_p50 = percentile(ages_us, 0.5);
  row.latency_p99 = percentile(ages_us, 0.99);
  row.latency_max = ages_us.empty() ? 0.0 : *std::max_element(ages_us.begin(), ages_us.end());
  row.sender_p50 = sent.p50;
  row.sender_p99 = sent.p99;
  row.receiver_p50 = percentile(durations, 0.5);
  row.receiver_p99 = percentile(durations, 0.99);
  return row;
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  double one = 0, five = 0, fifteen = 0;
  in >> one >> five >> fifteen;
  return fmt::format("{:.2f} {:.2f} {:.2f}", one, five, fifteen);
}

/// The median of each figure over the repetitions, and the range of the latency medians.
void print_row(const Scenario& scenario, const std::vector<Row>& rows) {
  const auto median = [&](double Row::*field) {
    std::vector<double> values;
    for (const auto& row : rows) values.push_back(row.*field);
    return percentile(values, 0.5);
  };
  double lowest = rows.front().latency_p50;
  double highest = lowest;
  for (const auto& row : rows) {
    lowest = std::min(lowest, row.latency_p50);
    highest = std::max(highest, row.latency_p50);
  }
  std::cout << fmt::format(
      "| {} | {} | {} | {:.0f} | {:.0f} | {:.0f} ({:.0f}-{:.0f}) | {:.0f} | {:.0f} | {:.1f} / "
      "{:.1f} | {:.1f} / {:.1f} |\n",
      scenario.values + 1, rate_text(scenario.sender_hz), rate_text(scenario.receiver_hz),
      median(&Row::sent_per_s), median(&Row::taken_per_s), median(&Row::latency_p50), lowest,
      highest, median(&Row::latency_p99), median(&Row::latency_max), median(&Row::sender_p50),
      median(&Row::sender_p99), median(&Row::receiver_p50), median(&Row::receiver_p99));
  std::cout.flush();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 5 && std::strcmp(argv[1], "--sender") == 0) {
    return run_sender(argv[2], std::stod(argv[3]), std::strcmp(argv[4], "unpaced") == 0);
  }
  bool quick = false;
  int repetitions = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--repetitions") == 0 && i + 1 < argc &&
               std::atoi(argv[i + 1]) > 0) {
      repetitions = std::atoi(argv[++i]);
    } else {
      std::cerr << "usage: arbiter_dds_bench [--quick] [--repetitions N]\n";
      return 2;
    }
  }
  const std::string self = "/proc/self/exe";
  char path[4096];
  const auto length = readlink(self.c_str(), path, sizeof path - 1);
  if (length <= 0) return 1;
  path[length] = '\0';

  std::cout << fmt::format("{} repetition(s) of each scenario; load average {}\n\n", repetitions,
                           load_average());
  std::cout << "| topics | sender | receiver | values/s sent | samples/s taken | latency p50 "
               "(µs) (range) | p99 (µs) | max (µs) | sender step p50 / p99 (µs) | receiver step "
               "p50 / p99 (µs) |\n"
               "|---|---|---|---|---|---|---|---|---|---|\n";
  // {values besides time, sender Hz, receiver Hz (0: back to back), seconds}
  static const Scenario kQuick[] = {{0, 100, 100, 0.5}, {9, 100, 100, 0.5}};
  static const Scenario kFull[] = {
      {0, 100, 100, 3.0},   {0, 100, 1000, 3.0},  {0, 100, 0, 3.0},    {0, 1000, 1000, 3.0},
      {9, 100, 100, 3.0},   {9, 1000, 1000, 3.0}, {99, 100, 100, 3.0}, {99, 1000, 1000, 3.0},
      {999, 100, 100, 3.0}, {9, 0, 0, 3.0},
  };
  const Scenario* begin = quick ? std::begin(kQuick) : std::begin(kFull);
  const Scenario* end = quick ? std::end(kQuick) : std::end(kFull);
  int failures = 0;
  for (const Scenario* scenario = begin; scenario != end; ++scenario) {
    std::vector<Row> rows;
    for (int r = 0; r < repetitions; ++r) {
      if (auto row = run_scenario(*scenario, path)) rows.push_back(*row);
    }
    if (rows.empty()) {
      ++failures;
      continue;
    }
    print_row(*scenario, rows);
  }
  std::cout << fmt::format("\nload average {}\n", load_average());
  return failures == 0 ? 0 : 1;
}

// arbiter_bench: the benchmarks, with the targets of docs/performance.md checked at the end; a
// config generator; and a measurement of any config file.
//
//   arbiter_bench [benchmark flags] [--no-target-check]
//   arbiter_bench --generate GRAPH --behaviours N [--inhibitions M] [--seed S] [--json] ...
//   arbiter_bench --measure FILE [--plugin-path DIR]... [--steps N]

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "arbiter/manager.hpp"
#include "benchmarks.hpp"
#include "generator.hpp"
#include "lsp_benchmarks.hpp"
#include "studio_benchmarks.hpp"
#if ARBITER_BENCH_PYTHON
#include "python_benchmarks.hpp"
#endif
#include "support.hpp"

namespace {

using arbiter::bench::Graph;

constexpr const char* kUsage = R"(usage:
  arbiter_bench [--benchmark_filter=REGEX ...] [--no-target-check]
      runs the benchmarks (Google Benchmark flags apply) and checks the targets that ran
  arbiter_bench --generate GRAPH --behaviours N [--inhibitions M] [--seed S] [--json]
                [--class CLASS] [--out FILE]
      writes a config: GRAPH is none, chain, dag or layers (see docs/performance.md); CLASS is
      the behaviours' class, scripted (default: runs in the CLI too) or bench.Trivial
  arbiter_bench --measure FILE [--plugin-path DIR]... [--steps N]
      loads FILE stage by stage, then steps it: load times, memory and step cost
)";

/// The result of each benchmark by name: with repetitions, the fastest (on a shared machine
/// interference only ever adds time), else the one run. Everything goes on to the display
/// reporter `--benchmark_format` asks for, so the output is Google Benchmark's own.
class Collector : public benchmark::BenchmarkReporter {
 public:
  struct Result {
    double cpu_time = 0;   // in the benchmark's time unit
    double real_time = 0;  // likewise
    std::map<std::string, double> counters;
  };

  Collector() : display_(benchmark::CreateDefaultDisplayReporter()) {}

  bool ReportContext(const Context& context) override { return display_->ReportContext(context); }

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      if (run.error_occurred) continue;
      const bool fastest = run.run_type == Run::RT_Aggregate && run.aggregate_name == "min";
      if (run.run_type == Run::RT_Aggregate && !fastest) continue;
      // Without "/iterations:1" and the like: the benchmark and its argument.
      const std::string name = run.run_name.args.empty()
                                   ? run.run_name.function_name
                                   : run.run_name.function_name + "/" + run.run_name.args;
      if (!fastest && fastest_names_.count(name) != 0) continue;
      if (fastest) fastest_names_.insert({name, true});
      Result& result = results[name];
      result.cpu_time = run.GetAdjustedCPUTime();
      result.real_time = run.GetAdjustedRealTime();
      for (const auto& [counter, value] : run.counters) result.counters[counter] = value.value;
    }
    display_->ReportRuns(runs);
  }

  void Finalize() override { display_->Finalize(); }

  /// True when the display is the console table, which the target table may follow on stdout;
  /// JSON and CSV output stays parseable.
  bool console() const {
    return dynamic_cast<const benchmark::ConsoleReporter*>(display_.get()) != nullptr;
  }

  std::map<std::string, Result> results;

 private:
  std::unique_ptr<benchmark::BenchmarkReporter> display_;
  std::map<std::string, bool> fastest_names_;
};

/// Prints each target whose benchmarks ran; returns how many were missed.
int check_targets(const Collector& collector, std::ostream& out) {
  const auto& results = collector.results;
  const auto counter = [&](const std::string& name,
                           const std::string& key) -> std::optional<double> {
    const auto found = results.find(name);
    if (found == results.end()) return std::nullopt;
    const auto value = found->second.counters.find(key);
    if (value == found->second.counters.end()) return std::nullopt;
    return value->second;
  };
  int missed = 0;
  bool any = false;
  const auto check = [&](const std::string& what, std::optional<double> value, double limit,
                         const char* unit) {
    if (!value) return;
    if (!any) out << fmt::format("\n{:<52} {:>10} {:>12}\n", "target", "measured", "limit");
    any = true;
    const bool ok = *value <= limit;
    missed += ok ? 0 : 1;
    out << fmt::format("{:<52} {:>10.3g} {:>9} {:<3} {}\n", what, *value,
                       fmt::format("<= {:g}", limit), unit, ok ? "ok" : "MISSED");
  };
  for (const char* graph : {"none", "chain", "dag", "layers"}) {
    const std::string base = fmt::format("step/{}/", graph);
    check(base + "1000: ns per behaviour per step", counter(base + "1000", "ns_per_behaviour"),
          10.0, "ns");
    const auto small = counter(base + "1000", "ns_per_behaviour");
    const auto large = counter(base + "10000", "ns_per_behaviour");
    if (small && large) {
      check(base + "10000 vs 1000: per-behaviour cost ratio", *large / *small, 2.0, "x");
    }
  }
  check("scl/replan5: ns per step", counter("scl/replan5", "ns_per_step"), 50.0, "ns");
  for (const auto& [n, limit] : {std::pair<int, double>{1000, 20.0}, {10000, 200.0}}) {
    const auto found = results.find(fmt::format("load/total/{}", n));
    if (found != results.end()) {
      check(fmt::format("load/total/{}: load, validate and compile", n), found->second.cpu_time,
            limit, "ms");
    }
  }
  for (const auto& [n, limit] : {std::pair<int, double>{200, 20.0}, {1000, 100.0}}) {
    const auto found = results.find(fmt::format("lsp/change/{}", n));
    if (found != results.end()) {
      check(fmt::format("lsp/change/{}: diagnostics after an edit", n), found->second.cpu_time,
            limit, "ms");
    }
  }
  // Each operation alone, and all of them in turn (studio/edit/<N>, per operation), meet it.
  for (const auto& [name, result] : results) {
    if (name.rfind("studio/edit/", 0) != 0) continue;
    const auto size = name.substr(name.rfind('/') + 1);
    const double limit = size == "200" ? 30.0 : size == "1000" ? 150.0 : 0.0;
    const auto operations = result.counters.find("operations");
    const double per_operation = operations == result.counters.end()
                                     ? result.cpu_time
                                     : result.cpu_time / operations->second;
    if (limit > 0) check(name + ": an operation", per_operation, limit, "ms");
  }
  for (const char* graph : {"none", "chain", "dag", "layers"}) {
    for (int n : {1000, 10000}) {
      const auto name = fmt::format("memory/{}/{}", graph, n);
      check(name + ": heap bytes per behaviour", counter(name, "bytes_per_behaviour"), 500.0, "B");
    }
  }
  check("record/layers/1000: recording overhead per step",
        counter("record/layers/1000", "overhead"), 0.10, "x");
  check("record/soccer: recording overhead per step", counter("record/soccer", "overhead"), 0.10,
        "x");
  check("record/soccer: bytes per step", counter("record/soccer", "bytes_per_step"), 200.0, "B");
  check("python/step/1000: from Python against C++", counter("python/step/1000", "ratio"), 1.1,
        "x");
  check("python/behaviour: activation + execute in Python", counter("python/behaviour", "call_ns"),
        1000.0, "ns");
  if (const auto found = results.find("python/to_dataframe/100000"); found != results.end()) {
    check("python/to_dataframe/100000: a trace into pandas", found->second.real_time, 2.0, "s");
  }
  if (any) {
    out << (missed == 0 ? "every target that ran is met\n"
                        : fmt::format("{} target(s) missed\n", missed));
  }
  return missed;
}

struct Arguments {
  std::vector<std::string> rest;
  std::optional<std::string> value(const std::string& flag) {
    for (std::size_t i = 0; i < rest.size(); ++i) {
      if (rest[i] == flag && i + 1 < rest.size()) {
        std::string found = rest[i + 1];
        rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(i),
                   rest.begin() + static_cast<std::ptrdiff_t>(i) + 2);
        return found;
      }
      if (rest[i].rfind(flag + "=", 0) == 0) {
        std::string found = rest[i].substr(flag.size() + 1);
        rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(i));
        return found;
      }
    }
    return std::nullopt;
  }
  bool flag(const std::string& name) {
    for (std::size_t i = 0; i < rest.size(); ++i) {
      if (rest[i] == name) {
        rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(i));
        return true;
      }
    }
    return false;
  }
};

std::size_t number(const std::optional<std::string>& text, std::size_t fallback) {
  if (!text) return fallback;
  char* end = nullptr;
  const auto value = std::strtoull(text->c_str(), &end, 10);
  if (end == text->c_str() || *end != '\0') {
    throw std::invalid_argument(fmt::format("'{}' is not a number", *text));
  }
  return static_cast<std::size_t>(value);
}

int generate(Arguments& args, const std::string& graph_name) {
  const auto graph = arbiter::bench::graph_from_string(graph_name);
  if (!graph) {
    std::cerr << fmt::format("unknown graph '{}': none, chain, dag or layers\n", graph_name);
    return 2;
  }
  arbiter::bench::GeneratorOptions options;
  options.graph = *graph;
  options.behaviours = number(args.value("--behaviours"), 1000);
  options.inhibitions = number(args.value("--inhibitions"), 0);
  options.seed = number(args.value("--seed"), 1);
  options.json = args.flag("--json");
  if (auto cls = args.value("--class")) options.behaviour_class = *cls;
  const auto out = args.value("--out");
  if (!args.rest.empty()) {
    std::cerr << "unexpected argument '" << args.rest.front() << "'\n" << kUsage;
    return 2;
  }
  const std::string text = arbiter::bench::generate_config(options);
  if (!out) {
    std::cout << text;
    return 0;
  }
  std::ofstream file(*out);
  file << text;
  if (!file) {
    std::cerr << "cannot write " << *out << "\n";
    return 1;
  }
  return 0;
}

int measure(Arguments& args, const std::string& path) {
  arbiter::LoadOptions options;
  while (auto dir = args.value("--plugin-path")) options.plugins.path.push_back(*dir);
  const std::size_t steps = number(args.value("--steps"), 0);
  if (!args.rest.empty()) {
    std::cerr << "unexpected argument '" << args.rest.front() << "'\n" << kUsage;
    return 2;
  }
  arbiter::Registry registry = arbiter::bench::make_registry();
  const std::size_t heap_before = arbiter::bench::heap_in_use();
  arbiter::bench::LoadTimes times;
  auto program = arbiter::bench::load_timed(path, registry, options, times);
  if (!program) return 1;
  const std::size_t behaviours = program->behaviours.size();
  const std::size_t declared = program->inhibitions.declared_inhibitions().size();
  const std::size_t closure = program->inhibitions.size();
  arbiter::Manager manager(
      std::move(*program),
      std::make_shared<spdlog::logger>("measure", std::make_shared<spdlog::sinks::null_sink_mt>()));
  manager.step();
  const std::size_t heap_after = arbiter::bench::heap_in_use();

  // Without --steps: as many steps as fit in about a second.
  std::size_t done = 0;
  const auto start = std::chrono::steady_clock::now();
  double elapsed_ms = 0;
  while (steps != 0 ? done < steps : elapsed_ms < 1000.0) {
    for (int i = 0; i < 16 && (steps == 0 || done < steps); ++i, ++done) manager.step();
    elapsed_ms = arbiter::bench::milliseconds_since(start);
  }
  const double ns_per_step = done == 0 ? 0.0 : elapsed_ms * 1e6 / static_cast<double>(done);

  std::cout << fmt::format("{}: {} behaviours, {} layers, {} state machines\n", path, behaviours,
                           manager.program().layers.size(), manager.program().controllers.size());
  std::cout << fmt::format("inhibitions: {} declared, {} after closure\n", declared, closure);
  std::cout << fmt::format(
      "load: {:.2f} ms = parse {:.2f} + validate {:.2f} + compile {:.2f} (steady clock)\n",
      times.total_ms(), times.parse_ms, times.validate_ms, times.compile_ms);
  if (heap_after != 0) {
    const double bytes = static_cast<double>(heap_after - heap_before);
    std::cout << fmt::format(
        "heap held by the manager and its program: {:.0f} bytes{}\n", bytes,
        behaviours == 0
            ? std::string()
            : fmt::format(" ({:.0f} per behaviour)", bytes / static_cast<double>(behaviours)));
  }
  std::cout << fmt::format("step: {:.1f} ns over {} steps{}\n", ns_per_step, done,
                           behaviours == 0
                               ? std::string()
                               : fmt::format(" ({:.2f} ns per behaviour)",
                                             ns_per_step / static_cast<double>(behaviours)));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  for (int i = 1; i < argc; ++i) args.rest.emplace_back(argv[i]);
  try {
    if (args.flag("--help") || args.flag("-h")) {
      std::cout << kUsage;
      benchmark::PrintDefaultHelp();
      return 0;
    }
    if (const auto graph = args.value("--generate")) return generate(args, *graph);
    if (const auto path = args.value("--measure")) return measure(args, *path);
  } catch (const std::exception& error) {
    std::cerr << error.what() << "\n" << kUsage;
    return 2;
  }
  const bool check = !args.flag("--no-target-check");

  std::vector<char*> forwarded{argv[0]};
  for (auto& arg : args.rest) forwarded.push_back(arg.data());
  int count = static_cast<int>(forwarded.size());
  benchmark::Initialize(&count, forwarded.data());
  if (benchmark::ReportUnrecognizedArguments(count, forwarded.data())) return 2;
  arbiter::bench::register_benchmarks();
  arbiter::bench::register_lsp_benchmarks();
  arbiter::bench::register_studio_benchmarks();
#if ARBITER_BENCH_PYTHON
  arbiter::bench::register_python_benchmarks();
#endif
  Collector collector;
  benchmark::RunSpecifiedBenchmarks(&collector);
  benchmark::Shutdown();
  // With --benchmark_format=json or csv the targets go to stderr, so stdout stays parseable.
  const int missed = check_targets(collector, collector.console() ? std::cout : std::cerr);
  return check && missed > 0 ? 1 : 0;
}

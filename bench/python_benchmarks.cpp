// The Python module's benchmarks (docs/python.md), run in an interpreter embedded in
// arbiter_bench that imports the module from the build tree, as a user's script imports it.
// The interpreter starts with the first of them: the others never pay for it.

#include "python_benchmarks.hpp"

#include <benchmark/benchmark.h>
#include <pybind11/embed.h>

#include <algorithm>
#include <filesystem>
#include <vector>

#include "support.hpp"

namespace py = pybind11;

namespace arbiter::bench {

namespace {

// What each benchmark runs from Python, as a user writes it.
constexpr const char* kHelpers = R"(
import os
import arbiter


def graph_config(layers=10, per_layer=100):
    """10 layers of 100 scripted behaviours, a chaining inhibition between neighbours."""
    lines = ["arbiter: 1", "name: bench", "layers:"]
    for layer in range(layers):
        lines += [f"  - name: l{layer}", "    actuators:",
                  f"      out{layer}: {{type: double, aggregate: true}}", "    behaviours:"]
        for b in range(per_layer):
            level = (b % 7 + 1) / 8
            lines.append(f"      b{b}: {{type: scripted, params: {{activation: [{level}, 0, 1], "
                         f"writes: {{out{layer}: {b}}}}}}}")
        lines.append("    inhibitions:")
        lines += [f"      - b{b} => b{b + 1}" for b in range(0, per_layer - 1, 2)]
    return "\n".join(lines) + "\n"


def manager_of(directory, name, text):
    config = os.path.join(directory, name)
    with open(config, "w") as out:
        out.write(text)
    manager = arbiter.load(config).manager()
    manager.step(100)
    return manager


def step_one_by_one(manager, steps):
    step = manager.step
    for _ in range(steps):
        step()


WALK = """
import arbiter


class Walk(arbiter.Behaviour):
    name = "bench.Walk"
    outputs = {"speed": "double"}

    def activation(self, ctx):
        return 0.5

    def execute(self, ctx):
        ctx.write("speed", 0.3)
"""

ONE_BEHAVIOUR = """arbiter: 1
name: one
plugins: [{python: bench_walk}]
layers:
  - name: control
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      walk: CLASS
"""


def walk_managers(directory):
    with open(os.path.join(directory, "bench_walk.py"), "w") as out:
        out.write(WALK)
    scripted = "{type: scripted, params: {activation: 0.5, writes: {speed: 0.3}}}"
    return (manager_of(directory, "python.yaml", ONE_BEHAVIOUR.replace("CLASS", "bench.Walk")),
            manager_of(directory, "scripted.yaml", ONE_BEHAVIOUR.replace("CLASS", scripted)))


def write_trace(config, path, steps):
    manager = arbiter.load(config).manager()
    manager.trace(path)
    manager.step(steps)
    del manager


def dataframe(path):
    return arbiter.open_recording(path).to_dataframe()
)";

/// The helpers above, in a directory of their own for the files they write.
struct Python {
  py::scoped_interpreter interpreter;
  py::module_ helpers;
  std::filesystem::path directory;

  Python() {
    py::module_::import("sys").attr("path").attr("insert")(0, ARBITER_BENCH_PYTHONPATH);
    helpers = py::module_::import("types").attr("ModuleType")("arbiter_bench");
    py::exec(kHelpers, helpers.attr("__dict__"));
    directory = std::filesystem::temp_directory_path() / "arbiter_bench_python";
    std::filesystem::create_directories(directory);
  }
};

Python& python() {
  static Python instance;
  return instance;
}

/// Runs `a` and `b` `batch` times each per iteration, alternating which goes first, and returns
/// the fastest batch of each per call (on a shared machine other load only ever adds time).
template <typename A, typename B>
std::pair<double, double> fastest_batches(benchmark::State& state, std::size_t batch, A&& a,
                                          B&& b) {
  std::vector<double> times[2];
  bool a_first = true;
  const auto timed = [&](int which) {
    const double start = cpu_seconds();
    if (which == 0) {
      a();
    } else {
      b();
    }
    times[which].push_back((cpu_seconds() - start) / static_cast<double>(batch));
  };
  for (auto _ : state) {
    timed(a_first ? 0 : 1);
    timed(a_first ? 1 : 0);
    a_first = !a_first;
  }
  return {fastest(times[0]), fastest(times[1])};
}

/// A 1000-behaviour graph stepped one Manager.step() call per step from a Python loop, against
/// the same manager's Manager.step(count), which loops in C++.
void step_from_python(benchmark::State& state) {
  Python& py = python();
  const py::object manager = py.helpers.attr("manager_of")(py.directory.string(), "graph.yaml",
                                                           py.helpers.attr("graph_config")());
  constexpr std::size_t kSteps = 200;
  const py::object one_by_one = py.helpers.attr("step_one_by_one");
  const py::object step = manager.attr("step");
  const auto [from_python, in_cpp] = fastest_batches(
      state, kSteps, [&] { one_by_one(manager, kSteps); }, [&] { step(kSteps); });
  state.counters["ns_per_step"] = in_cpp * 1e9;
  state.counters["python_ns_per_step"] = from_python * 1e9;
  state.counters["ratio"] = from_python / in_cpp;
}

/// A step of one Python behaviour (activation() and execute() writing a double) against the same
/// program with a `scripted` behaviour in its place: the difference is the calls into Python.
void python_behaviour(benchmark::State& state) {
  Python& py = python();
  const py::tuple managers = py.helpers.attr("walk_managers")(py.directory.string());
  constexpr std::size_t kSteps = 2000;
  const py::object python_step = managers[0].attr("step");
  const py::object scripted_step = managers[1].attr("step");
  const auto [with_python, with_scripted] = fastest_batches(
      state, kSteps, [&] { python_step(kSteps); }, [&] { scripted_step(kSteps); });
  state.counters["ns_per_step"] = with_scripted * 1e9;
  state.counters["python_ns_per_step"] = with_python * 1e9;
  state.counters["call_ns"] = (with_python - with_scripted) * 1e9;
}

/// A trace of the paper's walk-and-kick example read into a pandas DataFrame (wall time: pandas
/// may use threads).
void to_dataframe(benchmark::State& state) {
  Python& py = python();
  const auto steps = static_cast<std::size_t>(state.range(0));
  const std::string trace = (py.directory / "run.jsonl").string();
  py.helpers.attr("write_trace")(ARBITER_BENCH_PAPER_CONFIG, trace, steps);
  std::size_t columns = 0;
  for (auto _ : state) columns = py::len(py.helpers.attr("dataframe")(trace).attr("columns"));
  state.counters["columns"] = static_cast<double>(columns);
  state.counters["trace_mb"] = static_cast<double>(std::filesystem::file_size(trace)) / 1e6;
  std::filesystem::remove(trace);
}

}  // namespace

void register_python_benchmarks() {
  benchmark::RegisterBenchmark("python/step/1000", step_from_python)->Iterations(40);
  benchmark::RegisterBenchmark("python/behaviour", python_behaviour)->Iterations(20);
  benchmark::RegisterBenchmark("python/to_dataframe", to_dataframe)
      ->Arg(1000)
      ->Arg(100000)
      ->Iterations(1)
      ->Repetitions(3)
      ->ComputeStatistics("min", fastest)
      ->UseRealTime()
      ->Unit(benchmark::kSecond);
}

}  // namespace arbiter::bench

// The benchmarks (docs/performance.md): the step over generated graphs, an SCL plan, load and
// memory. Names are `<what>/<graph>/<N>`; per-item costs are user counters.

#include <benchmark/benchmark.h>
#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>
#include <tuple>
#include <vector>

#include "arbiter/lint.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/recorded_inputs.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/trace_reader.hpp"
#include "benchmarks.hpp"
#include "commands/record.hpp"
#include "generator.hpp"
#include "server/foxglove.hpp"
#include "support.hpp"
#if ARBITER_HAS_FOXGLOVE
#include "foxglove_subscriber.hpp"
#endif

namespace arbiter::bench {

namespace {

constexpr const char* kTrivial = "bench.Trivial";

Registry& registry() {
  static Registry instance = make_registry();
  return instance;
}

std::shared_ptr<spdlog::logger> quiet() {
  return std::make_shared<spdlog::logger>("bench", std::make_shared<spdlog::sinks::null_sink_mt>());
}

/// Runs `step` for the benchmark's iterations; returns CPU nanoseconds per step.
template <typename F>
double timed_loop(benchmark::State& state, F&& step) {
  const double start = cpu_seconds();
  for (auto _ : state) step();
  const double seconds = cpu_seconds() - start;
  return state.iterations() == 0 ? 0.0 : seconds * 1e9 / static_cast<double>(state.iterations());
}

void step(benchmark::State& state, Graph graph, const std::string& behaviour_class) {
  const auto n = static_cast<std::size_t>(state.range(0));
  GeneratorOptions options;
  options.graph = graph;
  options.behaviours = n;
  options.behaviour_class = behaviour_class;
  Manager manager(compile_text(generate_config(options), registry()), quiet());
  const std::size_t behaviours = manager.program().behaviours.size();
  manager.step();  // the first step may size what it needs; every later one allocates nothing
  const double ns = timed_loop(state, [&] { manager.step(); });
  state.counters["ns_per_behaviour"] = ns / static_cast<double>(behaviours);
  state.counters["closure"] = static_cast<double>(manager.program().inhibitions.size());
  state.counters["terms"] =
      static_cast<double>(manager.program().inhibitions.recipes().terms.size());
}

/// Keeps the calling thread on `cpu` until destroyed (where the machine has it): threads it starts
/// meanwhile start there too.
class PinnedTo {
 public:
  explicit PinnedTo(int cpu) {
    pinned_ = pthread_getaffinity_np(pthread_self(), sizeof before_, &before_) == 0 &&
              CPU_COUNT(&before_) > 1 && CPU_ISSET(cpu, &before_);
    if (!pinned_) return;
    cpu_set_t only;
    CPU_ZERO(&only);
    CPU_SET(cpu, &only);
    pthread_setaffinity_np(pthread_self(), sizeof only, &only);
  }
  ~PinnedTo() {
    if (pinned_) pthread_setaffinity_np(pthread_self(), sizeof before_, &before_);
  }
  PinnedTo(const PinnedTo&) = delete;
  PinnedTo& operator=(const PinnedTo&) = delete;

 private:
  cpu_set_t before_{};
  bool pinned_ = false;
};

/// The program an observed benchmark steps: the soccer demo (its plugin built beside, its
/// classes and value types in `soccer_registry`, which must outlive them), else the generated
/// `graph` of state.range(0) behaviours. False, the benchmark skipped, when the demo does not
/// load.
bool load_program(benchmark::State& state, Graph graph, bool soccer, Registry& soccer_registry,
                  std::optional<Program>& program, double soccer_rate_hz = 0.0) {
  if (soccer) {
    Diagnostics diagnostics;
    LoadOptions options;
    options.plugins.path = {ARBITER_BENCH_PLUGIN_DIR};
    std::string path = ARBITER_BENCH_SOCCER;
    if (soccer_rate_hz > 0.0) {
      // The demo as a robot stepping at that pace declares it: its rate_hz (the config's is 15).
      std::ifstream in(path);
      std::stringstream text;
      text << in.rdbuf();
      const auto config = std::regex_replace(text.str(), std::regex("\nrate_hz: [0-9.]+\n"),
                                             "\nrate_hz: " + std::to_string(soccer_rate_hz) + "\n");
      path = (std::filesystem::temp_directory_path() / "arbiter_bench_soccer.yaml").string();
      std::ofstream(path) << config;
    }
    program = load(path, soccer_registry, diagnostics, options);
    if (soccer_rate_hz > 0.0) std::filesystem::remove(path);
    if (!program) {
      state.SkipWithError("the soccer demo does not load (is its plugin built?)");
      return false;
    }
  } else {
    GeneratorOptions options;
    options.graph = graph;
    options.behaviours = static_cast<std::size_t>(state.range(0));
    options.behaviour_class = kTrivial;
    program = compile_text(generate_config(options), registry());
  }
  return true;
}

/// Steps both managers once, the recorded one with its writer started on CPU 1, and then keeps
/// the stepping thread on CPU 0 while `stepping_cpu` lives: as a robot would pin them. Left to
/// the scheduler, either moved now and then, and each move cost one kind of batch more than the
/// other. The writer starts on the first recorded step, where its creator is.
void start_pinned(Manager& plain, Manager& recorded, std::optional<PinnedTo>& stepping_cpu) {
  plain.step();
  {
    PinnedTo writer_cpu(1);
    recorded.step();
  }
  stepping_cpu.emplace(0);
}

/// The step with a Recorder attached, against the same graph without (the stepping thread's CPU
/// time only: the writer thread compresses on another core). `soccer`: the soccer demo (its
/// plugin built beside), else the generated `graph` of N behaviours.
void record(benchmark::State& state, Graph graph, bool soccer) {
  std::optional<Program> programs[2];
  Registry soccer_registry = make_registry();
  for (auto& program : programs) {
    if (!load_program(state, graph, soccer, soccer_registry, program)) return;
  }
  Manager plain(std::move(*programs[0]), quiet());
  Manager recorded(std::move(*programs[1]), quiet());
  const auto path = std::filesystem::temp_directory_path() / "arbiter_bench_record.mcap";
  RecordingInfo info;
  info.version = "bench";
  std::uint64_t steps = 0;
  std::uint64_t dropped = 0;
  double plain_ns = 0.0;
  double recorded_ns = 0.0;
  {
    constexpr std::size_t kRecordSlots = 1024;
    constexpr std::size_t kBatch = kRecordSlots / 4;
    std::optional<PinnedTo> stepping_cpu;
    Recorder recorder(path.string(), info, kRecordSlots);
    recorded.add_observer(recorder);
    start_pinned(plain, recorded, stepping_cpu);
    double plain_total = 0.0;
    double recorded_total = 0.0;
    // Steps are timed in batches: the clock is a system call here, dearer than a small step.
    // Before each batch the writer is woken and catches up, untimed: stepping as fast as it can,
    // the stepping thread outruns it (formatting and compressing a step cost more than the
    // step), and every timed step must find a free slot, as a dropped step would cost nothing.
    // During a batch the writer keeps to its period, as in a paced run. Both batches start after
    // the same pause, in alternating order, so neither finds the caches warmer.
    const auto batch = [&](Manager& manager, double& total) {
      recorder.drain();
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      const double start = cpu_seconds();
      for (std::size_t i = 0; i < kBatch; ++i) manager.step();
      total += cpu_seconds() - start;
    };
    bool plain_first = true;
    for (auto _ : state) {
      batch(plain_first ? plain : recorded, plain_first ? plain_total : recorded_total);
      batch(plain_first ? recorded : plain, plain_first ? recorded_total : plain_total);
      plain_first = !plain_first;
    }
    recorded.finish();
    steps = recorded.steps();
    dropped = recorder.dropped();
    const auto n = static_cast<double>(std::max<std::int64_t>(state.iterations(), 1)) *
                   static_cast<double>(kBatch);
    plain_ns = plain_total * 1e9 / n;
    recorded_ns = recorded_total * 1e9 / n;
  }
  state.counters["ns_per_step"] = plain_ns;
  state.counters["recorded_ns_per_step"] = recorded_ns;
  state.counters["overhead"] = plain_ns > 0.0 ? recorded_ns / plain_ns - 1.0 : 0.0;
  state.counters["bytes_per_step"] =
      static_cast<double>(std::filesystem::file_size(path)) / static_cast<double>(steps);
  state.counters["dropped"] = static_cast<double>(dropped);
  std::filesystem::remove(path);
}

/// Hands the steps on to `to` only while open: one manager's steps, observed and not in turn.
struct GatedObserver : Observer {
  explicit GatedObserver(Observer& to_) : to(to_) {}
  void on_start(const Manager& manager) override { to.on_start(manager); }
  void on_step(const Manager& manager) override {
    if (open) to.on_step(manager);
  }
  void on_reload(const Manager& manager) override { to.on_reload(manager); }
  void on_staged(const Program& next, std::uint64_t stage) override { to.on_staged(next, stage); }
  void on_retiring(const Program& replaced) override { to.on_retiring(replaced); }
  void on_finish(const Manager& manager) override { to.on_finish(manager); }
  void on_safe(const Manager& manager) override { to.on_safe(manager); }
  Observer& to;
  bool open = true;
};

/// The period of a paced benchmark's steps: 2 kHz, a fast robot's loop, gathers the steps
/// quickly; 200 Hz finds even less in the caches and TLB after each sleep (a slower robot's loop
/// is colder still), and the plain step there costs several times as much.
enum class Pace { k2kHz, k200Hz };
std::chrono::microseconds period_of(Pace pace) {
  return std::chrono::microseconds(pace == Pace::k2kHz ? 500 : 5000);
}

/// `manager`'s steps at a robot's pace, a step every `period`, each timed alone by the wall clock
/// (a vDSO read here, about 27 ns), the one handed on by `gate` and the one not in turn, on CPU
/// 0; counters: their medians, the overhead and the paired overhead. Between two steps the thread
/// sleeps, as a paced run does, so a step does not find the caches as the step before left them: an
/// observer's cost where it runs. Medians, so that a step that an interrupt or the observer's other
/// thread met does not count. One manager takes both kinds of step: two managers of the same
/// program differ by where their memory lies, and that alone made one's step up to 12 % slower than
/// the other's with nothing observed. An observed step carries what changed over two steps, a
/// little more than one observing every step copies.
void paced_steps(benchmark::State& state, Manager& manager, GatedObserver& gate, Pace pace) {
  constexpr std::size_t kSteps = 200;  // of each, per iteration
  const auto period = period_of(pace);
  std::vector<double> plain_ns;
  std::vector<double> observed_ns;
  plain_ns.reserve(kSteps * static_cast<std::size_t>(state.max_iterations));
  observed_ns.reserve(kSteps * static_cast<std::size_t>(state.max_iterations));
  {
    PinnedTo stepping_cpu(0);
    using Clock = std::chrono::steady_clock;
    auto next = Clock::now();
    const auto timed_step = [&](bool observed, std::vector<double>& ns) {
      gate.open = observed;
      next += period;
      std::this_thread::sleep_until(next);
      const auto start = Clock::now();
      manager.step();
      ns.push_back(std::chrono::duration<double, std::nano>(Clock::now() - start).count());
    };
    for (auto _ : state) {
      for (std::size_t i = 0; i < kSteps; ++i) {
        timed_step(false, plain_ns);
        timed_step(true, observed_ns);
      }
    }
  }
  gate.open = true;
  const auto median = [](std::vector<double> values) {
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  };
  // Also what each observed step cost over the plain step just before it: a pair is one period
  // apart, so a change in the machine's state over the run (another VM's load, a frequency
  // change) moves both of its steps alike.
  std::vector<double> differences(plain_ns.size());
  for (std::size_t i = 0; i < plain_ns.size(); ++i) differences[i] = observed_ns[i] - plain_ns[i];
  const double plain_median = median(plain_ns);
  const double observed_median = median(observed_ns);
  state.counters["ns_per_step"] = plain_median;
  state.counters["observed_ns_per_step"] = observed_median;
  state.counters["overhead"] = observed_median / plain_median - 1.0;
  state.counters["paired_overhead"] = median(differences) / plain_median;
  // And the means, of all but each kind's slowest 5 % (those an interrupt met): a step that costs
  // more now and then (one carrying a picture, at a server's scene rate) counts here at its share.
  const auto trimmed_mean = [](std::vector<double> values) {
    std::sort(values.begin(), values.end());
    values.resize(values.size() - values.size() / 20);
    double sum = 0.0;
    for (const double value : values) sum += value;
    return sum / static_cast<double>(std::max<std::size_t>(values.size(), 1));
  };
  state.counters["mean_overhead"] = trimmed_mean(observed_ns) / trimmed_mean(plain_ns) - 1.0;
}

/// The soccer demo recorded at a robot's pace (paced_steps()), the writer on CPU 1.
void record_paced(benchmark::State& state, Pace pace) {
  std::optional<Program> program;
  Registry soccer_registry = make_registry();
  if (!load_program(state, Graph::kLayers, true, soccer_registry, program)) return;
  Manager manager(std::move(*program), quiet());
  const auto path = std::filesystem::temp_directory_path() / "arbiter_bench_record_paced.mcap";
  RecordingInfo info;
  info.version = "bench";
  std::uint64_t dropped = 0;
  {
    Recorder recorder(path.string(), info);
    GatedObserver gate(recorder);
    manager.add_observer(gate);
    {
      PinnedTo writer_cpu(1);  // the writer starts on the first recorded step, where its creator is
      manager.step();
    }
    paced_steps(state, manager, gate, pace);
    manager.finish();
    dropped = recorder.dropped();
  }
  std::filesystem::remove(path);
  state.counters["dropped"] = static_cast<double>(dropped);
}

#if ARBITER_HAS_FOXGLOVE
/// What a served step's client gets of the picture: nothing (it subscribes to every channel but
/// the picture's, as one that only plots does, and the server copies no picture), pictures at the
/// server's scene rate (FoxgloveServer::kSceneRate, as `arbiter run --foxglove`), or every step's
/// (`--foxglove-scene-rate 0`).
enum class Pictures { kNone, kAtSceneRate, kEveryStep };

/// A program served over the Foxglove WebSocket protocol (`arbiter run --foxglove`) at a robot's
/// pace (paced_steps()) to a client subscribed to every channel, the server's and the client's
/// threads on CPU 1. The soccer demo, or a generated graph of `state.range(0)` behaviours: the
/// capture's cost is mostly fixed, so its share falls as a step grows.
void foxglove_paced(benchmark::State& state, Graph graph, bool soccer, Pictures pictures,
                    Pace pace) {
  std::optional<Program> program;
  Registry soccer_registry = make_registry();
  // At its pace: the server sends every picture of a program no faster than its scene rate.
  const double rate_hz = 1e6 / static_cast<double>(period_of(pace).count());
  if (!load_program(state, graph, soccer, soccer_registry, program, rate_hz)) return;
  Manager manager(std::move(*program), quiet());
  std::ostringstream said;
  std::optional<PinnedTo> others_cpu(1);
  auto server = cli::FoxgloveServer::open("127.0.0.1", 0, "bench", "arbiter bench", said, said);
  if (!server) {
    state.SkipWithError(said.str().c_str());
    return;
  }
  if (pictures == Pictures::kEveryStep) server->set_scene_rate(0.0);
  GatedObserver gate(server->observer());
  manager.add_observer(gate);
  manager.step();
  test::FoxgloveSubscriber client(server->url(),
                                  pictures == Pictures::kNone ? "/arbiter/scene" : "");
  others_cpu.reset();
  // Subscribed once the steps reach the client.
  for (int i = 0; i < 2000 && client.received() == 0; ++i) {
    manager.step();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (client.received() == 0) {
    state.SkipWithError("the client received nothing");
    return;
  }
  paced_steps(state, manager, gate, pace);
  const auto received = client.received();
  manager.finish();
  const auto counts = server->counts();
  server->stop();
  state.counters["received"] = static_cast<double>(received);
  state.counters["dropped"] =
      static_cast<double>(counts.dropped_steps + counts.dropped_for_slow_clients);
}
#endif

/// `arbiter replay` of a recording of the soccer demo `state.range(0)` steps long, whole, in
/// recorded steps per second (CPU time); and apart, the two reads of the recording a replay
/// makes as it goes: its inputs (each step's message parsed and held) and its step records
/// (each checked, as every trace reader does). What is left is stepping, tracing and comparing.
enum class ReplayPart { kWhole, kInputs, kSteps };
void replay(benchmark::State& state, ReplayPart part) {
  Registry soccer_registry = make_registry();
  LoadOptions options;
  options.plugins.path = {ARBITER_BENCH_PLUGIN_DIR};
  Diagnostics diagnostics;
  auto program = load(ARBITER_BENCH_SOCCER, soccer_registry, diagnostics, options);
  if (!program) {
    state.SkipWithError("the soccer demo does not load (is its plugin built?)");
    return;
  }
  const auto path = std::filesystem::temp_directory_path() / "arbiter_bench_replay.mcap";
  const auto steps = static_cast<std::uint64_t>(state.range(0));
  {
    Manager manager(std::move(*program), quiet());
    Recorder recorder(path.string(),
                      cli::recording_info(ARBITER_BENCH_SOCCER, soccer_registry, options, "bench"),
                      Recorder::kSlots, RingFull::kWaitForWriter);
    manager.add_observer(recorder);
    for (std::uint64_t i = 0; i < steps; ++i) manager.step();
    manager.finish();
  }
  cli::ReplayOptions replay;
  replay.recording = path.string();
  replay.load = options;
  replay.version = "bench";
  for (auto _ : state) {
    if (part == ReplayPart::kWhole) {
      std::ostringstream out;
      std::ostringstream err;
      if (cli::replay(replay, soccer_registry, out, err) != 0) {
        state.SkipWithError(err.str().c_str());
        break;
      }
    } else if (part == ReplayPart::kInputs) {
      RecordingReader reader(replay.recording);
      RecordedInputs inputs;
      RecordingReader::Event event;
      Diagnostics unused;
      while (reader.next(event)) {
        if (event.kind == RecordingReader::Event::Kind::kInputs) {
          inputs.load(event.step, event.text, unused);
        }
      }
    } else {
      const auto source = open_trace(replay.recording);
      TraceRecord record;
      while (source->next(record)) benchmark::DoNotOptimize(record.step);
    }
  }
  state.counters["steps_per_second"] =
      benchmark::Counter(static_cast<double>(steps) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
  std::filesystem::remove(path);
}

const char* const kPlan = R"(arbiter: 1
name: replan
state_machines:
  plan:
    states:
      s0: STATE
      s1: STATE
      s2: STATE
      s3: STATE
      s4: {type: STATE, params: {append: [s0, s1, s2, s3, s4]}}
    queue: [s0, s1, s2, s3, s4]
)";

/// A standalone controller whose 5-state plan is appended again by its last state: every step
/// is one transition (deactivate, pop, activate, execute), every fifth also five queue edits.
void scl(benchmark::State& state, const std::string& state_class) {
  std::string text = kPlan;
  for (auto at = text.find("STATE"); at != std::string::npos; at = text.find("STATE", at)) {
    text.replace(at, 5, state_class);
  }
  Manager manager(compile_text(text, registry()), quiet());
  manager.step();
  const double ns = timed_loop(state, [&] { manager.step(); });
  const Controller& controller = *manager.program().controllers.front();
  if (controller.status() != ControllerStatus::kRunning) {
    state.SkipWithError("the plan stopped running");
  }
  state.counters["ns_per_step"] = ns;
}

/// A generated dag config written to a file once per size, as users' configs are read.
const std::string& config_file(std::size_t n) {
  static std::map<std::size_t, std::string> files;
  auto& path = files[n];
  if (path.empty()) {
    GeneratorOptions options;
    options.graph = Graph::kDag;
    options.behaviours = n;
    path = (std::filesystem::temp_directory_path() /
            ("arbiter_bench_dag_" + std::to_string(n) + ".yaml"))
               .string();
    std::ofstream(path) << generate_config(options);
  }
  return path;
}

enum class Stage { kParse, kValidate, kCompile, kLint, kTotal };

/// One stage of arbiter::load() (or all of it) for the dag config of N behaviours, 3N
/// inhibitions.
void load(benchmark::State& state, Stage stage) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const std::string& path = config_file(n);
  Registry fresh = make_registry();
  Diagnostics diagnostics;
  const auto document = read_document(path, diagnostics);
  const Model model = build_model(*document, fresh, diagnostics);
  if (diagnostics.has_errors()) {
    state.SkipWithError(format(diagnostics).c_str());
    return;
  }
  const auto linted = stage == Stage::kLint ? compile(model, fresh, diagnostics) : std::nullopt;
  LoadOptions total;  // the whole pipeline, as `arbiter validate` runs it
  total.lint = lint;
  double paused = 0.0;
  const auto discard = [&](std::optional<Program>& program) {
    const double before = cpu_seconds();
    state.PauseTiming();  // destroying the program is not part of loading it
    program.reset();
    state.ResumeTiming();
    paused += cpu_seconds() - before;
  };
  const double start = cpu_seconds();
  for (auto _ : state) {
    Diagnostics each;
    switch (stage) {
      case Stage::kParse:
        benchmark::DoNotOptimize(read_document(path, each));
        break;
      case Stage::kValidate:
        load_plugins(*document, {}, fresh, each);
        benchmark::DoNotOptimize(build_model(*document, fresh, each));
        break;
      case Stage::kCompile: {
        auto program = compile(model, fresh, each);
        discard(program);
        break;
      }
      case Stage::kLint:
        lint(model, *linted, each);
        break;
      case Stage::kTotal: {
        auto program = arbiter::load(path, fresh, each, total);
        if (!program) state.SkipWithError(format(each).c_str());
        discard(program);
        break;
      }
    }
  }
  const double seconds = cpu_seconds() - start - paused;
  state.counters["us_per_behaviour"] =
      seconds * 1e6 / static_cast<double>(state.iterations()) / static_cast<double>(n);
}

/// Heap held by a running manager (its program included), per behaviour, after the first step.
void memory(benchmark::State& state, Graph graph) {
  const auto n = static_cast<std::size_t>(state.range(0));
  GeneratorOptions options;
  options.graph = graph;
  options.behaviours = n;
  options.behaviour_class = kTrivial;
  const std::string text = generate_config(options);
  const auto logger = quiet();
  for (auto _ : state) {
    const std::size_t before = heap_in_use();
    Manager manager(compile_text(text, registry(), "/tmp/arbiter_bench/generated.yaml"), logger);
    manager.step();
    const std::size_t after = heap_in_use();
    state.counters["bytes_per_behaviour"] =
        static_cast<double>(after - before) / static_cast<double>(n);
  }
}

constexpr Graph kGraphs[] = {Graph::kNone, Graph::kChain, Graph::kDag, Graph::kLayers};

}  // namespace

void register_benchmarks() {
  for (Graph graph : kGraphs) {
    const std::string name = "step/" + std::string(to_string(graph));
    benchmark::RegisterBenchmark(name.c_str(), step, graph, std::string(kTrivial))
        ->ComputeStatistics("min", fastest)
        ->Arg(10)
        ->Arg(100)
        ->Arg(1000)
        ->Arg(10000);
  }
  // The same graphs of the built-in `scripted` behaviour, whose own cost (a level list, writes
  // of any type through the value type's functions) comes on top.
  for (Graph graph : kGraphs) {
    const std::string name = "step_scripted/" + std::string(to_string(graph));
    benchmark::RegisterBenchmark(name.c_str(), step, graph, std::string("scripted"))
        ->ComputeStatistics("min", fastest)
        ->Arg(1000);
  }
  benchmark::RegisterBenchmark("record/layers", record, Graph::kLayers, false)
      ->ComputeStatistics("min", fastest)
      ->Arg(1000);
  benchmark::RegisterBenchmark("record/soccer", record, Graph::kLayers, true)
      ->ComputeStatistics("min", fastest)
      ->MinTime(0.2);
  benchmark::RegisterBenchmark("record/soccer/paced", record_paced, Pace::k2kHz)
      ->ComputeStatistics("min", fastest)
      ->Iterations(5)
      ->UseRealTime();
  benchmark::RegisterBenchmark("record/soccer/paced/200hz", record_paced, Pace::k200Hz)
      ->ComputeStatistics("min", fastest)
      ->Iterations(5)
      ->UseRealTime();
#if ARBITER_HAS_FOXGLOVE
  const std::tuple<const char*, Pictures, Pace> served_soccer[] = {
      {"foxglove/soccer/paced", Pictures::kAtSceneRate, Pace::k2kHz},
      {"foxglove/soccer/paced/200hz", Pictures::kAtSceneRate, Pace::k200Hz},
      {"foxglove/soccer/paced/every_picture", Pictures::kEveryStep, Pace::k2kHz},
      {"foxglove/soccer/paced/200hz/every_picture", Pictures::kEveryStep, Pace::k200Hz},
      {"foxglove/soccer/paced/no_scene", Pictures::kNone, Pace::k2kHz}};
  for (const auto& [name, pictures, pace] : served_soccer) {
    benchmark::RegisterBenchmark(name, foxglove_paced, Graph::kLayers, true, pictures, pace)
        ->ComputeStatistics("min", fastest)
        ->Iterations(5)
        ->UseRealTime();
  }
  benchmark::RegisterBenchmark("foxglove/layers/paced", foxglove_paced, Graph::kLayers, false,
                               Pictures::kAtSceneRate, Pace::k2kHz)
      ->ComputeStatistics("min", fastest)
      ->Arg(100)
      ->Arg(1000)
      ->Iterations(5)
      ->UseRealTime();
#endif
  const std::pair<const char*, ReplayPart> replay_parts[] = {
      {"replay/soccer", ReplayPart::kWhole},
      {"replay/soccer/read_inputs", ReplayPart::kInputs},
      {"replay/soccer/read_steps", ReplayPart::kSteps}};
  for (const auto& [name, part] : replay_parts) {
    benchmark::RegisterBenchmark(name, replay, part)
        ->ComputeStatistics("min", fastest)
        ->Arg(2000)
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::RegisterBenchmark("scl/replan5", scl, std::string("bench.Proceed"))
      ->ComputeStatistics("min", fastest);
  benchmark::RegisterBenchmark("scl/replan5_scripted", scl, std::string("scripted"))
      ->ComputeStatistics("min", fastest);
  const std::pair<const char*, Stage> stages[] = {{"load/parse", Stage::kParse},
                                                  {"load/validate", Stage::kValidate},
                                                  {"load/compile", Stage::kCompile},
                                                  {"load/lint", Stage::kLint},
                                                  {"load/total", Stage::kTotal}};
  for (const auto& [name, stage] : stages) {
    benchmark::RegisterBenchmark(name, load, stage)
        ->ComputeStatistics("min", fastest)
        ->Arg(1000)
        ->Arg(10000)
        ->Unit(benchmark::kMillisecond);
  }
  for (Graph graph : kGraphs) {
    const std::string name = "memory/" + std::string(to_string(graph));
    benchmark::RegisterBenchmark(name.c_str(), memory, graph)
        ->ComputeStatistics("min", fastest)
        ->Arg(1000)
        ->Arg(10000)
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  }
}

}  // namespace arbiter::bench

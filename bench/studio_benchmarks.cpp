// studio/edit/<N>: what the studio's page waits for after an edit by mouse or keyboard in a config
// of N behaviours (the dag graph, 3N inhibitions): Studio::edit(), which runs the edit engine's
// operation, checks it by loading the edited texts, and answers with the edits, the texts, the
// graph, the diagnostics and the review, as `POST /studio/edit` does without the HTTP around it.
// An iteration of studio/edit/<N> makes each of the studio's operations once; studio/edit/<op>/<N>
// is one operation alone. Every operation is made on the generated config as it is: the texts are
// put back (untimed) after each.
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "arbiter/lint.hpp"
#include "generator.hpp"
#include "server/studio.hpp"
#include "studio_benchmarks.hpp"
#include "support.hpp"

namespace arbiter::bench {

namespace {

/// The studio's operations on the dag config of `behaviours` behaviours, as the page sends them.
struct Operations {
  std::string set_param;
  std::string add_inhibition;
  std::string flip_chaining;
  std::string remove_inhibition;
  std::string rename;
  std::string add_behaviour;
  std::string remove_behaviour;

  std::vector<const std::string*> all() const {
    return {&set_param, &add_inhibition, &flip_chaining,   &remove_inhibition,
            &rename,    &add_behaviour,  &remove_behaviour};
  }
};

bool declares(const std::string& text, std::size_t from, std::size_t to) {
  for (const char* arrow : {"=>", "->"}) {
    if (text.find(fmt::format("- b{} {} b{}\n", from, arrow, to)) != std::string::npos) return true;
  }
  return false;
}

Operations operations(const std::string& text, std::size_t behaviours) {
  const std::size_t middle = behaviours / 2;
  // The first pair, earlier to later (the graph stays acyclic), that is not inhibited yet.
  std::size_t from = 0;
  std::size_t to = 1;
  while (declares(text, from, to)) {
    if (++to == behaviours) to = ++from + 1;
  }
  // The first declared inhibition.
  const auto first = text.find("      - b");
  const auto end = text.find('\n', first);
  const std::string item = text.substr(first + 8, end - first - 8);
  const auto arrow = item.find(" => ") != std::string::npos ? item.find(" => ") : item.find(" -> ");
  const std::string inhibitor = item.substr(0, arrow);
  const std::string inhibited = item.substr(arrow + 4);
  Operations ops;
  ops.set_param = fmt::format(
      R"({{"op": "set_param", "layer": "l0", "behaviour": "b{}", "param": "activation", )"
      R"("value": 0.25}})",
      middle);
  ops.add_inhibition = fmt::format(
      R"({{"op": "add_inhibition", "layer": "l0", "inhibitor": "b{}", "inhibited": "b{}", )"
      R"("chaining": true}})",
      from, to);
  const std::string declared =
      fmt::format(R"("layer": "l0", "inhibitor": "{}", "inhibited": "{}")", inhibitor, inhibited);
  ops.flip_chaining = fmt::format(R"({{"op": "flip_chaining", {}}})", declared);
  ops.remove_inhibition = fmt::format(R"({{"op": "remove_inhibition", {}}})", declared);
  ops.rename = fmt::format(
      R"({{"op": "rename", "kind": "behaviour", "scope": "l0", "name": "b{}", "to": "renamed"}})",
      middle);
  ops.add_behaviour =
      R"({"op": "add_behaviour", "layer": "l0", "name": "added", "type": "scripted"})";
  ops.remove_behaviour =
      fmt::format(R"({{"op": "remove_behaviour", "layer": "l0", "name": "b{}"}})", middle);
  return ops;
}

/// A studio on a generated config written to a file of its own (the studio reads the disk).
class Bench {
 public:
  explicit Bench(std::size_t behaviours)
      : dir_(std::filesystem::temp_directory_path() /
             fmt::format("arbiter_bench_studio_{}_{}", ::getpid(), behaviours)) {
    GeneratorOptions options;
    options.graph = Graph::kDag;
    options.behaviours = behaviours;
    text_ = generate_config(options);
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "config.yaml").string();
    std::ofstream(path_) << text_;
    ops_ = operations(text_, behaviours);
    LoadOptions load;
    load.lint = lint;  // as `arbiter edit` loads
    registry_ = make_registry();
    studio_ = std::make_unique<cli::Studio>(path_, registry_, load);
    restore_ = nlohmann::json{{"texts", {{path_, text_}}}}.dump();
  }
  ~Bench() {
    studio_.reset();
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  Bench(const Bench&) = delete;
  Bench& operator=(const Bench&) = delete;

  const Operations& ops() const { return ops_; }

  /// Makes each of `ops` every iteration; the texts are put back, untimed, after each.
  void run(benchmark::State& state, const std::vector<const std::string*>& ops) {
    std::size_t bytes = 0;
    for (auto _ : state) {
      for (const std::string* op : ops) {
        const cli::Reply reply = studio_->edit(*op);
        if (reply.first != 200) {
          state.SkipWithError(("an operation was refused: " + reply.second.substr(0, 300)).c_str());
          return;
        }
        bytes += reply.second.size();
        state.PauseTiming();
        studio_->set_texts(restore_);
        state.ResumeTiming();
      }
    }
    state.counters["reply_bytes"] =
        benchmark::Counter(static_cast<double>(bytes) / static_cast<double>(ops.size()),
                           benchmark::Counter::kAvgIterations);
  }

 private:
  std::filesystem::path dir_;
  std::string text_;
  std::string path_;
  Operations ops_;
  Registry registry_;
  std::unique_ptr<cli::Studio> studio_;
  std::string restore_;
};

// Each iteration makes every operation once: `operations` says how many, and the time of one is
// the iteration's divided by it.
void edit(benchmark::State& state) {
  Bench bench(static_cast<std::size_t>(state.range(0)));
  const auto all = bench.ops().all();
  bench.run(state, all);
  state.counters["operations"] = static_cast<double>(all.size());
}

void one(benchmark::State& state, std::string Operations::*op) {
  Bench bench(static_cast<std::size_t>(state.range(0)));
  bench.run(state, {&(bench.ops().*op)});
}

}  // namespace

void register_studio_benchmarks() {
  benchmark::RegisterBenchmark("studio/edit", edit)
      ->Arg(200)
      ->Arg(1000)
      ->ComputeStatistics("min", fastest)
      ->Unit(benchmark::kMillisecond);
  const std::pair<const char*, std::string Operations::*> each[] = {
      {"set_param", &Operations::set_param},
      {"add_inhibition", &Operations::add_inhibition},
      {"flip_chaining", &Operations::flip_chaining},
      {"remove_inhibition", &Operations::remove_inhibition},
      {"rename", &Operations::rename},
      {"add_behaviour", &Operations::add_behaviour},
      {"remove_behaviour", &Operations::remove_behaviour}};
  for (const auto& [name, op] : each) {
    benchmark::RegisterBenchmark(fmt::format("studio/edit/{}", name).c_str(), one, op)
        ->Arg(200)
        ->Arg(1000)
        ->ComputeStatistics("min", fastest)
        ->Unit(benchmark::kMillisecond);
  }
}

}  // namespace arbiter::bench

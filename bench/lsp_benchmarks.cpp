// lsp/change/<N>: what an editor waits for after a keystroke in a config of N behaviours (the
// dag graph, 3N inhibitions): the server's didChange handler, which loads the edited text through
// the whole pipeline and returns the publishDiagnostics notifications. Driven through
// Server::handle, without stdio.
#include <benchmark/benchmark.h>

#include <string>

#include "arbiter/lint.hpp"
#include "generator.hpp"
#include "lsp/server.hpp"
#include "lsp_benchmarks.hpp"
#include "support.hpp"

namespace arbiter::bench {

namespace {

void change(benchmark::State& state) {
  GeneratorOptions options;
  options.graph = Graph::kDag;
  options.behaviours = static_cast<std::size_t>(state.range(0));
  const std::string text = generate_config(options);
  // A file that need not exist: the editor's buffer is what is loaded.
  const std::string uri = "file:///tmp/arbiter_bench_lsp/config.yaml";
  LoadOptions load;
  load.lint = lint;  // as `arbiter lsp` loads
  lsp::Server server(make_registry, load);
  server.handle(nlohmann::json{{"jsonrpc", "2.0"},
                               {"id", 1},
                               {"method", "initialize"},
                               {"params", nlohmann::json::object()}});
  server.handle(
      nlohmann::json{{"jsonrpc", "2.0"},
                     {"method", "textDocument/didOpen"},
                     {"params",
                      {{"textDocument",
                        {{"uri", uri}, {"languageId", "yaml"}, {"version", 1}, {"text", text}}}}}});
  // Each change alternates between two texts, so that every one is a real edit.
  const std::string texts[] = {text + "# edited\n", text};
  std::size_t published = 0;
  int version = 2;
  for (auto _ : state) {
    const nlohmann::json message = {
        {"jsonrpc", "2.0"},
        {"method", "textDocument/didChange"},
        {"params",
         {{"textDocument", {{"uri", uri}, {"version", version}}},
          {"contentChanges", nlohmann::json::array({{{"text", texts[version % 2]}}})}}}};
    ++version;
    const auto out = server.handle(message);
    published += out.size();
    benchmark::DoNotOptimize(out);
  }
  if (published != static_cast<std::size_t>(state.iterations())) {
    state.SkipWithError("a change did not publish diagnostics once");
  }
}

}  // namespace

void register_lsp_benchmarks() {
  benchmark::RegisterBenchmark("lsp/change", change)
      ->Arg(200)
      ->Arg(1000)
      ->Unit(benchmark::kMillisecond);
}

}  // namespace arbiter::bench

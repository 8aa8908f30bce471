// lsp/change/<N>: what an editor waits for after a keystroke in a config of N behaviours (the
// dag graph, 3N inhibitions): the server's didChange handler, which loads the edited text through
// the whole pipeline and returns the publishDiagnostics notifications. Driven through
// Server::handle, without stdio.
// lsp/change_beside/<N>: the same for a small config (20 behaviours) while a config of N
// behaviours is open too, which an edit of the small one must not check again.
#include <benchmark/benchmark.h>

#include <string>

#include "arbiter/lint.hpp"
#include "generator.hpp"
#include "lsp/server.hpp"
#include "lsp_benchmarks.hpp"
#include "support.hpp"

namespace arbiter::bench {

namespace {

nlohmann::json opened(const std::string& uri, const std::string& text) {
  return {
      {"jsonrpc", "2.0"},
      {"method", "textDocument/didOpen"},
      {"params",
       {{"textDocument", {{"uri", uri}, {"languageId", "yaml"}, {"version", 1}, {"text", text}}}}}};
}

// Edits the config at `uri` (alternating between two texts, so that every change is a real edit)
// with `beside` behaviours in another open config: each edit publishes the edited one's
// diagnostics, once.
void edit(benchmark::State& state, std::size_t behaviours, std::size_t beside) {
  GeneratorOptions options;
  options.graph = Graph::kDag;
  options.behaviours = behaviours;
  const std::string text = generate_config(options);
  // Files that need not exist: the editor's buffers are what is loaded.
  const std::string uri = "file:///tmp/arbiter_bench_lsp/config.yaml";
  LoadOptions load;
  load.lint = lint;  // as `arbiter lsp` loads
  lsp::Server server(make_registry, load);
  server.handle(nlohmann::json{{"jsonrpc", "2.0"},
                               {"id", 1},
                               {"method", "initialize"},
                               {"params", nlohmann::json::object()}});
  server.handle(opened(uri, text));
  if (beside > 0) {
    options.behaviours = beside;
    server.handle(opened("file:///tmp/arbiter_bench_lsp/beside.yaml", generate_config(options)));
  }
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
    state.SkipWithError("a change did not publish the edited config's diagnostics once");
  }
}

void change(benchmark::State& state) {
  edit(state, static_cast<std::size_t>(state.range(0)), 0);
}

void change_beside(benchmark::State& state) {
  edit(state, 20, static_cast<std::size_t>(state.range(0)));
}

// lsp/code_action/<N>: what an editor asks at each move of the cursor onto a behaviour's
// declaration (the middle one's, in the config of N behaviours): the actions there, the removal
// and the moves offered without their edit. lsp/resolve_move/<N>: choosing "Move ... up", whose
// edit is checked by loading the config with it.
void code_action(benchmark::State& state, bool resolve) {
  GeneratorOptions options;
  options.graph = Graph::kDag;
  options.behaviours = static_cast<std::size_t>(state.range(0));
  const std::string text = generate_config(options);
  const std::string uri = "file:///tmp/arbiter_bench_lsp/config.yaml";
  LoadOptions load;
  load.lint = lint;
  lsp::Server server(make_registry, load);
  server.handle(nlohmann::json{{"jsonrpc", "2.0"},
                               {"id", 1},
                               {"method", "initialize"},
                               {"params", nlohmann::json::object()}});
  server.handle(opened(uri, text));
  // The middle behaviour's declaration: the middle line of the first `behaviours:` block.
  std::size_t at = text.find("behaviours:\n");
  std::size_t line = 0;
  for (std::size_t i = 0; i < at; ++i) line += text[i] == '\n';
  line += 1 + options.behaviours / 2;
  std::size_t begin = 0;
  for (std::size_t l = 0; l < line; ++l) begin = text.find('\n', begin) + 1;
  const std::size_t character = text.find_first_not_of(' ', begin) - begin;
  const nlohmann::json position = {{"line", line}, {"character", character}};
  const nlohmann::json request = {{"jsonrpc", "2.0"},
                                  {"id", 2},
                                  {"method", "textDocument/codeAction"},
                                  {"params",
                                   {{"textDocument", {{"uri", uri}}},
                                    {"range", {{"start", position}, {"end", position}}},
                                    {"context", {{"diagnostics", nlohmann::json::array()}}}}}};
  nlohmann::json move;
  const nlohmann::json offered = server.handle(request).at(0).at("result");
  for (const auto& action : offered) {
    if (action.value("title", "").rfind("Move the behaviour", 0) == 0 &&
        action.value("title", "").find(" up") != std::string::npos)
      move = action;
  }
  if (move.is_null()) {
    state.SkipWithError("no move offered on a behaviour's declaration");
    return;
  }
  const nlohmann::json chosen = {
      {"jsonrpc", "2.0"}, {"id", 3}, {"method", "codeAction/resolve"}, {"params", move}};
  for (auto _ : state) {
    const auto out = server.handle(resolve ? chosen : request);
    if (!out.at(0).contains("result")) state.SkipWithError("the request failed");
    benchmark::DoNotOptimize(out);
  }
}

void code_actions(benchmark::State& state) {
  code_action(state, false);
}

void resolve_move(benchmark::State& state) {
  code_action(state, true);
}

}  // namespace

void register_lsp_benchmarks() {
  benchmark::RegisterBenchmark("lsp/code_action", code_actions)
      ->Arg(200)
      ->Arg(1000)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("lsp/resolve_move", resolve_move)
      ->Arg(200)
      ->Arg(1000)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("lsp/change", change)
      ->Arg(20)
      ->Arg(200)
      ->Arg(1000)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("lsp/change_beside", change_beside)
      ->Arg(1000)
      ->Unit(benchmark::kMillisecond);
}

}  // namespace arbiter::bench

#include "core/compile/layer_order.hpp"

#include <fmt/format.h>

#include <deque>
#include <queue>
#include <unordered_map>

namespace arbiter::detail {

namespace {

// Reports one shortest cycle of the closed graph among the behaviours Kahn could not order.
void report_cycle(const LayerDecl& layer, const std::vector<Edge>& edges,
                  const std::vector<std::vector<std::uint32_t>>& out,
                  const std::vector<bool>& remaining, Diagnostics& diagnostics) {
  const std::size_t n = remaining.size();
  // A closed edge u→v: declared, or implied by a chain of two or more chaining edges.
  auto chain_reach = [&](std::uint32_t from) {
    std::vector<std::int64_t> parent(n, -1);
    std::deque<std::uint32_t> frontier{from};
    while (!frontier.empty()) {
      const auto at = frontier.front();
      frontier.pop_front();
      for (auto e : out[at]) {
        if (!edges[e].chaining || parent[edges[e].to] != -1 || edges[e].to == from) continue;
        parent[edges[e].to] = e;
        frontier.push_back(edges[e].to);
      }
    }
    return parent;  // edge id into each reachable behaviour
  };
  std::vector<std::uint32_t> best;
  std::vector<std::vector<std::int64_t>> reach(n);
  constexpr std::size_t kMaxStarts = 256;
  std::size_t starts = 0;
  for (std::uint32_t s = 0; s < n && starts < kMaxStarts; ++s) {
    if (!remaining[s]) continue;
    ++starts;
    std::vector<std::int64_t> previous(n, -1);
    std::deque<std::uint32_t> frontier{s};
    bool closed = false;
    std::uint32_t last = s;
    while (!frontier.empty() && !closed) {
      const auto at = frontier.front();
      frontier.pop_front();
      if (reach[at].empty()) reach[at] = chain_reach(at);
      std::vector<std::uint32_t> successors;
      for (auto e : out[at]) successors.push_back(edges[e].to);
      for (std::uint32_t v = 0; v < n; ++v) {
        if (reach[at][v] != -1) successors.push_back(v);
      }
      for (auto v : successors) {
        if (v == s) {
          closed = true;
          last = at;
          break;
        }
        if (previous[v] == -1 && remaining[v]) {
          previous[v] = at;
          frontier.push_back(v);
        }
      }
    }
    if (!closed) continue;
    std::vector<std::uint32_t> cycle{last};
    while (cycle.back() != s) cycle.push_back(static_cast<std::uint32_t>(previous[cycle.back()]));
    std::reverse(cycle.begin(), cycle.end());
    if (best.empty() || cycle.size() < best.size()) best = cycle;
  }
  const auto& names = layer.behaviours;
  std::string text = names[best.front()].name.text;
  std::vector<Note> notes;
  const SourceLocation* report_at = nullptr;
  for (std::size_t i = 0; i < best.size(); ++i) {
    const auto from = best[i];
    const auto to = best[(i + 1) % best.size()];
    const Edge* declared = nullptr;
    for (auto e : out[from]) {
      if (edges[e].to == to && (declared == nullptr || edges[e].chaining)) declared = &edges[e];
    }
    if (declared != nullptr) {
      text += fmt::format(" {} {}", declared->chaining ? "=>" : "->", names[to].name.text);
      notes.push_back({fmt::format("{} {} {} declared at {}", names[from].name.text,
                                   declared->chaining ? "=>" : "->", names[to].name.text,
                                   to_string(declared->location)),
                       declared->location});
      if (report_at == nullptr || i + 1 == best.size()) report_at = &declared->location;
      continue;
    }
    text += fmt::format(" => {} (implicit)", names[to].name.text);
    std::vector<const Edge*> chain;
    for (auto at = to; at != from;) {
      const Edge& edge = edges[static_cast<std::size_t>(reach[from][at])];
      chain.push_back(&edge);
      at = edge.from;
    }
    std::reverse(chain.begin(), chain.end());
    std::string via = names[from].name.text;
    std::string declared_at;
    for (const Edge* edge : chain) {
      via += " => " + names[edge->to].name.text;
      declared_at += (declared_at.empty() ? "" : ", ") + to_string(edge->location);
    }
    // The chain's first link stands for it: a note links to one place.
    notes.push_back({fmt::format("{} => {} is implicit: chaining {} (declared at {})",
                                 names[from].name.text, names[to].name.text, via, declared_at),
                     chain.front()->location});
  }
  auto& error =
      diagnostics.error(report_at != nullptr ? *report_at : layer.name.location, "inhibition-cycle",
                        fmt::format("inhibition cycle in layer '{}': {}", layer.name.text, text));
  error.notes = std::move(notes);
}

}  // namespace

LayerGraph order_behaviours(const LayerDecl& layer, Diagnostics& diagnostics) {
  const std::size_t n = layer.behaviours.size();
  LayerGraph graph;
  graph.out.resize(n);
  std::unordered_map<std::string_view, std::uint32_t> index(2 * n);
  for (std::uint32_t i = 0; i < n; ++i) index[layer.behaviours[i].name.text] = i;
  std::vector<std::uint32_t> in_degree(n, 0);
  for (const auto& inhibition : layer.inhibitions) {
    const auto from = index.find(inhibition.inhibitor.text);
    const auto to = index.find(inhibition.inhibited.text);
    if (from == index.end() || to == index.end()) continue;
    graph.out[from->second].push_back(static_cast<std::uint32_t>(graph.edges.size()));
    ++in_degree[to->second];
    graph.edges.push_back({from->second, to->second, inhibition.chaining, inhibition.location});
  }
  std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, std::greater<>> ready;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (in_degree[i] == 0) ready.push(i);
  }
  while (!ready.empty()) {
    const std::uint32_t next = ready.top();
    ready.pop();
    graph.order.push_back(next);
    for (auto e : graph.out[next]) {
      if (--in_degree[graph.edges[e].to] == 0) ready.push(graph.edges[e].to);
    }
  }
  if (graph.order.size() != n) {
    std::vector<bool> remaining(n, true);
    for (auto i : graph.order) remaining[i] = false;
    report_cycle(layer, graph.edges, graph.out, remaining, diagnostics);
  }
  return graph;
}

void check_inhibition_cycles(const Model& model, Diagnostics& diagnostics) {
  for (const auto& layer : model.layers) order_behaviours(layer, diagnostics);
}

}  // namespace arbiter::detail

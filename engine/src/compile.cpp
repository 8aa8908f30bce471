#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <deque>
#include <mutex>
#include <queue>
#include <unordered_map>

#include "arbiter/init_context.hpp"
#include "arbiter/program.hpp"
#include "controller_builder.hpp"

namespace arbiter {

std::optional<std::uint32_t> Program::find_behaviour(std::string_view layer,
                                                     std::string_view name) const {
  for (const auto& compiled : layers) {
    if (compiled.name != layer) continue;
    for (std::uint32_t b = compiled.behaviour_begin; b < compiled.behaviour_end; ++b) {
      if (behaviours[b].name == name) return b;
    }
  }
  return std::nullopt;
}

Controller* Program::find_controller(std::string_view name) const {
  for (const auto& controller : controllers) {
    if (controller->name() == name) return controller.get();
  }
  return nullptr;
}

std::optional<std::uint32_t> Program::find_actuator(std::string_view name) const {
  for (std::uint32_t a = 0; a < actuators.size(); ++a) {
    if (actuators[a].name == name) return a;
  }
  return std::nullopt;
}

Inhibitions::Inhibitions(std::vector<std::string> files, std::vector<Declared> declared,
                         Recipes recipes, const std::vector<CompiledBehaviour>& behaviours)
    : files_(std::move(files)),
      declared_(std::move(declared)),
      recipes_(std::move(recipes)),
      behaviours_(behaviours.data()),
      lists_(std::make_shared<Lists>()) {
  recipes_.terms.shrink_to_fit();  // held for the program's life
  const std::size_t n = behaviours.size();
  declared_begin_.assign(n + 1, 0);
  chaining_out_begin_.assign(n + 1, 0);
  for (const auto& inhibition : declared_) {
    ++declared_begin_[inhibition.inhibited + 1];
    if (inhibition.chaining) ++chaining_out_begin_[inhibition.inhibitor + 1];
  }
  for (std::size_t b = 0; b < n; ++b) {
    declared_begin_[b + 1] += declared_begin_[b];
    chaining_out_begin_[b + 1] += chaining_out_begin_[b];
  }
  // declared_ is by inhibited, so each inhibitor's list comes out by inhibited too.
  chaining_out_.resize(chaining_out_begin_[n]);
  std::vector<std::uint32_t> fill(chaining_out_begin_.begin(), chaining_out_begin_.end() - 1);
  for (std::uint32_t d = 0; d < declared_.size(); ++d) {
    if (declared_[d].chaining) chaining_out_[fill[declared_[d].inhibitor]++] = d;
  }
  // A block term stands for its behaviour and everything chained to it.
  std::vector<std::size_t> chained(n, 0);
  closed_begin_.assign(n + 1, 0);
  for (std::size_t b = 0; b < n; ++b) {
    std::size_t count = 0;
    for (auto t = recipes_.begin[b]; t < recipes_.split[b]; ++t) {
      const std::uint32_t term = recipes_.terms[t];
      count += (term & 1u) != 0 ? 1 + chained[term >> 1] : 1;
    }
    chained[b] = count;
    closed_begin_[b + 1] = closed_begin_[b] + count + (recipes_.begin[b + 1] - recipes_.split[b]);
  }
}

void Inhibitions::closed(std::uint32_t behaviour, std::vector<std::uint32_t>& out) const {
  out.clear();
  const auto& [begin, split, terms] = recipes_;
  out.insert(out.end(), terms.begin() + begin[behaviour], terms.begin() + begin[behaviour + 1]);
  // `out` is its own work list: a block term expands into its behaviour's chained terms.
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::uint32_t term = out[i];
    const std::uint32_t of = term >> 1;
    out[i] = of;
    if ((term & 1u) != 0) {
      out.insert(out.end(), terms.begin() + begin[of], terms.begin() + split[of]);
    }
  }
  // The expansion is disjoint, so a large one is put in order through a bitmap of the range it
  // spans, in linear time (a long chain's behaviours each have thousands).
  constexpr std::size_t kSortBelow = 64;
  if (out.size() < kSortBelow) {
    std::sort(out.begin(), out.end());
    return;
  }
  const auto [low, high] = std::minmax_element(out.begin(), out.end());
  const std::uint32_t first = *low;
  std::vector<std::uint64_t> bits((*high - first) / 64 + 1, 0);
  for (const auto inhibitor : out)
    bits[(inhibitor - first) / 64] |= 1ull << ((inhibitor - first) % 64);
  out.clear();
  for (std::size_t w = 0; w < bits.size(); ++w) {
    for (std::uint64_t word = bits[w]; word != 0; word &= word - 1) {
      out.push_back(first + static_cast<std::uint32_t>(64 * w + __builtin_ctzll(word)));
    }
  }
}

std::vector<std::uint32_t> Inhibitions::closed(std::uint32_t behaviour) const {
  std::vector<std::uint32_t> out;
  out.reserve(closed_count(behaviour));
  closed(behaviour, out);
  return out;
}

const Inhibitions::Declared* Inhibitions::find_declared(std::uint32_t inhibitor,
                                                        std::uint32_t inhibited) const {
  if (inhibited + 1 >= declared_begin_.size()) return nullptr;
  const auto first = declared_.begin() + declared_begin_[inhibited];
  const auto last = declared_.begin() + declared_begin_[inhibited + 1];
  const auto found = std::lower_bound(
      first, last, inhibitor,
      [](const Declared& declared, std::uint32_t value) { return declared.inhibitor < value; });
  return found != last && found->inhibitor == inhibitor ? &*found : nullptr;
}

struct Inhibitions::Lists {
  std::once_flag declared_once;
  std::vector<CompiledInhibition> declared;  // as declared_
  std::once_flag all_once;
  std::vector<CompiledInhibition> all;
};

const CompiledInhibition* Inhibitions::declared(std::uint32_t inhibitor,
                                                std::uint32_t inhibited) const {
  const Declared* found = find_declared(inhibitor, inhibited);
  if (found == nullptr) return nullptr;
  std::call_once(lists_->declared_once, [&] {
    lists_->declared.reserve(declared_.size());
    for (const auto& declared : declared_) {
      lists_->declared.push_back(make(declared.inhibitor, declared.inhibited));
    }
  });
  return &lists_->declared[static_cast<std::size_t>(found - declared_.data())];
}

CompiledInhibition Inhibitions::make(std::uint32_t inhibitor, std::uint32_t inhibited) const {
  CompiledInhibition inhibition;
  inhibition.inhibitor = inhibitor;
  inhibition.inhibited = inhibited;
  if (const Declared* declared = find_declared(inhibitor, inhibited)) {
    inhibition.chaining = declared->chaining;
    inhibition.location = {files_[declared->file], declared->line, declared->column};
  } else {
    inhibition.chaining = true;
    inhibition.implicit = true;
    inhibition.location = behaviours_[inhibited].location;
  }
  return inhibition;
}

std::vector<CompiledInhibition> Inhibitions::of(std::uint32_t behaviour) const {
  std::vector<CompiledInhibition> out;
  for (const auto inhibitor : closed(behaviour)) out.push_back(make(inhibitor, behaviour));
  return out;
}

const std::vector<CompiledInhibition>& Inhibitions::list() const {
  static const std::vector<CompiledInhibition> kNone;
  if (!lists_) return kNone;
  std::call_once(lists_->all_once, [&] {
    lists_->all.reserve(size());
    std::vector<std::uint32_t> inhibitors;
    for (std::uint32_t b = 0; b + 1 < closed_begin_.size(); ++b) {
      closed(b, inhibitors);
      for (const auto inhibitor : inhibitors) lists_->all.push_back(make(inhibitor, b));
    }
  });
  return lists_->all;
}

std::vector<std::uint32_t> Inhibitions::chain(std::uint32_t from, std::uint32_t to) const {
  // Breadth-first over declared chaining inhibitions: the shortest chain explains best.
  std::unordered_map<std::uint32_t, std::uint32_t> parent{{from, from}};
  std::deque<std::uint32_t> frontier{from};
  while (!frontier.empty()) {
    const std::uint32_t at = frontier.front();
    frontier.pop_front();
    if (at == to) break;
    for (auto i = chaining_out_begin_[at]; i < chaining_out_begin_[at + 1]; ++i) {
      const std::uint32_t next = declared_[chaining_out_[i]].inhibited;
      if (parent.emplace(next, at).second) frontier.push_back(next);
    }
  }
  if (parent.count(to) == 0 || from == to) return {};
  std::vector<std::uint32_t> path{to};
  while (path.back() != from) path.push_back(parent[path.back()]);
  std::reverse(path.begin(), path.end());
  return path;
}

namespace {

struct Edge {
  std::uint32_t from = 0;  // declaration indices within the layer
  std::uint32_t to = 0;
  bool chaining = false;
  SourceLocation location;
};

/// Who steps each controller, filled as behaviours and states claim them.
struct Claim {
  bool claimed = false;
  std::uint32_t layer = kUnbound;  ///< the layer whose sensors the states read
  std::uint32_t owner = kUnbound;  ///< the behaviour whose outputs the states write through
};

/// What an instance being initialised belongs to, beyond its layer.
/// Lookups shared by every instance's init, so that binding stays linear in the config's size.
struct Bindings {
  std::unordered_map<std::string, std::uint32_t> actuator;  ///< name → actuator index
  std::unordered_map<std::uint64_t, std::uint32_t> slot;    ///< (actuator, owner) → writer slot
};

struct InitScope {
  Bindings* bindings = nullptr;
  std::vector<Claim>* claims = nullptr;
  Controller* controller = nullptr;            ///< for states: their controller
  const StateMachineDecl* machine = nullptr;   ///< ... and its declaration
  const std::vector<Name>* sensors = nullptr;  ///< the layer's sensors as declared, if it has one
};

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
  std::vector<std::string> notes;
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
      notes.push_back(fmt::format("{} {} {} declared at {}", names[from].name.text,
                                  declared->chaining ? "=>" : "->", names[to].name.text,
                                  to_string(declared->location)));
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
    notes.push_back(fmt::format("{} => {} is implicit: chaining {} (declared at {})",
                                names[from].name.text, names[to].name.text, via, declared_at));
  }
  auto& error =
      diagnostics.error(report_at != nullptr ? *report_at : layer.name.location, "inhibition-cycle",
                        fmt::format("inhibition cycle in layer '{}': {}", layer.name.text, text));
  error.notes = std::move(notes);
}

/// A layer's declared inhibitions as a graph over its behaviours (declaration indices), and
/// their topological order.
struct LayerGraph {
  std::vector<Edge> edges;
  std::vector<std::vector<std::uint32_t>> out;  // edge ids by inhibitor
  std::vector<std::uint32_t> order;             // all behaviours, unless there is a cycle
};

/// Kahn's algorithm, always taking the ready behaviour declared first; reports a cycle.
/// Inhibitions naming no valid behaviour (in a model with errors) are left out.
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

/// A declared inhibition of one layer between topological positions.
struct PositionEdge {
  std::uint32_t from = 0;
  std::uint32_t to = 0;
  bool chaining = false;
  const SourceLocation* location = nullptr;
};

/// The chaining closure of one layer, turned into refinement recipes (Inhibitions::recipes()).
/// chained(p), the behaviours with a chain of chaining inhibitions to p, is a bitset over earlier
/// positions, kept only for behaviours on a chaining inhibition and only as wide as their
/// position: at most n²/16 bytes, and only while compiling.
class LayerClosure {
 public:
  LayerClosure(std::size_t n, std::vector<PositionEdge> edges) : n_(n), edges_(std::move(edges)) {
    // A pair declared both ways counts as chaining (docs/semantics.md, "Inhibitions and their
    // closure"). The model merges duplicates; this keeps the closure right whatever it is given.
    std::sort(edges_.begin(), edges_.end(), [](const PositionEdge& a, const PositionEdge& b) {
      if (a.to != b.to) return a.to < b.to;
      if (a.from != b.from) return a.from < b.from;
      return a.chaining > b.chaining;
    });
    edges_.erase(std::unique(edges_.begin(), edges_.end(),
                             [](const PositionEdge& a, const PositionEdge& b) {
                               return a.to == b.to && a.from == b.from;
                             }),
                 edges_.end());
    in_begin_.assign(n_ + 1, 0);
    for (const auto& edge : edges_) ++in_begin_[edge.to + 1];
    for (std::size_t p = 0; p < n_; ++p) in_begin_[p + 1] += in_begin_[p];

    offset_.assign(n_, kNone);
    for (const auto& edge : edges_) {
      if (edge.chaining) offset_[edge.from] = offset_[edge.to] = 0;
    }
    std::size_t total = 0;
    for (std::size_t p = 0; p < n_; ++p) {
      if (offset_[p] == kNone) continue;
      offset_[p] = total;
      total += words(p);
    }
    bits_.assign(total, 0);
    size_.assign(n_, 0);
    for (std::uint32_t p = 0; p < n_; ++p) {
      if (offset_[p] == kNone) continue;
      std::uint64_t* mine = chained(p);
      for (auto e = in_begin_[p]; e < in_begin_[p + 1]; ++e) {
        if (!edges_[e].chaining) continue;
        const std::uint32_t q = edges_[e].from;
        const std::uint64_t* theirs = chained(q);
        for (std::size_t w = 0; w < words(q); ++w) mine[w] |= theirs[w];
        mine[q / 64] |= bit(q);
      }
      for (std::size_t w = 0; w < words(p); ++w) {
        size_[p] += static_cast<std::uint32_t>(__builtin_popcountll(mine[w]));
      }
    }
  }

  /// The declared inhibitions, by inhibited, then inhibitor; duplicates merged.
  const std::vector<PositionEdge>& edges() const { return edges_; }

  /// Appends one recipe per behaviour, in position order; behaviour indices start at `base`.
  /// The chained part takes the chaining inhibitor with the largest closed set as one block,
  /// then covers the rest of chained(p) greedily: an inhibitor whose closed set is disjoint
  /// from what is covered is one more block; one that overlaps it is a single term, and its own
  /// chaining inhibitors are looked at in turn.
  void append_recipes(std::uint32_t base, Inhibitions::Recipes& recipes) const {
    std::vector<std::uint64_t> covered(n_ / 64 + 1, 0);
    std::vector<std::uint32_t> visited(n_, 0);  // p + 1 once looked at for p
    std::vector<std::uint32_t> pending;
    std::vector<std::uint32_t> parents;
    auto& terms = recipes.terms;
    const auto single = [&](std::uint32_t q) { return 2 * (base + q); };
    const auto block = [&](std::uint32_t q) { return 2 * (base + q) + 1; };
    const auto cover = [&](std::uint32_t q) {
      const std::uint64_t* theirs = chained(q);
      for (std::size_t w = 0; w < words(q); ++w) covered[w] |= theirs[w];
      covered[q / 64] |= bit(q);
    };
    for (std::uint32_t p = 0; p < n_; ++p) {
      const std::size_t first = terms.size();
      chaining_parents(p, pending);
      if (pending.size() == 1) {
        terms.push_back(block(pending[0]));
      } else if (!pending.empty()) {
        std::fill(covered.begin(), covered.begin() + static_cast<std::ptrdiff_t>(words(p)), 0);
        terms.push_back(block(pending.back()));
        cover(pending.back());
        pending.pop_back();
        while (!pending.empty()) {  // the largest closed set first
          const std::uint32_t q = pending.back();
          pending.pop_back();
          if (visited[q] == p + 1) continue;  // covered when it was first looked at
          visited[q] = p + 1;
          const bool self = (covered[q / 64] & bit(q)) != 0;
          bool inside = self;
          bool outside = !self;
          const std::uint64_t* theirs = chained(q);
          for (std::size_t w = 0; w < words(q) && !(inside && outside); ++w) {
            inside = inside || (theirs[w] & covered[w]) != 0;
            outside = outside || (theirs[w] & ~covered[w]) != 0;
          }
          if (!outside) continue;
          if (!inside) {
            terms.push_back(block(q));
            cover(q);
            continue;
          }
          if (!self) {
            terms.push_back(single(q));
            covered[q / 64] |= bit(q);
          }
          chaining_parents(q, parents);
          pending.insert(pending.end(), parents.begin(), parents.end());
        }
      }
      std::sort(terms.begin() + static_cast<std::ptrdiff_t>(first), terms.end());
      recipes.split.push_back(static_cast<std::uint32_t>(terms.size()));
      const std::size_t rest = terms.size();
      for (auto e = in_begin_[p]; e < in_begin_[p + 1]; ++e) {
        const std::uint32_t q = edges_[e].from;
        if (edges_[e].chaining) continue;
        if (offset_[p] != kNone && (chained(p)[q / 64] & bit(q)) != 0) continue;
        terms.push_back(single(q));
      }
      std::sort(terms.begin() + static_cast<std::ptrdiff_t>(rest), terms.end());
      recipes.begin.push_back(static_cast<std::uint32_t>(terms.size()));
    }
  }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  static std::size_t words(std::size_t p) { return p / 64 + 1; }
  static std::uint64_t bit(std::size_t p) { return std::uint64_t{1} << (p % 64); }
  std::uint64_t* chained(std::size_t p) { return bits_.data() + offset_[p]; }
  const std::uint64_t* chained(std::size_t p) const { return bits_.data() + offset_[p]; }

  // p's chaining inhibitors, the one with the fewest chained behaviours first.
  void chaining_parents(std::uint32_t p, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (auto e = in_begin_[p]; e < in_begin_[p + 1]; ++e) {
      if (edges_[e].chaining) out.push_back(edges_[e].from);
    }
    std::sort(out.begin(), out.end(), [&](std::uint32_t a, std::uint32_t b) {
      return size_[a] != size_[b] ? size_[a] < size_[b] : a < b;
    });
  }

  std::size_t n_;
  std::vector<PositionEdge> edges_;
  std::vector<std::uint32_t> in_begin_;  // edges_ by inhibited
  std::vector<std::size_t> offset_;      // into bits_; kNone off the chaining inhibitions
  std::vector<std::uint64_t> bits_;
  std::vector<std::uint32_t> size_;  // |chained(p)|
};

/// What every class's init() may do; the behaviour's and the state's contexts below add theirs.
template <typename Base>
class InstanceInit : public Base {
 public:
  InstanceInit(Program& program, const Registry& registry, Diagnostics& diagnostics,
               const CompiledLayer& layer, std::uint32_t owner, const std::string& name,
               const SourceLocation& location, const ClassInfo& cls, const ParamSet& params,
               const std::vector<PortBinding>& ports, InitScope scope = {})
      : program_(program),
        registry_(registry),
        diagnostics_(diagnostics),
        layer_(layer),
        owner_(owner),
        name_(name),
        location_(location),
        cls_(cls),
        params_(params),
        ports_(ports),
        scope_(scope) {}

  const std::string& name() const override { return name_; }
  const SourceLocation& location() const override { return location_; }
  double rate_hz() const override { return program_.rate_hz; }

  SourceLocation param_location(std::string_view param_name) const override {
    const Param* param = params_.find(param_name);
    return param != nullptr ? param->location : location_;
  }

  AnyOutput output_to_actuator(const std::string& actuator, const SourceLocation& at) override {
    std::vector<std::string> own;
    for (std::uint32_t a = layer_.actuator_begin; a < layer_.actuator_end; ++a) {
      if (program_.actuators[a].name == actuator) return {slot_for(a), program_.actuators[a].type};
      own.push_back(program_.actuators[a].name);
    }
    auto& diagnostic =
        error_at(at, "unknown-actuator",
                 fmt::format("'{}' is not an actuator of layer '{}'", actuator, layer_.name));
    if (const auto other = program_.find_actuator(actuator)) {
      diagnostic.notes.push_back(
          fmt::format("'{}' is an actuator of layer '{}'; a behaviour writes only to actuators "
                      "of its own layer",
                      actuator, program_.layers[program_.actuators[*other].layer].name));
      return {};
    }
    const auto hint = suggest(actuator, own);
    diagnostic.notes.push_back(hint.empty() ? "the layer declares no actuators" : hint);
    return {};
  }

  std::vector<LayerItem> layer_actuators() const override {
    std::vector<LayerItem> items;
    for (std::uint32_t a = layer_.actuator_begin; a < layer_.actuator_end; ++a) {
      const CompiledActuator& actuator = program_.actuators[a];
      items.push_back({actuator.name, actuator.type, actuator.location});
    }
    return items;
  }

  std::vector<LayerItem> layer_sensors() const override {
    std::vector<LayerItem> items;
    for (std::size_t s = 0; s < layer_.sensors.size(); ++s) {
      const CompiledActuator& actuator = program_.actuators[layer_.sensors[s]];
      const bool named = scope_.sensors != nullptr && s < scope_.sensors->size();
      items.push_back(
          {actuator.name, actuator.type, named ? (*scope_.sensors)[s].location : location_});
    }
    return items;
  }

  ValueBox make_value(const ValueType& type, const Node& node) override {
    ValueBox box(type);
    std::string expected;
    if (!type.from_node(node, box.data(), expected)) {
      error_at(node.location(), "wrong-type",
               fmt::format("{} '{}' ({}) needs {} ({}) here, found {}", to_string(cls_.kind), name_,
                           cls_.name, expected, type.name, node.describe()));
      return {};
    }
    return box;
  }

  Diagnostic& error(const SourceLocation& at, std::string message) override {
    return error_at(at, "class-error", std::move(message));
  }
  Diagnostic& warning(const SourceLocation& at, std::string message) override {
    return diagnostics_.warning(at, "class-warning", std::move(message));
  }

 protected:
  const ParamValue* find_param(std::string_view param_name,
                               const std::type_info& requested) override {
    const ParamSpec* spec = cls_.find_param(param_name);
    const Param* param = params_.find(param_name);
    if (spec == nullptr || param == nullptr) {
      error_at(
          location_, "class-error",
          fmt::format("class {} reads param '{}' that it does not declare", cls_.name, param_name));
      return nullptr;
    }
    const bool matches =
        std::visit([&](const auto& value) { return typeid(value) == requested; }, param->value);
    if (!matches) {
      error_at(location_, "class-error",
               fmt::format("class {} reads param '{}' ({}) as a different C++ type", cls_.name,
                           param_name, to_string(spec->kind)));
      return nullptr;
    }
    return &param->value;
  }

  std::uint32_t resolve_port(std::string_view port, PortDirection direction,
                             const std::type_info& type) override {
    for (const auto& binding : ports_) {
      if (binding.port->name != port) continue;
      if (binding.port->direction != direction || *binding.port->cpp_type != type) {
        error_at(location_, "class-error",
                 fmt::format("class {} resolves port '{}' with a different direction or type "
                             "than it declares",
                             cls_.name, port));
        return kUnbound;
      }
      if (binding.target.empty()) return kUnbound;
      const auto actuator = scope_.bindings->actuator.find(binding.target);
      if (actuator == scope_.bindings->actuator.end()) return kUnbound;
      return direction == PortDirection::kInput ? actuator->second : slot_for(actuator->second);
    }
    error_at(location_, "class-error",
             fmt::format("class {} resolves port '{}' that it does not declare", cls_.name, port));
    return kUnbound;
  }

  std::uint32_t resolve_sensor(const std::string& sensor, const std::type_info& type,
                               const SourceLocation& at) override {
    std::vector<std::string> own;
    for (const auto a : layer_.sensors) {
      const CompiledActuator& actuator = program_.actuators[a];
      if (actuator.name != sensor) {
        own.push_back(actuator.name);
        continue;
      }
      if (actuator.type->cpp_type != nullptr && *actuator.type->cpp_type == type) return a;
      error_at(at, "class-error",
               fmt::format("class {} reads sensor '{}' ({}) as a different C++ type", cls_.name,
                           sensor, actuator.type->name));
      return kUnbound;
    }
    auto& diagnostic =
        error_at(at, "unknown-actuator",
                 fmt::format("'{}' is not a sensor of layer '{}'", sensor, layer_.name));
    const auto hint = suggest(sensor, own);
    diagnostic.notes.push_back(hint.empty() ? "the layer reads no sensors" : hint);
    return kUnbound;
  }

 protected:
  Diagnostic& error_at(const SourceLocation& at, std::string code, std::string message) {
    return diagnostics_.error(at, std::move(code), std::move(message));
  }

  std::uint32_t slot_for(std::uint32_t actuator) {
    const std::uint64_t key = (std::uint64_t{actuator} << 32) | owner_;
    const auto [found, fresh] =
        scope_.bindings->slot.emplace(key, static_cast<std::uint32_t>(program_.slots.size()));
    if (fresh) program_.slots.push_back({actuator, owner_, 0});
    return found->second;
  }

  Program& program_;
  const Registry& registry_;
  Diagnostics& diagnostics_;
  const CompiledLayer& layer_;
  std::uint32_t owner_;
  const std::string& name_;
  const SourceLocation& location_;
  const ClassInfo& cls_;
  const ParamSet& params_;
  const std::vector<PortBinding>& ports_;
  InitScope scope_;
};

class BehaviourInit final : public InstanceInit<BehaviourInitContext> {
 public:
  using InstanceInit::InstanceInit;

  Controller* claim_controller(const std::string& machine, const SourceLocation& at) override {
    std::vector<std::string> known;
    for (std::uint32_t c = 0; c < program_.controllers.size(); ++c) {
      Controller& controller = *program_.controllers[c];
      known.push_back(controller.name());
      if (controller.name() != machine) continue;
      Claim& claim = (*scope_.claims)[c];
      if (claim.claimed) {
        error_at(at, "machine-owned-twice",
                 fmt::format("state machine '{}' already has an owner; a controller is stepped "
                             "by one owner only",
                             machine));
        return nullptr;
      }
      const bool in_program = !program_.layers.empty() && &layer_ >= &program_.layers.front() &&
                              &layer_ <= &program_.layers.back();
      claim = {true,
               in_program ? static_cast<std::uint32_t>(&layer_ - program_.layers.data()) : kUnbound,
               owner_};
      ControllerBuilder(controller).set_owned(owner_);
      return &controller;
    }
    auto& error =
        error_at(at, "unknown-machine", fmt::format("no state machine named '{}'", machine));
    const auto hint = suggest(machine, known);
    error.notes.push_back(hint.empty() ? "the config declares no state_machines" : hint);
    return nullptr;
  }
};

class StateInit final : public InstanceInit<StateInitContext> {
 public:
  using InstanceInit::InstanceInit;

  bool plan_state(const std::string& state, const Node* params, const SourceLocation& at,
                  PlannedState& out) override {
    const std::uint32_t s = find_declared(state, at);
    if (s == kUnbound) return false;
    const StateDecl& decl = scope_.machine->states[s];
    const std::size_t errors = diagnostics_.error_count();
    out.params = check_state_params(decl, params, at, registry_, diagnostics_);
    out.state = s;
    index_params(*decl.cls, out);
    return diagnostics_.error_count() == errors;
  }

 protected:
  std::uint32_t resolve_param(std::string_view param_name, ParamKind kind) override {
    const ParamSpec* spec = cls_.find_param(param_name);
    if (spec == nullptr) {
      std::vector<std::string> known;
      for (const auto& declared : cls_.params) known.push_back(declared.name);
      auto& error = error_at(
          location_, "class-error",
          fmt::format("class {} reads param '{}' that it does not declare", cls_.name, param_name));
      const auto hint = suggest(param_name, known);
      if (!hint.empty()) error.notes.push_back(hint);
      return kUnbound;
    }
    if (spec->kind != kind) {
      error_at(location_, "class-error",
               fmt::format("class {} reads param '{}' ({}) through a handle of kind {}", cls_.name,
                           param_name, to_string(spec->kind), to_string(kind)));
      return kUnbound;
    }
    return static_cast<std::uint32_t>(spec - cls_.params.data());
  }

  std::uint32_t resolve_state(const std::string& state, const std::string_view* params,
                              const ParamKind* kinds, std::size_t count, std::uint32_t* indices,
                              const SourceLocation& at) override {
    const std::uint32_t s = find_declared(state, at);
    if (s == kUnbound) return kUnbound;
    const StateDecl& decl = scope_.machine->states[s];
    const ClassInfo& cls = *decl.cls;
    const std::size_t errors = diagnostics_.error_count();
    std::vector<std::string> known;
    for (const auto& declared : cls.params) known.push_back(declared.name);
    for (std::size_t i = 0; i < count; ++i) {
      const ParamSpec* spec = cls.find_param(params[i]);
      if (spec == nullptr) {
        auto& error = error_at(at, "class-error",
                               fmt::format("class {} plans state '{}' ({}) with param '{}', which "
                                           "its class does not declare",
                                           cls_.name, state, cls.name, params[i]));
        const auto hint = suggest(params[i], known);
        if (!hint.empty()) error.notes.push_back(hint);
        continue;
      }
      indices[i] = static_cast<std::uint32_t>(spec - cls.params.data());
      if (spec->kind != kinds[i]) {
        error_at(
            at, "class-error",
            fmt::format("class {} plans param '{}' ({}) of state '{}' in a slot of kind {}",
                        cls_.name, params[i], to_string(spec->kind), state, to_string(kinds[i])));
      }
      for (std::size_t j = 0; j < i; ++j) {
        if (params[j] == params[i]) {
          error_at(at, "class-error",
                   fmt::format("class {} plans param '{}' of state '{}' twice", cls_.name,
                               params[i], state));
        }
      }
    }
    for (std::size_t p = 0; p < cls.params.size(); ++p) {
      const ParamSpec& spec = cls.params[p];
      if (!spec.required() || decl.params.find(spec.name) != nullptr) continue;
      bool slotted = false;
      for (std::size_t i = 0; i < count; ++i) slotted = slotted || params[i] == spec.name;
      if (!slotted) {
        error_at(at, "class-error",
                 fmt::format("class {} plans state '{}' without its required param '{}'; give "
                             "it a slot or set it on the state",
                             cls_.name, state, spec.name));
      }
    }
    return diagnostics_.error_count() == errors ? s : kUnbound;
  }

 private:
  // A state of this state's machine, reported at `at` when there is none.
  std::uint32_t find_declared(const std::string& state, const SourceLocation& at) {
    std::vector<std::string> known;
    for (std::uint32_t s = 0; s < scope_.machine->states.size(); ++s) {
      const StateDecl& decl = scope_.machine->states[s];
      if (decl.name.text == state) return s;
      known.push_back(decl.name.text);
    }
    auto& error = error_at(
        at, "unknown-state",
        fmt::format("state machine '{}' has no state '{}'", scope_.machine->name.text, state));
    const auto hint = suggest(state, known);
    if (!hint.empty()) error.notes.push_back(hint);
    return kUnbound;
  }
};

class Compiler {
 public:
  Compiler(const Model& model, const Registry& registry, Diagnostics& diagnostics)
      : model_(model), registry_(registry), diagnostics_(diagnostics) {}

  std::optional<Program> run() {
    program_.libraries = registry_.libraries();
    program_.name = model_.name;
    program_.rate_hz = model_.rate_hz;
    program_.steps = model_.steps;
    program_.on_exception = model_.on_exception;
    std::size_t behaviours = 0;
    std::size_t inhibitions = 0;
    for (const auto& layer : model_.layers) {
      behaviours += layer.behaviours.size();
      inhibitions += layer.inhibitions.size();
    }
    program_.behaviours.reserve(behaviours);
    sources_.reserve(behaviours);
    declared_.reserve(inhibitions);
    recipes_.begin.reserve(behaviours + 1);
    recipes_.split.reserve(behaviours);
    recipes_.terms.reserve(inhibitions);
    recipes_.begin.push_back(0);
    declare_actuators();
    for (const auto& layer : model_.layers) order_layer(layer);
    if (diagnostics_.has_errors()) return std::nullopt;
    // Recipe terms index two factors per behaviour in 32 bits.
    assert(program_.behaviours.size() < (std::size_t{1} << 31));
    program_.inhibitions = Inhibitions(std::move(files_), std::move(declared_), std::move(recipes_),
                                       program_.behaviours);
    declare_controllers();
    for (std::size_t l = 0; l < model_.layers.size(); ++l) instantiate(model_.layers[l], l);
    if (diagnostics_.has_errors()) return std::nullopt;
    build_controllers();
    if (diagnostics_.has_errors()) return std::nullopt;
    lay_out_values();
    return std::move(program_);
  }

 private:
  void declare_actuators() {
    for (const auto& layer : model_.layers) {
      CompiledLayer compiled;
      compiled.name = layer.name.text;
      compiled.location = layer.name.location;
      compiled.normalise = layer.normalise.value_or(model_.normalise);
      compiled.interface_class = layer.interface;
      compiled.actuator_begin = static_cast<std::uint32_t>(program_.actuators.size());
      for (const auto& actuator : layer.actuators) {
        CompiledActuator out;
        out.name = actuator.name.text;
        out.type = actuator.type;
        out.aggregate = actuator.aggregate;
        out.layer = static_cast<std::uint32_t>(program_.layers.size());
        out.default_value = actuator.default_value;
        out.safe_value = actuator.safe_value;
        out.location = actuator.name.location;
        bindings_.actuator.emplace(out.name, static_cast<std::uint32_t>(program_.actuators.size()));
        program_.actuators.push_back(std::move(out));
      }
      compiled.actuator_end = static_cast<std::uint32_t>(program_.actuators.size());
      program_.layers.push_back(std::move(compiled));
    }
    for (std::size_t l = 0; l < model_.layers.size(); ++l) {
      for (const auto& sensor : model_.layers[l].sensors) {
        program_.layers[l].sensors.push_back(bindings_.actuator.at(sensor.text));
      }
    }
  }

  // Topological order, closure and the layer's inhibitions, or a cycle error.
  void order_layer(const LayerDecl& layer) {
    const std::size_t n = layer.behaviours.size();
    const auto base = static_cast<std::uint32_t>(program_.behaviours.size());
    CompiledLayer& compiled = program_.layers[&layer - model_.layers.data()];
    compiled.behaviour_begin = base;

    const LayerGraph graph = order_behaviours(layer, diagnostics_);
    if (graph.order.size() != n) {
      compiled.behaviour_end = base;
      return;
    }
    const auto& edges = graph.edges;
    const auto& order = graph.order;
    std::vector<std::uint32_t> position(n, 0);
    for (std::uint32_t p = 0; p < n; ++p) position[order[p]] = p;

    for (std::uint32_t p = 0; p < n; ++p) {
      const BehaviourDecl& decl = layer.behaviours[order[p]];
      sources_.push_back(&decl);
      CompiledBehaviour behaviour;
      behaviour.name = decl.name.text;
      behaviour.cls = decl.cls;
      behaviour.location = decl.location;
      behaviour.on_exception = decl.on_exception.value_or(model_.on_exception);
      behaviour.layer = static_cast<std::uint32_t>(&compiled - program_.layers.data());
      program_.behaviours.push_back(std::move(behaviour));
    }
    compiled.behaviour_end = static_cast<std::uint32_t>(program_.behaviours.size());

    std::vector<PositionEdge> by_position;
    by_position.reserve(edges.size());
    for (const auto& edge : edges) {
      by_position.push_back(
          {position[edge.from], position[edge.to], edge.chaining, &edge.location});
    }
    LayerClosure closure(n, std::move(by_position));
    closure.append_recipes(base, recipes_);
    for (const auto& edge : closure.edges()) {
      const SourceLocation& at = *edge.location;
      const auto file = file_index_.emplace(at.file, static_cast<std::uint32_t>(files_.size()));
      if (file.second) files_.push_back(at.file);
      declared_.push_back({base + edge.from, base + edge.to, file.first->second, at.line, at.column,
                           edge.chaining});
    }
  }

  void instantiate(const LayerDecl& decl, std::size_t l) {
    CompiledLayer& layer = program_.layers[l];
    if (decl.interface != nullptr) {
      layer.interface = decl.interface->make_interface();
      InstanceInit<InitContext> init(
          program_, registry_, diagnostics_, layer, kUnbound, layer.name, layer.location,
          *decl.interface, decl.params, decl.ports,
          InitScope{&bindings_, &claims_, nullptr, nullptr, &decl.sensors});
      guarded_init(diagnostics_, *decl.interface, layer.location,
                   [&] { layer.interface->init(init); });
      return;
    }
    // Initialised in declaration order, not execution order: the writer slots their outputs get
    // then do not move when an edit only reorders the layer (a flipped inhibition), so a hot
    // reload keeps those behaviours' instances (their handles are unchanged).
    std::vector<std::uint32_t> by_declaration;
    for (std::uint32_t b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
      by_declaration.push_back(b);
    }
    std::sort(by_declaration.begin(), by_declaration.end(), [&](std::uint32_t a, std::uint32_t b) {
      return std::less<const BehaviourDecl*>()(sources_[a], sources_[b]);
    });
    for (const std::uint32_t b : by_declaration) {
      CompiledBehaviour& behaviour = program_.behaviours[b];
      const BehaviourDecl* source = sources_[b];
      behaviour.instance = behaviour.cls->make_behaviour();
      BehaviourInit init(program_, registry_, diagnostics_, layer, b, behaviour.name,
                         behaviour.location, *behaviour.cls, source->params, source->ports,
                         InitScope{&bindings_, &claims_, nullptr, nullptr, &decl.sensors});
      guarded_init(diagnostics_, *behaviour.cls, behaviour.location,
                   [&] { behaviour.instance->init(init); });
    }
  }

  template <typename F>
  void guarded_init(Diagnostics& into, const ClassInfo& cls, const SourceLocation& at, F&& init) {
    try {
      init();
    } catch (const std::exception& error) {
      into.error(at, "init-failed",
                 fmt::format("class {} failed to initialise: {}", cls.name, error.what()));
    } catch (...) {
      into.error(at, "init-failed",
                 fmt::format("class {} failed to initialise (unknown exception)", cls.name));
    }
  }

  void declare_controllers() {
    for (const auto& machine : model_.state_machines) {
      auto controller =
          std::make_unique<Controller>(machine.name.text, machine.location, machine.capacity);
      for (const auto& state : machine.states) {
        CompiledState compiled;
        compiled.name = state.name.text;
        compiled.cls = state.cls;
        compiled.location = state.location;
        compiled.params = state.params.items;
        ControllerBuilder(*controller).add_state(std::move(compiled));
      }
      program_.controllers.push_back(std::move(controller));
    }
    claims_.assign(program_.controllers.size(), Claim{});
  }

  // Children inherit their parent's layer and owner; then every pooled state is initialised
  // against that layer.
  void build_controllers() {
    const auto index_of = [&](const std::string& name) {
      for (std::uint32_t c = 0; c < model_.state_machines.size(); ++c) {
        if (model_.state_machines[c].name.text == name) return c;
      }
      return kUnbound;
    };
    std::vector<std::uint32_t> parent(program_.controllers.size(), kUnbound);
    for (std::uint32_t c = 0; c < model_.state_machines.size(); ++c) {
      Controller& controller = *program_.controllers[c];
      std::vector<Controller*> children;
      const auto& decl = model_.state_machines[c];
      for (std::uint32_t s = 0; s < decl.states.size(); ++s) {
        if (!decl.states[s].machine) continue;
        const auto child = index_of(decl.states[s].machine->text);
        if (child == kUnbound) continue;
        if (claims_[child].claimed) {
          diagnostics_.error(decl.states[s].machine->location, "machine-owned-twice",
                             fmt::format("state machine '{}' is stepped by a behaviour and "
                                         "cannot also be the child of state '{}'",
                                         decl.states[s].machine->text, decl.states[s].name.text));
          continue;
        }
        ControllerBuilder(*program_.controllers[child]).set_owned();
        parent[child] = c;
        ControllerBuilder(controller)
            .set_state_child(s, static_cast<std::uint32_t>(children.size()));
        children.push_back(program_.controllers[child].get());
      }
      ControllerBuilder(controller).set_children(std::move(children));
    }
    for (std::uint32_t c = 0; c < program_.controllers.size(); ++c) {
      auto root = c;
      while (parent[root] != kUnbound && !claims_[root].claimed) root = parent[root];
      if (root != c) claims_[c] = {true, claims_[root].layer, claims_[root].owner};
    }
    static const CompiledLayer kNoLayer;
    for (std::uint32_t c = 0; c < program_.controllers.size(); ++c) {
      Controller& controller = *program_.controllers[c];
      const StateMachineDecl& decl = model_.state_machines[c];
      const Claim& claim = claims_[c];
      const CompiledLayer& layer =
          claim.layer == kUnbound ? kNoLayer : program_.layers[claim.layer];
      const std::vector<Name>* sensors =
          claim.layer == kUnbound ? nullptr : &model_.layers[claim.layer].sensors;
      std::vector<ParamSet> params(decl.states.size());
      std::vector<std::vector<PortBinding>> ports(decl.states.size());
      for (std::uint32_t s = 0; s < decl.states.size(); ++s) {
        params[s] = with_defaults(decl.states[s]);
        ports[s] = bind_state_ports(decl.states[s], layer);
      }
      std::vector<PlannedState> initial;
      for (const auto& entry : decl.queue) {
        const auto s = find_state(controller, entry.state.text);
        if (s) initial.push_back({*s, entry.overrides, {}});
      }
      ControllerBuilder(controller).set_initial_queue(std::move(initial));
      for (const auto& preemption : decl.preempt) {
        const auto s = find_state(controller, preemption.go_to.state.text);
        if (s) {
          ControllerBuilder(controller)
              .add_preemption(preemption.cycle, {*s, preemption.go_to.overrides, {}});
        }
      }
      std::vector<bool> reported(decl.states.size(), false);
      ControllerBuilder(controller).build_pool([&](std::uint32_t s, State& state) {
        // Every pooled object is initialised alike; report problems once, for the first.
        Diagnostics repeat;
        StateInit init(program_, registry_, reported[s] ? repeat : diagnostics_, layer, claim.owner,
                       decl.states[s].name.text, decl.states[s].location, *decl.states[s].cls,
                       params[s], ports[s],
                       InitScope{&bindings_, &claims_, &controller, &decl, sensors});
        guarded_init(reported[s] ? repeat : diagnostics_, *decl.states[s].cls,
                     decl.states[s].location, [&] { state.init(init); });
        reported[s] = true;
      });
    }
  }

  static ParamSet with_defaults(const StateDecl& state) {
    ParamSet set;
    for (const auto& spec : state.cls->params) {
      if (const Param* given = state.params.find(spec.name)) {
        set.items.push_back(*given);
      } else if (spec.default_value) {
        set.items.push_back({spec.name, *spec.default_value, state.location, true});
      }
    }
    return set;
  }

  // A state's ports bind by name to its owner's layer: sensors for inputs, actuators for outputs.
  std::vector<PortBinding> bind_state_ports(const StateDecl& state, const CompiledLayer& layer) {
    std::vector<PortBinding> bindings;
    for (const auto& spec : state.cls->ports) {
      PortBinding binding{&spec, {}, state.location};
      std::optional<std::uint32_t> actuator;
      if (spec.direction == PortDirection::kInput) {
        for (auto sensor : layer.sensors) {
          if (program_.actuators[sensor].name == spec.name) actuator = sensor;
        }
      } else {
        for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
          if (program_.actuators[a].name == spec.name) actuator = a;
        }
      }
      if (!actuator) {
        if (!spec.optional) {
          diagnostics_.error(
              state.location, "unbound-port",
              fmt::format(
                  "{} port '{}' of state '{}' ({}) needs {} named '{}'{}",
                  spec.direction == PortDirection::kInput ? "input" : "output", spec.name,
                  state.name.text, state.cls->name,
                  spec.direction == PortDirection::kInput ? "a sensor" : "an actuator", spec.name,
                  layer.name.empty() ? " but its controller is standalone (no owning behaviour)"
                                     : fmt::format(" in layer '{}'", layer.name)));
        }
        bindings.push_back(binding);
        continue;
      }
      const ValueType* type = program_.actuators[*actuator].type;
      if (registry_.value_type_of(*spec.cpp_type) != type) {
        diagnostics_.error(
            state.location, "type-mismatch",
            fmt::format("port '{}' of state '{}' has type '{}' but '{}' is '{}'", spec.name,
                        state.name.text, registry_.value_type_name(*spec.cpp_type), spec.name,
                        type->name));
        bindings.push_back(binding);
        continue;
      }
      binding.target = spec.name;
      bindings.push_back(binding);
    }
    return bindings;
  }

  void lay_out_values() {
    std::size_t bytes = 0;
    auto place = [&](const ValueType& type) {
      bytes = (bytes + type.alignment - 1) / type.alignment * type.alignment;
      const auto offset = static_cast<std::uint32_t>(bytes);
      bytes += type.size;
      return offset;
    };
    for (auto& actuator : program_.actuators) {
      actuator.offset = place(*actuator.type);
      program_.actuator_offsets.push_back(actuator.offset);
    }
    std::vector<std::vector<std::uint32_t>> writers(program_.actuators.size());
    for (std::uint32_t s = 0; s < program_.slots.size(); ++s) {
      auto& slot = program_.slots[s];
      const ValueType* type = program_.actuators[slot.actuator].type;
      slot.offset = place(*type);
      program_.slot_offsets.push_back(slot.offset);
      program_.slot_types.push_back(type);
      writers[slot.actuator].push_back(s);
    }
    for (auto& list : writers) {
      // Ties between writers go to the earlier in execution order, whoever created the slot.
      std::stable_sort(list.begin(), list.end(), [&](std::uint32_t a, std::uint32_t b) {
        return program_.slots[a].owner < program_.slots[b].owner;
      });
      program_.actuator_slot_begin.push_back(
          static_cast<std::uint32_t>(program_.actuator_slots.size()));
      program_.actuator_slots.insert(program_.actuator_slots.end(), list.begin(), list.end());
      program_.max_writers = std::max(program_.max_writers, list.size());
    }
    program_.actuator_slot_begin.push_back(
        static_cast<std::uint32_t>(program_.actuator_slots.size()));
    program_.value_bytes = bytes;
  }

  const Model& model_;
  const Registry& registry_;
  Diagnostics& diagnostics_;
  Program program_;
  std::vector<Claim> claims_;
  Bindings bindings_;
  std::vector<const BehaviourDecl*> sources_;  // each compiled behaviour's declaration
  // The inhibitions, gathered layer by layer.
  std::vector<std::string> files_;
  std::unordered_map<std::string, std::uint32_t> file_index_;
  std::vector<Inhibitions::Declared> declared_;
  Inhibitions::Recipes recipes_;
};

}  // namespace

std::optional<Program> compile(const Model& model, const Registry& registry,
                               Diagnostics& diagnostics) {
  return Compiler(model, registry, diagnostics).run();
}

void check_inhibition_cycles(const Model& model, Diagnostics& diagnostics) {
  for (const auto& layer : model.layers) order_behaviours(layer, diagnostics);
}

}  // namespace arbiter

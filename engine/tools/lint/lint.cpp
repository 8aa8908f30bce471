#include "arbiter/lint.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <string_view>

namespace arbiter {

namespace {

// Every lint runs in time linear in the config's size (declared inhibitions, not their closure)
// except redundant-inhibition, whose reachability costs (behaviours × chaining inhibitions / 64)
// word operations per layer: lints run on every load.

constexpr std::string_view kRedundantInhibition = "redundant-inhibition";
constexpr std::string_view kNeverActive = "never-active";
constexpr std::string_view kUnreadActuator = "unread-actuator";
constexpr std::string_view kDelayedSensor = "delayed-sensor";
constexpr std::string_view kConflictingWriters = "conflicting-writers";

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
/// Chains in messages are cut short beyond this many links.
constexpr std::size_t kMaxLinks = 12;
/// Pairs of writers named in notes, at most.
constexpr std::size_t kMaxPairs = 6;

const char* arrow(bool chaining) {
  return chaining ? "=>" : "->";
}

/// A list of edge ids per behaviour, all in one array: a vector per behaviour costs an
/// allocation each, which showed at 10 000 behaviours.
class EdgeLists {
 public:
  struct Range {
    const std::uint32_t* first;
    const std::uint32_t* last;
    const std::uint32_t* begin() const { return first; }
    const std::uint32_t* end() const { return last; }
  };

  /// `owner_of(e)` is the behaviour edge e is listed under, or kNone; lists keep edge order.
  template <typename OwnerOf>
  EdgeLists(std::uint32_t behaviours, std::uint32_t edges, OwnerOf owner_of)
      : begin_(behaviours + 1, 0) {
    for (std::uint32_t e = 0; e < edges; ++e) {
      if (const std::uint32_t owner = owner_of(e); owner != kNone) ++begin_[owner + 1];
    }
    for (std::uint32_t b = 0; b < behaviours; ++b) begin_[b + 1] += begin_[b];
    ids_.resize(begin_[behaviours]);
    std::vector<std::uint32_t> next(begin_.begin(), begin_.end() - 1);
    for (std::uint32_t e = 0; e < edges; ++e) {
      if (const std::uint32_t owner = owner_of(e); owner != kNone) ids_[next[owner]++] = e;
    }
  }
  EdgeLists() = default;

  Range operator[](std::uint32_t b) const {
    return {ids_.data() + begin_[b], ids_.data() + begin_[b + 1]};
  }

 private:
  std::vector<std::uint32_t> begin_;
  std::vector<std::uint32_t> ids_;
};

/// A layer's behaviour names → their index in the layer, in one open-addressing table: a hash
/// node per name (std::unordered_map) cost more than the rest of the linter's setup at 10 000.
class NameIndex {
 public:
  NameIndex(const std::vector<CompiledBehaviour>& behaviours, std::uint32_t base,
            std::uint32_t size)
      : behaviours_(behaviours), base_(base) {
    std::size_t capacity = 16;
    while (capacity < 2 * std::size_t{size}) capacity *= 2;
    slots_.assign(capacity, kNone);
    for (std::uint32_t i = 0; i < size; ++i) {
      std::size_t slot = first_slot(behaviours[base + i].name);
      while (slots_[slot] != kNone) slot = (slot + 1) & (slots_.size() - 1);
      slots_[slot] = i;
    }
  }

  /// The index of the behaviour named `name` (the first of that name), or kNone.
  std::uint32_t find(std::string_view name) const {
    for (std::size_t slot = first_slot(name);; slot = (slot + 1) & (slots_.size() - 1)) {
      const std::uint32_t i = slots_[slot];
      if (i == kNone || behaviours_[base_ + i].name == name) return i;
    }
  }

 private:
  std::size_t first_slot(std::string_view name) const {
    return std::hash<std::string_view>{}(name) & (slots_.size() - 1);
  }

  const std::vector<CompiledBehaviour>& behaviours_;
  std::uint32_t base_;
  std::vector<std::uint32_t> slots_;
};

/// A layer's declared inhibitions over its behaviours, numbered by execution (topological)
/// order: an inhibitor always comes before what it inhibits.
struct LayerGraph {
  struct Edge {
    std::uint32_t from = 0;
    std::uint32_t to = 0;
    const InhibitionDecl* decl = nullptr;
  };
  std::uint32_t base = 0;  ///< program index of the layer's first behaviour
  std::uint32_t size = 0;
  std::vector<Edge> edges;
  EdgeLists in;         ///< edge ids, by inhibited
  EdgeLists chain_out;  ///< chaining edge ids, by inhibitor

  const Edge* declared(std::uint32_t from, std::uint32_t to) const {
    for (auto e : in[to]) {
      if (edges[e].from == from) return &edges[e];
    }
    return nullptr;
  }
};

class Linter {
 public:
  Linter(const Model& model, const Program& program, Diagnostics& diagnostics)
      : model_(model), program_(program), diagnostics_(diagnostics) {
    decls_.assign(program.behaviours.size(), nullptr);
    graphs_.resize(program.layers.size());
    for (std::uint32_t l = 0; l < program.layers.size(); ++l) {
      const CompiledLayer& layer = program.layers[l];
      LayerGraph& graph = graphs_[l];
      graph.base = layer.behaviour_begin;
      graph.size = layer.behaviour_end - layer.behaviour_begin;
      const NameIndex index(program.behaviours, graph.base, graph.size);
      for (const auto& decl : model.layers[l].behaviours) {
        if (const auto found = index.find(decl.name.text); found != kNone) {
          decls_[graph.base + found] = &decl;
        }
      }
      graph.edges.reserve(model.layers[l].inhibitions.size());
      for (const auto& inhibition : model.layers[l].inhibitions) {
        const auto from = index.find(inhibition.inhibitor.text);
        const auto to = index.find(inhibition.inhibited.text);
        if (from == kNone || to == kNone) continue;
        graph.edges.push_back({from, to, &inhibition});
      }
      const auto edges = static_cast<std::uint32_t>(graph.edges.size());
      graph.in = EdgeLists(graph.size, edges, [&](std::uint32_t e) { return graph.edges[e].to; });
      graph.chain_out = EdgeLists(graph.size, edges, [&](std::uint32_t e) {
        return graph.edges[e].decl->chaining ? graph.edges[e].from : kNone;
      });
    }
  }

  void run() {
    check_ignore_lists();
    for (std::uint32_t l = 0; l < program_.layers.size(); ++l) redundant_inhibitions(l);
    never_active();
    unread_actuators();
    delayed_sensors();
    conflicting_writers();
  }

 private:
  bool silenced(std::string_view code, std::uint32_t layer) const {
    const auto names = [&](const std::vector<Name>& list) {
      return std::any_of(list.begin(), list.end(), [&](const Name& n) { return n.text == code; });
    };
    return names(model_.lint_ignore) || names(model_.layers[layer].lint_ignore);
  }

  Diagnostic* warn(std::string_view code, std::uint32_t layer, const SourceLocation& at,
                   std::string message) {
    if (silenced(code, layer)) return nullptr;
    return &diagnostics_.warning(at, std::string(code), std::move(message));
  }

  const std::string& name_of(const LayerGraph& graph, std::uint32_t local) const {
    return program_.behaviours[graph.base + local].name;
  }

  /// "a => b => c", or "a => b => ... => y => z" when longer than kMaxLinks.
  std::string chain_text(const LayerGraph& graph, const std::vector<std::uint32_t>& path,
                         bool complete) const {
    std::string text;
    for (std::size_t i = 0; i < path.size(); ++i) {
      text += (i == 0 ? "" : " => ") + name_of(graph, path[i]);
    }
    return complete ? text : text + " => ...";
  }

  void check_ignore_lists() {
    std::vector<std::string> known;
    for (const auto& lint : lint_codes()) known.emplace_back(lint.code);
    const auto check = [&](const std::vector<Name>& list) {
      for (const auto& name : list) {
        if (std::find(known.begin(), known.end(), name.text) != known.end()) continue;
        diagnostics_
            .warning(name.location, "unknown-lint",
                     fmt::format("'{}' names no lint; it silences nothing", name.text))
            .unknown_name(name.text, known);
      }
    };
    check(model_.lint_ignore);
    for (const auto& layer : model_.layers) check(layer.lint_ignore);
  }

  // A declared inhibition a -> c (or a => c) is redundant when a chain of two or more other
  // chaining inhibitions a => x => ... => c exists: the closure holds a -> c anyway. In a DAG
  // such a chain starts with a chaining edge a => x, x != c, from which c is reachable over
  // chaining edges. Reachability is computed for targets in blocks of kBlock behaviours, in
  // reverse execution order (successors come later), as bit sets.
  void redundant_inhibitions(std::uint32_t l) {
    const LayerGraph& graph = graphs_[l];
    if (graph.edges.empty()) return;
    constexpr std::uint32_t kWords = 64;
    constexpr std::uint32_t kBlock = kWords * 64;
    std::vector<std::uint64_t> reach;
    for (std::uint32_t start = 0; start < graph.size; start += kBlock) {
      const std::uint32_t end = std::min(graph.size, start + kBlock);
      std::vector<std::uint32_t> candidates;
      for (std::uint32_t e = 0; e < graph.edges.size(); ++e) {
        if (graph.edges[e].to >= start && graph.edges[e].to < end) candidates.push_back(e);
      }
      if (candidates.empty()) continue;
      // reach[x]: the behaviours of the block reachable from x over one or more chaining edges.
      // Only behaviours before `end` can reach into the block.
      reach.assign(static_cast<std::size_t>(end) * kWords, 0);
      const auto row = [&](std::uint32_t x) { return reach.data() + std::size_t{x} * kWords; };
      const auto has = [&](std::uint32_t x, std::uint32_t target) {
        const std::uint32_t bit = target - start;
        return (row(x)[bit / 64] >> (bit % 64)) & 1u;
      };
      for (std::uint32_t x = end; x-- > 0;) {
        std::uint64_t* mine = row(x);
        for (auto e : graph.chain_out[x]) {
          const std::uint32_t y = graph.edges[e].to;
          if (y >= end) continue;
          if (y >= start) mine[(y - start) / 64] |= std::uint64_t{1} << ((y - start) % 64);
          const std::uint64_t* theirs = row(y);
          for (std::uint32_t w = 0; w < kWords; ++w) mine[w] |= theirs[w];
        }
      }
      for (auto e : candidates) {
        const auto& edge = graph.edges[e];
        for (auto first : graph.chain_out[edge.from]) {
          const std::uint32_t x = graph.edges[first].to;
          if (x == edge.to || x >= edge.to || !has(x, edge.to)) continue;
          // A chain a => x => ... => c, walked forward through successors that reach c.
          std::vector<std::uint32_t> path{edge.from, x};
          std::vector<const LayerGraph::Edge*> links{&graph.edges[first]};
          bool stepped = true;
          while (stepped && path.back() != edge.to && links.size() < kMaxLinks) {
            stepped = false;
            for (auto next : graph.chain_out[path.back()]) {
              const std::uint32_t y = graph.edges[next].to;
              if (y == edge.to || (y < edge.to && has(y, edge.to))) {
                path.push_back(y);
                links.push_back(&graph.edges[next]);
                stepped = true;
                break;
              }
            }
          }
          report_redundant(l, edge, path, links);
          break;
        }
      }
    }
  }

  void report_redundant(std::uint32_t l, const LayerGraph::Edge& edge,
                        std::vector<std::uint32_t> path,
                        const std::vector<const LayerGraph::Edge*>& links) {
    const LayerGraph& graph = graphs_[l];
    const InhibitionDecl& decl = *edge.decl;
    const bool complete = path.back() == edge.to;
    std::string chain = chain_text(graph, path, complete);
    if (!complete) chain += " => " + name_of(graph, edge.to);
    Diagnostic* warning =
        warn(kRedundantInhibition, l, decl.location,
             fmt::format("inhibition '{} {} {}' is already implied by chaining {}",
                         decl.inhibitor.text, arrow(decl.chaining), decl.inhibited.text, chain));
    if (warning == nullptr) return;
    for (const auto* link : links) {
      warning->notes.push_back(
          {fmt::format("{} => {} declared at {}", link->decl->inhibitor.text,
                       link->decl->inhibited.text, to_string(link->decl->location)),
           link->decl->location});
    }
    warning->notes.push_back("remove it: the closure gives the same inhibition");
  }

  /// The scripted levels of a behaviour, or null when its level is not known before it runs.
  const std::vector<double>* scripted_levels(std::uint32_t b) const {
    const BehaviourDecl* decl = decls_[b];
    if (decl == nullptr || decl->cls == nullptr || decl->cls->name != "scripted") return nullptr;
    const Param* param = decl->params.find("activation");
    if (param == nullptr) return nullptr;
    return std::get_if<std::vector<double>>(&param->value);
  }

  static bool all_equal(const std::vector<double>* levels, double value) {
    return levels != nullptr && !levels->empty() &&
           std::all_of(levels->begin(), levels->end(),
                       [&](double level) { return level == value; });
  }

  // "Always" is decided statically: only a scripted behaviour's level is known before it runs.
  // One that requests 1 at every step and that nothing can inhibit (each of its inhibitors is
  // never active) is fully active at every step, and zeroes everything it inhibits. The closed
  // inhibitors of b are its declared ones and everything chained to b, so both properties are
  // carried along chaining edges in execution order instead of walking the closure.
  void never_active() {
    const std::size_t n = program_.behaviours.size();
    always_full_.assign(n, false);
    never_active_.assign(n, false);
    for (std::uint32_t l = 0; l < program_.layers.size(); ++l) {
      const LayerGraph& graph = graphs_[l];
      // Over the behaviours chained to b (a chain of chaining inhibitions leads from them to b):
      std::vector<std::uint32_t> chained_full(graph.size, kNone);  // the first fully active one
      std::vector<std::uint32_t> chained_via(graph.size, kNone);   // the edge it comes through
      std::vector<char> chained_never(graph.size, 1);              // whether all are never active
      for (std::uint32_t b = 0; b < graph.size; ++b) {
        std::uint32_t cause = kNone;
        std::uint32_t cause_edge = kNone;
        bool free = true;  // every closed inhibitor is never active
        for (auto e : graph.in[b]) {
          const auto& edge = graph.edges[e];
          const std::uint32_t x = edge.from;
          const std::uint32_t g = graph.base + x;
          free = free && never_active_[g] != 0;
          if (always_full_[g] && x < cause) {
            cause = x;
            cause_edge = e;
          }
          if (!edge.decl->chaining) continue;
          const std::uint32_t through = always_full_[g] ? x : chained_full[x];
          if (through < chained_full[b]) {
            chained_full[b] = through;
            chained_via[b] = e;
          }
          chained_never[b] = chained_never[b] && never_active_[g] && chained_never[x];
          free = free && chained_never[x];
          if (chained_full[x] < cause) {
            cause = chained_full[x];
            cause_edge = e;
          }
        }
        const auto* levels = scripted_levels(graph.base + b);
        always_full_[graph.base + b] = all_equal(levels, 1.0) && free;
        never_active_[graph.base + b] = cause != kNone || all_equal(levels, 0.0);
        if (cause != kNone) report_never_active(l, b, cause, cause_edge, chained_via);
      }
    }
  }

  void report_never_active(std::uint32_t l, std::uint32_t b, std::uint32_t cause,
                           std::uint32_t cause_edge, const std::vector<std::uint32_t>& via) {
    const LayerGraph& graph = graphs_[l];
    const auto& inhibited = program_.behaviours[graph.base + b];
    const std::string& inhibitor = name_of(graph, cause);
    Diagnostic* warning =
        warn(kNeverActive, l, inhibited.location,
             fmt::format("behaviour '{}' can never be active: '{}' inhibits it and is fully "
                         "active at every step",
                         inhibited.name, inhibitor));
    if (warning == nullptr) return;
    const Param* param = decls_[graph.base + cause]->params.find("activation");
    Note scripted(fmt::format(
        "'{}' is scripted to request 1 at every step ({}) and nothing can inhibit it", inhibitor,
        param->defaulted ? "its default activation"
                         : fmt::format("activation at {}", to_string(param->location))));
    if (!param->defaulted) scripted.location = param->location;
    warning->notes.push_back(std::move(scripted));
    if (const auto* direct = graph.declared(cause, b)) {
      warning->notes.push_back(
          {fmt::format("{} {} {} declared at {}", inhibitor, arrow(direct->decl->chaining),
                       inhibited.name, to_string(direct->decl->location)),
           direct->decl->location});
      return;
    }
    // Back from b along the edges the cover came through, to the cover.
    std::vector<std::uint32_t> path{b};
    std::uint32_t at = graph.edges[cause_edge].from;
    while (at != cause && path.size() < kMaxLinks) {
      path.push_back(at);
      at = graph.edges[via[at]].from;
    }
    const bool complete = at == cause;
    path.push_back(cause);
    std::reverse(path.begin(), path.end());
    std::string chain = chain_text(graph, path, true);
    if (!complete) chain.insert(chain.find(" => ") + 4, "... => ");
    warning->notes.push_back(
        fmt::format("'{}' inhibits '{}' through chaining: {}", inhibitor, inhibited.name, chain));
  }

  // With an interface layer in the config, data leaves through sensors; an actuator that no
  // sensor reads is then lost. Without one, the host reads actuators directly, so every actuator
  // may be an output and this lint does not apply.
  void unread_actuators() {
    const bool has_interface =
        std::any_of(program_.layers.begin(), program_.layers.end(),
                    [](const CompiledLayer& layer) { return layer.is_interface(); });
    if (!has_interface) return;
    std::vector<bool> read(program_.actuators.size(), false);
    for (const auto& layer : program_.layers) {
      for (auto sensor : layer.sensors) read[sensor] = true;
    }
    for (std::uint32_t a = 0; a < program_.actuators.size(); ++a) {
      if (read[a]) continue;
      const auto& actuator = program_.actuators[a];
      Diagnostic* warning = warn(kUnreadActuator, actuator.layer, actuator.location,
                                 fmt::format("actuator '{}' of layer '{}' is read by no sensor",
                                             actuator.name, program_.layers[actuator.layer].name));
      if (warning == nullptr) continue;
      warning->notes.push_back(
          "list it under 'sensors:' of the layer that needs it (an interface layer, to send it "
          "out), or remove it");
      warning->notes.push_back(
          "if the host program reads it directly, silence this with 'lint: {ignore: "
          "[unread-actuator]}' in its layer");
    }
  }

  // docs/semantics.md, "Timing: the one-step delay": a sensor of a normal layer sees this step's
  // value of an actuator of an earlier layer or of an interface layer, and last step's value of one
  // of its own or a later layer. Interface layers read their sensors in the output pass, after
  // every layer.
  void delayed_sensors() {
    for (std::uint32_t l = 0; l < program_.layers.size(); ++l) {
      const auto& layer = program_.layers[l];
      if (layer.is_interface()) continue;
      for (std::size_t i = 0; i < layer.sensors.size(); ++i) {
        const auto& actuator = program_.actuators[layer.sensors[i]];
        const auto& source = program_.layers[actuator.layer];
        if (source.is_interface() || actuator.layer < l) continue;
        const std::string whose = actuator.layer == l
                                      ? "its own layer"
                                      : fmt::format("layer '{}', which runs after it", source.name);
        Diagnostic* warning =
            warn(kDelayedSensor, l, model_.layers[l].sensors[i].location,
                 fmt::format("sensor '{}' of layer '{}' reads an actuator of {}: it sees the "
                             "value of the previous step",
                             actuator.name, layer.name, whose));
        if (warning == nullptr) continue;
        warning->notes.push_back(
            "layers run in declaration order; a sensor sees this step's value only of an "
            "actuator of an earlier layer or of an interface layer");
        warning->notes.push_back(
            {fmt::format("'{}' is declared at {}", actuator.name, to_string(actuator.location)),
             actuator.location});
      }
    }
  }

  // Of a non-aggregatable actuator's writers, the most active wins each step. Two writers with
  // an inhibition between them (declared or implied) have a stated priority; two without one
  // are a conflict that only their levels decide. An inhibitor runs before what it inhibits, so
  // only the earlier of two writers can inhibit the later.
  void conflicting_writers() {
    std::vector<std::uint32_t> closed;
    for (std::uint32_t a = 0; a < program_.actuators.size(); ++a) {
      const auto& actuator = program_.actuators[a];
      if (actuator.aggregate) continue;
      std::vector<std::uint32_t> writers;
      for (auto s = program_.actuator_slot_begin[a]; s < program_.actuator_slot_begin[a + 1]; ++s) {
        const auto owner = program_.slots[program_.actuator_slots[s]].owner;
        if (owner != kNoBehaviour && !never_active_[owner]) writers.push_back(owner);
      }
      std::sort(writers.begin(), writers.end());
      writers.erase(std::unique(writers.begin(), writers.end()), writers.end());
      if (writers.size() < 2) continue;
      std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
      for (std::size_t k = 1; k < writers.size(); ++k) {
        program_.inhibitions.closed(writers[k], closed);  // in execution order
        for (std::size_t i = 0; i < k; ++i) {
          if (!std::binary_search(closed.begin(), closed.end(), writers[i])) {
            pairs.emplace_back(writers[i], writers[k]);
          }
        }
      }
      if (pairs.empty()) continue;
      std::vector<std::uint32_t> involved;
      for (const auto& [first, second] : pairs) {
        involved.push_back(first);
        involved.push_back(second);
      }
      std::sort(involved.begin(), involved.end());
      involved.erase(std::unique(involved.begin(), involved.end()), involved.end());
      std::string names;
      for (std::size_t i = 0; i < involved.size(); ++i) {
        const char* separator = i == 0 ? "" : i + 1 == involved.size() ? " and " : ", ";
        names += fmt::format("{}'{}'", separator, program_.behaviours[involved[i]].name);
      }
      Diagnostic* warning = warn(
          kConflictingWriters, actuator.layer, actuator.location,
          fmt::format("actuator '{}' ({}, not aggregated) has writers that can be active in the "
                      "same step with no inhibition between them: {}",
                      actuator.name, actuator.type->name, names));
      if (warning == nullptr) continue;
      warning->notes.push_back(
          "the most active writer wins each step, and a tie goes to the one earlier in "
          "execution order");
      for (std::size_t p = 0; p < pairs.size() && p < kMaxPairs; ++p) {
        warning->notes.push_back(fmt::format(
            "declare '{} -> {}' (or the reverse) to say which of the two has priority",
            program_.behaviours[pairs[p].first].name, program_.behaviours[pairs[p].second].name));
      }
      if (pairs.size() > kMaxPairs) {
        warning->notes.push_back(
            fmt::format("... and {} more pairs without an inhibition", pairs.size() - kMaxPairs));
      }
      if (actuator.type->aggregatable()) {
        warning->notes.push_back(fmt::format(
            "or make '{}' 'aggregate: true' to average what they write", actuator.name));
      }
    }
  }

  const Model& model_;
  const Program& program_;
  Diagnostics& diagnostics_;
  std::vector<LayerGraph> graphs_;           ///< by layer
  std::vector<const BehaviourDecl*> decls_;  ///< by behaviour index
  std::vector<bool> always_full_;            ///< by behaviour index
  std::vector<bool> never_active_;
};

}  // namespace

const std::vector<LintCode>& lint_codes() {
  static const std::vector<LintCode> kCodes = {
      {kRedundantInhibition, "an inhibition declared although chaining already implies it"},
      {kNeverActive,
       "a behaviour that can never be active: an inhibitor that is fully active at every step "
       "covers it"},
      {kUnreadActuator, "an actuator that no sensor reads, in a config with an interface layer"},
      {kDelayedSensor,
       "a sensor that reads an actuator of its own or a later layer: it sees last step's value"},
      {kConflictingWriters,
       "a non-aggregated actuator with writers that can be active together and have no "
       "inhibition between them"},
  };
  return kCodes;
}

void lint(const Model& model, const Program& program, Diagnostics& diagnostics) {
  Linter(model, program, diagnostics).run();
}

}  // namespace arbiter

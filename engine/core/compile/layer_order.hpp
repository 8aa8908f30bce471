#pragma once
// A layer's behaviours in inhibition order, and the chaining closure of its inhibitions: what the
// compiler needs to turn declared inhibitions into the program's order and refinement recipes.
// Internal to the engine.

#include <algorithm>
#include <cstdint>
#include <vector>

#include "arbiter/model.hpp"
#include "arbiter/program.hpp"

namespace arbiter::detail {

struct Edge {
  std::uint32_t from = 0;  // declaration indices within the layer
  std::uint32_t to = 0;
  bool chaining = false;
  SourceLocation location;
};

/// A layer's declared inhibitions as a graph over its behaviours (declaration indices), and
/// their topological order.
struct LayerGraph {
  std::vector<Edge> edges;
  std::vector<std::vector<std::uint32_t>> out;  // edge ids by inhibitor
  std::vector<std::uint32_t> order;             // all behaviours, unless there is a cycle
};

/// Kahn's algorithm, always taking the ready behaviour declared first; reports a cycle.
/// Inhibitions naming no valid behaviour (in a model with errors) are left out.
LayerGraph order_behaviours(const LayerDecl& layer, Diagnostics& diagnostics);

/// Reports each layer's inhibition cycle, as compile() does, for a model that may have other
/// errors: inhibitions that name no valid behaviour are left out. Lets the load pipeline report a
/// cycle in the same pass as the model's problems.
void check_inhibition_cycles(const Model& model, Diagnostics& diagnostics);

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

}  // namespace arbiter::detail

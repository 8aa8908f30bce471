// The compiled program's lookups by name and its inhibition relation (closure, chains, lists).

#include <algorithm>
#include <deque>
#include <mutex>

#include "arbiter/program.hpp"

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

}  // namespace arbiter

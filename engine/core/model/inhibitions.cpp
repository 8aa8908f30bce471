// A layer's inhibitions: `a => b` (chaining), `a -> b` (non-chaining) or the mapping form, each
// naming two behaviours of the same layer. Read after every layer's behaviours are known, so that
// a behaviour of another layer is told apart from a typo.
#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>

#include "arbiter/fields.hpp"
#include "core/model/builder.hpp"

namespace arbiter::detail {

namespace {

/// Where an inhibition is written: an unquoted `a => b` spans its whole text, so that errors
/// about the inhibition underline all of it, not only its first name.
SourceLocation entry_location(const Node& item) {
  SourceLocation where = item.location();
  if (item.is_scalar() && !item.quoted()) {
    int characters = 0;
    for (const char c : item.text()) characters += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    where.length = characters;
  }
  return where;
}

}  // namespace

// Lookups for add_inhibition, so that a layer's inhibitions are read in linear time.
struct ModelBuilder::InhibitionIndex {
  std::unordered_set<std::string_view> behaviours;        // valid ones of the layer
  std::unordered_map<std::string, std::size_t> declared;  // "inhibitor inhibited" → index
};

void ModelBuilder::read_inhibitions(const Node& node, LayerDecl& layer,
                                    const PendingLayer& pending) {
  if (node.reads_as_null()) return;
  InhibitionIndex index;
  index.behaviours.reserve(layer.behaviours.size());
  for (const auto& behaviour : layer.behaviours) index.behaviours.insert(behaviour.name.text);
  if (!node.is_sequence()) {
    diagnostics_.error(node.location(), "wrong-type",
                       fmt::format("'inhibitions' must be a list such as [a => b, b -> c], "
                                   "found {}",
                                   node.describe()));
    return;
  }
  index.declared.reserve(node.items().size());
  layer.inhibitions.reserve(layer.inhibitions.size() + node.items().size());
  for (const auto& item : node.items()) {
    InhibitionDecl inhibition;
    inhibition.location = entry_location(item);
    if (item.is_scalar()) {
      if (!parse_inhibition(item, inhibition)) continue;
    } else {
      Fields fields(item, "an inhibition", {"inhibitor", "inhibited", "chaining"}, diagnostics_,
                    "'a => b', 'a -> b' or a mapping {inhibitor: a, inhibited: b, chaining: "
                    "true}");
      if (!fields.ok()) continue;
      const Node* inhibitor = fields.required("inhibitor");
      const Node* inhibited = fields.required("inhibited");
      if (inhibitor == nullptr || inhibited == nullptr) continue;
      auto a = read_string(*inhibitor, "a behaviour name");
      auto b = read_string(*inhibited, "a behaviour name");
      if (!a || !b) continue;
      inhibition.inhibitor = {*a, inhibitor->location()};
      inhibition.inhibited = {*b, inhibited->location()};
      if (const Node* chaining = fields.optional("chaining")) {
        inhibition.chaining = read_bool(*chaining, "chaining").value_or(false);
      }
    }
    add_inhibition(std::move(inhibition), layer, pending, index);
  }
}

bool ModelBuilder::parse_inhibition(const Node& item, InhibitionDecl& inhibition) {
  const std::string& text = item.text();
  // Every arrow, in order: `a => b => c` is two inhibitions written as one.
  std::vector<std::size_t> arrows;
  for (std::size_t i = 0; i + 1 < text.size(); ++i) {
    if ((text[i] == '=' || text[i] == '-') && text[i + 1] == '>') arrows.push_back(i++);
  }
  auto trimmed = [&](std::size_t begin, std::size_t end) {
    while (begin < end && text[begin] == ' ') ++begin;
    while (end > begin && text[end - 1] == ' ') --end;
    return std::pair{begin, end};
  };
  if (arrows.empty()) {
    auto& error = diagnostics_.error(
        inhibition.location, "bad-inhibition",
        fmt::format("cannot read inhibition '{}': write 'a => b' (chaining) or 'a -> b' "
                    "(non-chaining)",
                    text));
    for (const char* backwards : {"<=", "<-"}) {
      const auto at = text.find(backwards);
      if (at == std::string::npos) continue;
      const auto [lb, le] = trimmed(0, at);
      const auto [rb, re] = trimmed(at + 2, text.size());
      error.notes.push_back(fmt::format(
          "an inhibition points from the inhibitor to the inhibited: did you mean "
          "'{} {}> {}'?",
          text.substr(rb, re - rb), backwards[1] == '=' ? '=' : '-', text.substr(lb, le - lb)));
    }
    return false;
  }
  // `- a => b` with the next item's `- ` indented deeper: YAML folds that line into this
  // item as `a => b - c -> d`.
  const auto folded = text.find(" - ");
  if (arrows.size() > 1 && folded != std::string::npos && !item.quoted() &&
      folded > arrows.front()) {
    diagnostics_
        .error(inhibition.location, "bad-inhibition",
               fmt::format("inhibition '{}' runs on into the next item", text))
        .notes.push_back(fmt::format(
            "the '- {}' after it is indented deeper than this item's '- ', so YAML reads it "
            "as more of this item's text; line up the '- ' of every item",
            text.substr(folded + 3)));
    return false;
  }
  if (arrows.size() > 1) {
    std::vector<std::string> parts;
    std::size_t begin = 0;
    for (std::size_t k = 0; k <= arrows.size(); ++k) {
      const auto [b, e] = trimmed(begin, k < arrows.size() ? arrows[k] : text.size());
      parts.push_back(text.substr(b, e - b));
      if (k < arrows.size()) begin = arrows[k] + 2;
    }
    std::string split;
    for (std::size_t k = 0; k < arrows.size(); ++k) {
      const char* separator = k == 0 ? "" : k + 1 == arrows.size() ? " and " : ", ";
      split +=
          fmt::format("{}'{} {} {}'", separator, parts[k], text.substr(arrows[k], 2), parts[k + 1]);
    }
    diagnostics_
        .error(item.text_location(arrows[1]), "bad-inhibition",
               fmt::format("inhibition '{}' has more than one arrow; write one inhibition per "
                           "item",
                           text))
        .notes.push_back(fmt::format("did you mean {}?", split));
    return false;
  }
  const std::size_t arrow = arrows.front();
  const std::string_view symbol = std::string_view(text).substr(arrow, 2);
  inhibition.chaining = symbol == "=>";
  auto side = [&](std::size_t from, std::size_t to, Name& name, const char* which) {
    const auto [begin, end] = trimmed(from, to);
    name.text = text.substr(begin, end - begin);
    name.location = item.text_location(begin);
    if (name.text.empty()) {
      diagnostics_.error(name.location, "bad-inhibition",
                         fmt::format("inhibition '{}' is missing the {} behaviour {} '{}'", text,
                                     which, from == 0 ? "before" : "after", symbol));
      return false;
    }
    return true;
  };
  const bool left = side(0, arrow, inhibition.inhibitor, "inhibiting");
  const bool right = side(arrow + 2, text.size(), inhibition.inhibited, "inhibited");
  return left && right;
}

void ModelBuilder::add_inhibition(InhibitionDecl inhibition, LayerDecl& layer,
                                  const PendingLayer& pending, InhibitionIndex& index) {
  bool ok = true;
  for (const Name* end : {&inhibition.inhibitor, &inhibition.inhibited}) {
    if (index.behaviours.count(end->text) != 0) continue;
    ok = false;
    const auto& declared = pending.behaviour_names;
    if (std::find(declared.begin(), declared.end(), end->text) != declared.end()) {
      continue;  // declared but invalid: already reported
    }
    const LayerDecl* elsewhere = nullptr;
    for (std::size_t i = 0; i < model_.layers.size() && elsewhere == nullptr; ++i) {
      const auto& names = pending_layers_[i].behaviour_names;
      if (&model_.layers[i] != &layer &&
          std::find(names.begin(), names.end(), end->text) != names.end()) {
        elsewhere = &model_.layers[i];
      }
    }
    if (elsewhere != nullptr) {
      diagnostics_
          .error(end->location, "cross-layer-inhibition",
                 fmt::format("inhibition across layers: '{}' is a behaviour of {}, not of {}",
                             end->text, layer_label(*elsewhere), layer_label(layer)))
          .notes.push_back(
              "a behaviour inhibits only behaviours of its own layer; layers "
              "above influence layers below through actuators and sensors");
      continue;
    }
    diagnostics_
        .error(end->location, "unknown-behaviour",
               fmt::format("inhibition names unknown behaviour '{}' in {}", end->text,
                           layer_label(layer)))
        .unknown_name(end->text, declared,
                      fmt::format("{} declares no behaviours", layer_label(layer)));
  }
  if (!ok) return;
  if (inhibition.inhibitor.text == inhibition.inhibited.text) {
    diagnostics_.error(
        inhibition.location, "self-inhibition",
        fmt::format("behaviour '{}' cannot inhibit itself", inhibition.inhibitor.text));
    return;
  }
  // A config holds no NUL byte, so it separates the two names unambiguously.
  const auto [found, added] = index.declared.emplace(
      inhibition.inhibitor.text + '\0' + inhibition.inhibited.text, layer.inhibitions.size());
  if (!added) {
    auto& existing = layer.inhibitions[found->second];
    auto& warning = diagnostics_.warning(
        inhibition.location, "duplicate-inhibition",
        fmt::format("duplicate inhibition {} {} {}: applied once", inhibition.inhibitor.text,
                    inhibition.chaining ? "=>" : "->", inhibition.inhibited.text));
    warning.notes.push_back(
        {fmt::format("first declared at {}", to_string(existing.location)), existing.location});
    if (inhibition.chaining != existing.chaining) {
      existing.chaining = true;
      warning.notes.push_back(
          "declared both chaining (=>) and non-chaining (->): it counts as chaining");
    }
    return;
  }
  layer.inhibitions.push_back(std::move(inhibition));
}

}  // namespace arbiter::detail

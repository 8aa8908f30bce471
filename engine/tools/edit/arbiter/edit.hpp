#pragma once
// engine/tools/edit: changes to a behaviour graph made as edits of its configs' text, each what a
// person would have typed: the lines an operation does not need to change stay byte for byte as
// they were, comments and key order included, in YAML and JSON alike, in the file that declares
// the element. The language server's rename and code actions use them.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "arbiter/document.hpp"
#include "arbiter/load.hpp"

namespace arbiter {

/// Bytes [begin, end) of `file`'s text, replaced with `text`.
struct TextEdit {
  std::string file;
  std::size_t begin = 0;
  std::size_t end = 0;
  std::string text;
};

/// What an operation gives: its edits, or why it was refused (and no edit).
struct EditResult {
  std::vector<TextEdit> edits;
  std::string refused;
  bool ok() const { return refused.empty(); }
};

/// A declared inhibition, by its layer and its endpoints' names.
struct InhibitionRef {
  std::string layer;
  std::string inhibitor;
  std::string inhibited;
};

/// Removes the inhibition from the layer's `inhibitions:` (the whole key when it was the only
/// one), wherever `loaded`'s files declare it.
EditResult remove_inhibition(const Loaded& loaded, const InhibitionRef& inhibition);

/// Declares the inhibition, chaining (`=>`) or not (`->`): after the last item of the layer's
/// `inhibitions:` (a line of its own in a block sequence), or the key added with it. Refused
/// when the layer is not declared or the inhibition already is.
EditResult add_inhibition(const Loaded& loaded, const InhibitionRef& inhibition, bool chaining);

/// Makes a chaining inhibition (`=>`) non-chaining (`->`) and the other way round.
EditResult flip_chaining(const Loaded& loaded, const InhibitionRef& inhibition);

/// Sets the param `param` of behaviour `behaviour` of layer `layer` to `value`, written as it is
/// to be in the file (`0.6`, `true`, `"text"`, `[1, 2]`): the value replaced where the param is
/// written, else the param added to `params:` (which is added when missing). A value written as
/// a block collection is refused: replacing its lines is not an edit of one value.
EditResult set_param(const Loaded& loaded, const std::string& layer, const std::string& behaviour,
                     const std::string& param, const std::string& value);

/// Adds `entry` (`key: value`, as it is to be written) to the mapping `node` of `file`: before
/// a flow mapping's closing brace, else as a line of its own after the last line of the block
/// mapping, at its keys' indentation. Refused when the mapping's text is not where `node` says.
EditResult add_entry(const SourceFile& file, const Node& node, const std::string& entry);

/// The byte offset of a 1-based line and code-point column of `text` (clamped to the line).
std::size_t offset_of(const std::string& text, int line, int column);

/// A config loaded again with edits applied, before anything is written.
struct EditedConfig {
  /// The edited texts, which the load read through (declared first: destroyed after `loaded`).
  std::unique_ptr<Overlay> texts;
  Loaded loaded;
};

/// The config of `loaded` loaded again with `edits` applied to the texts it read (files it did
/// not read come from the disk): the diagnostics, model and program the edits would give.
/// `options.source` is replaced; the plugins are loaded into `registry` again.
EditedConfig load_edited(const Loaded& loaded, const std::vector<TextEdit>& edits,
                         Registry& registry, LoadOptions options = {});

/// `text` (of `file`) with the edits of `file` applied; they must not overlap.
std::string apply_edits(const std::string& text, const std::string& file,
                        const std::vector<TextEdit>& edits);

}  // namespace arbiter

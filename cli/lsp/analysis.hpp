#pragma once
// What the language server knows of a loaded config, shared by the files that answer requests:
// positions in its files' text, what it declares and uses where, and the reading of config text
// that completion and config detection share.

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "arbiter/edit.hpp"
#include "arbiter/load.hpp"
#include "arbiter/registry.hpp"
#include "lsp/server.hpp"

namespace arbiter::lsp {

using json = nlohmann::json;

// JSON-RPC's error for a request that is understood but cannot be carried out.
constexpr int kRequestFailed = -32803;

/// Thrown by a request handler: answered as a JSON-RPC error.
struct RequestError {
  int code;
  std::string message;
};

std::string uri_to_path(const std::string& uri);
std::string path_to_uri(const std::string& path);

inline bool continuation(unsigned char c) {
  return (c & 0xC0) == 0x80;
}

/// A file's text with its line starts: converts the engine's 1-based code-point positions and
/// LSP's 0-based UTF-16 positions to byte offsets and back.
class Lines {
 public:
  explicit Lines(const std::string& text) : text_(text) {
    starts_.push_back(0);
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '\n') starts_.push_back(i + 1);
    }
  }
  const std::string& text() const { return text_; }

  std::size_t line_end(std::size_t line) const {
    std::size_t end = line + 1 < starts_.size() ? starts_[line + 1] - 1 : text_.size();
    if (end > starts_[line] && text_[end - 1] == '\r') --end;
    return end;
  }

  /// Byte offset of a 1-based line and code-point column.
  std::size_t offset(int line, int column) const {
    if (line < 1) return 0;
    const auto l = std::min(static_cast<std::size_t>(line - 1), starts_.size() - 1);
    std::size_t at = starts_[l];
    const std::size_t end = line_end(l);
    for (int c = 1; c < column && at < end; ++c) {
      ++at;
      while (at < end && continuation(static_cast<unsigned char>(text_[at]))) ++at;
    }
    return at;
  }

  /// Byte offset of an LSP position (clamped to its line).
  std::size_t offset(const json& position) const {
    const auto line = std::min(position.value("line", std::size_t{0}), starts_.size() - 1);
    std::size_t units = position.value("character", std::size_t{0});
    std::size_t at = starts_[line];
    const std::size_t end = line_end(line);
    while (at < end && units > 0) {
      const auto c = static_cast<unsigned char>(text_[at]);
      const std::size_t length = c < 0x80 ? 1 : c < 0xE0 ? 2 : c < 0xF0 ? 3 : 4;
      units -= std::min<std::size_t>(units, length == 4 ? 2 : 1);
      at = std::min(end, at + length);
    }
    return at;
  }

  json position(std::size_t offset) const {
    offset = std::min(offset, text_.size());
    const auto line = static_cast<std::size_t>(
        std::upper_bound(starts_.begin(), starts_.end(), offset) - starts_.begin() - 1);
    std::size_t units = 0;
    for (std::size_t at = starts_[line]; at < offset; ++at) {
      const auto c = static_cast<unsigned char>(text_[at]);
      if (continuation(c)) continue;
      units += c >= 0xF0 ? 2 : 1;
    }
    return {{"line", line}, {"character", units}};
  }

  json range(std::size_t begin, std::size_t end) const {
    return {{"start", position(begin)}, {"end", position(end)}};
  }

  /// The extent of the token at `begin`: a quoted string with its quotes, or a name.
  std::size_t token_end(std::size_t begin) const { return arbiter::token_end(text_, begin); }

  std::size_t line_of(std::size_t offset) const {
    return static_cast<std::size_t>(std::upper_bound(starts_.begin(), starts_.end(), offset) -
                                    starts_.begin() - 1);
  }
  std::size_t line_start(std::size_t line) const { return starts_[line]; }
  std::size_t line_count() const { return starts_.size(); }

 private:
  const std::string& text_;
  std::vector<std::size_t> starts_;
};

// What a config declares and uses, by place (engine/tools/edit).
using Kind = SymbolKind;
using arbiter::InhibitionSite;
using arbiter::Occurrence;
using arbiter::PortOwner;

/// A config loaded, with the index of its names (ConfigIndex) and its files' lines.
struct Analysis : ConfigIndex {
  std::string root;
  // Before `loaded`, so destroyed after it: the program holds the registry's plugin code.
  std::unique_ptr<Registry> registry;
  Loaded loaded;
  std::map<std::string, std::unique_ptr<Lines>> lines;  // by file

  const Lines* lines_of(const std::string& file) const {
    const auto found = lines.find(file);
    return found == lines.end() ? nullptr : found->second.get();
  }
  const Occurrence* at(const std::string& file, std::size_t offset) const {
    for (const auto& item : occurrences) {
      if (item.file == file && item.begin <= offset && offset <= item.end) return &item;
    }
    return nullptr;
  }
  const Occurrence* definition_of(const Occurrence& use) const {
    for (const auto& item : occurrences) {
      if (item.definition && item.kind == use.kind && item.scope == use.scope &&
          item.name == use.name)
        return &item;
    }
    return nullptr;
  }
};

/// Fills the lines, occurrences and inhibitions of `analysis` from its loaded files.
void index_config(Analysis& analysis);

/// An empty range at a 0-based line and character.
json range_json(int line, int character);

/// Where a request's position is: its file, and the byte offset in it.
struct Cursor {
  std::string path;
  std::size_t offset = 0;
};

Cursor cursor_of(const json& params, const Analysis* analysis);
/// The LSP location of bytes [begin, end) of `file`.
json location_json(const Analysis& analysis, const std::string& file, std::size_t begin,
                   std::size_t end);

/// The engine's edits as the `changes` of a WorkspaceEdit, added to `changes` (by URI).
void add_changes(const Analysis& analysis, const std::vector<TextEdit>& edits, json& changes);

/// A character of a name, as config text is read: letters, digits, `_`, `.`, `$` and `-`.
bool name_char(char c);

/// One line of block YAML as completion and config detection read it.
struct YamlLine {
  bool blank = true;
  int dash = -1;
  int content = 0;
  std::string key;
};

YamlLine parse_yaml_line(const std::string& line);

/// What a file is, by its text alone (so that a file that does not parse yet counts too).
ConfigText classify(const std::string& path, const std::string& text);

}  // namespace arbiter::lsp

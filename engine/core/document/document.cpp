#include "arbiter/document.hpp"

#include <fmt/format.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/exceptions.h>
#include <yaml-cpp/mark.h>
#include <yaml-cpp/parser.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>
#include <string>

#include "core/document/source_text.hpp"
#include "core/document/utf8.hpp"

namespace arbiter {

namespace {

using detail::is_blank;
using detail::is_continuation_byte;
using detail::plain_null;
using detail::SourceText;

// Returns the offset of the first byte that is not valid UTF-8, or npos.
std::size_t find_invalid_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t length = detail::utf8_char(text, i).length;
    if (length == 0) return i;
    i += length;
  }
  return std::string_view::npos;
}

// yaml-cpp 0.7 decodes some escapes of valid UTF-8 input into invalid UTF-8: `\N` and `\_` in
// a double-quoted YAML string to the single bytes 0x85 and 0xA0, and a `\u` surrogate (JSON's way
// of writing an emoji) to a 3-byte sequence of its own. Re-encodes those, and replaces anything
// else invalid with U+FFFD, so that every node's text is UTF-8 (messages and traces are JSON).
std::string repair_utf8(std::string_view text) {
  const auto surrogate = [&](std::size_t at) -> std::uint32_t {
    if (at + 3 > text.size() || static_cast<unsigned char>(text[at]) != 0xED) return 0;
    const auto b1 = static_cast<unsigned char>(text[at + 1]);
    const auto b2 = static_cast<unsigned char>(text[at + 2]);
    if ((b1 & 0xE0) != 0xA0 || (b2 & 0xC0) != 0x80) return 0;
    return 0xD000u | ((b1 & 0x3Fu) << 6) | (b2 & 0x3Fu);
  };
  const auto append = [](std::string& out, std::uint32_t code) {
    if (code < 0x80) {
      out += static_cast<char>(code);
    } else if (code < 0x800) {
      out += static_cast<char>(0xC0 | (code >> 6));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else if (code < 0x10000) {
      out += static_cast<char>(0xE0 | (code >> 12));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (code >> 18));
      out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    }
  };
  std::string out;
  out.reserve(text.size() + 8);
  std::size_t i = 0;
  while (i < text.size()) {
    const std::size_t bad = find_invalid_utf8(text.substr(i));
    if (bad == std::string_view::npos) {
      out.append(text.substr(i));
      break;
    }
    out.append(text.substr(i, bad));
    i += bad;
    const auto byte = static_cast<unsigned char>(text[i]);
    const std::uint32_t high = surrogate(i);
    const std::uint32_t low = high != 0 ? surrogate(i + 3) : 0;
    if (high >= 0xD800 && high <= 0xDBFF && low >= 0xDC00 && low <= 0xDFFF) {
      append(out, 0x10000 + ((high - 0xD800) << 10) + (low - 0xDC00));
      i += 6;
    } else if (high != 0) {
      append(out, 0xFFFD);
      i += 3;
    } else if (byte == 0x85 || byte == 0xA0) {
      append(out, byte);
      i += 1;
    } else {
      append(out, 0xFFFD);
      i += 1;
    }
  }
  return out;
}

/// The innermost flow collection (`{` or `[`) still open at `stop`, found by a light scan that
/// skips comments and quoted scalars; yaml-cpp reports where it gave up, not where the
/// unclosed bracket is.
std::optional<std::size_t> open_flow_bracket(std::string_view text, std::size_t stop) {
  std::vector<std::size_t> open;
  auto token_start = [&](std::size_t i) {
    // A bracket or quote starts a token after a value indicator or at the start of a line.
    std::size_t j = i;
    while (j > 0 && (text[j - 1] == ' ' || text[j - 1] == '\t')) --j;
    if (j == 0 || text[j - 1] == '\n') return true;
    return std::string_view(":-?,[{").find(text[j - 1]) != std::string_view::npos;
  };
  for (std::size_t i = 0; i < stop && i < text.size(); ++i) {
    const char c = text[i];
    if (c == '#' && (i == 0 || is_blank(text[i - 1]))) {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if ((c == '"' || c == '\'') && token_start(i)) {
      for (++i; i < text.size() && i < stop; ++i) {
        if (c == '"' && text[i] == '\\') {
          ++i;
        } else if (text[i] == c) {
          if (c == '\'' && i + 1 < text.size() && text[i + 1] == '\'') {
            ++i;  // '' inside single quotes
          } else {
            break;
          }
        }
      }
    } else if ((c == '[' || c == '{') && (!open.empty() || token_start(i))) {
      open.push_back(i);
    } else if ((c == ']' || c == '}') && !open.empty()) {
      open.pop_back();
    }
  }
  if (open.empty()) return std::nullopt;
  return open.back();
}

/// How far off the indentation of the line holding `at` is, when it lines up with no block it
/// could belong to: the lines above it that enclose it (each less or as far indented as the ones
/// after it) give the columns its key (or its `- `) could start at. "this line is indented one
/// space too much to line up with 'actuators' on line 5"; empty when it lines up with one, or
/// nothing encloses it.
std::string indent_mistake(std::string_view text, std::size_t at) {
  auto line_start = [&](std::size_t offset) {
    const auto newline = offset == 0 ? std::string_view::npos : text.rfind('\n', offset - 1);
    return newline == std::string_view::npos ? std::size_t{0} : newline + 1;
  };
  auto indent_of = [&](std::size_t begin) {
    std::size_t i = begin;
    while (i < text.size() && text[i] == ' ') ++i;
    return i - begin;
  };
  const std::size_t begin = line_start(std::min(at, text.size()));
  const std::size_t indent = indent_of(begin);
  const bool item = text.compare(begin + indent, 2, "- ") == 0;
  struct Candidate {
    std::size_t column;  // 0-based
    std::size_t line_begin;
  };
  std::vector<Candidate> candidates;
  std::optional<std::size_t> enclosing;  // lines above indented deeper are in other blocks
  int lines = 0;
  for (std::size_t end = begin; end > 0 && lines < 1000; ++lines) {
    const std::size_t start = line_start(end - 1);
    const std::size_t depth = indent_of(start);
    const std::size_t content = start + depth;
    end = start;
    if (content >= text.size() || text[content] == '\n' || text[content] == '#' ||
        text[content] == '\r' || text[content] == '\t') {
      continue;  // blank, a comment, or a tab (reported on its own)
    }
    if (enclosing && depth > *enclosing) continue;
    enclosing = depth;
    // `- key: value` opens a list (items at the dash) and a mapping (keys after it).
    std::size_t column = depth;
    while (text.compare(start + column, 2, "- ") == 0) {
      if (item) candidates.push_back({column, start});
      column += 2;
      while (start + column < text.size() && text[start + column] == ' ') ++column;
    }
    candidates.push_back({column, start});
    if (depth == 0) break;
  }
  // Candidates run from the nearest line up. A tie goes to the inner block, the lines just above
  // (a key between its parent's column and its siblings' is most often a sibling), and the outer
  // one is named too.
  const Candidate* nearest = nullptr;
  const Candidate* outer = nullptr;
  std::size_t best = std::string_view::npos;
  for (const auto& candidate : candidates) {
    const std::size_t distance =
        candidate.column > indent ? candidate.column - indent : indent - candidate.column;
    if (distance == 0) return {};
    if (distance < best) {
      best = distance;
      nearest = &candidate;
      outer = nullptr;
    } else if (distance == best && outer == nullptr &&
               (candidate.column > indent) != (nearest->column > indent)) {
      outer = &candidate;
    }
  }
  if (nearest == nullptr) return {};
  const auto place = [&](const Candidate& candidate) {
    std::size_t word_end = candidate.line_begin + candidate.column;
    while (word_end < text.size() && text[word_end] != ':' && text[word_end] != '\n' &&
           text[word_end] != ' ') {
      ++word_end;
    }
    const std::string_view word = text.substr(candidate.line_begin + candidate.column,
                                              word_end - candidate.line_begin - candidate.column);
    const std::size_t line_number = static_cast<std::size_t>(std::count(
                                        text.begin(), text.begin() + candidate.line_begin, '\n')) +
                                    1;
    return fmt::format(
        "{} on line {}",
        word == "-" || word.empty() ? std::string("the list item") : fmt::format("'{}'", word),
        line_number);
  };
  const std::string spaces = fmt::format(
      "{} space{}", best == 1 ? std::string("one") : std::to_string(best), best == 1 ? "" : "s");
  std::string note = fmt::format("this line is indented {} too {} to line up with {}", spaces,
                                 nearest->column > indent ? "little" : "much", place(*nearest));
  if (outer != nullptr) {
    note += fmt::format(" (or {} too {} for {})", spaces,
                        outer->column > indent ? "little" : "much", place(*outer));
  }
  return note;
}

/// Turns a yaml-cpp exception into a diagnostic that says what is wrong in the user's terms.
void report_yaml_error(const SourceText& source, const YAML::Exception& error,
                       Diagnostics& diagnostics) {
  const std::string_view text = source.text();
  const std::size_t at = source.offset(error.mark);
  const std::string& what = error.msg;
  const char here = at < text.size() ? text[at] : '\0';
  std::string message = "invalid YAML: " + what;
  std::vector<Note> notes;
  const bool structural = what == YAML::ErrorMsg::END_OF_MAP_FLOW ||
                          what == YAML::ErrorMsg::END_OF_SEQ_FLOW ||
                          what == YAML::ErrorMsg::BLOCK_ENTRY || what == YAML::ErrorMsg::MAP_KEY ||
                          what == YAML::ErrorMsg::MAP_VALUE || what == YAML::ErrorMsg::END_OF_MAP ||
                          what == YAML::ErrorMsg::END_OF_SEQ;
  // An unclosed '{' or '[' on an earlier line is the usual cause of a structural error.
  if (const auto opener = structural ? open_flow_bracket(text, at) : std::nullopt;
      opener && source.location(*opener).line < source.location(at).line) {
    diagnostics
        .error(source.location(*opener), "yaml-syntax",
               fmt::format("invalid YAML: '{}' is never closed", text[*opener]))
        .notes.push_back({fmt::format("the parser reached {} without finding its '{}'",
                                      source.describe(at), text[*opener] == '{' ? '}' : ']'),
                          source.location(at)});
    return;
  }
  // Where the line's indentation lines up with nothing above it, that is the mistake to name.
  const std::string off = structural && what != YAML::ErrorMsg::END_OF_MAP_FLOW &&
                                  what != YAML::ErrorMsg::END_OF_SEQ_FLOW
                              ? indent_mistake(text, at)
                              : std::string();
  if (what == YAML::ErrorMsg::MAP_VALUE) {
    message = "invalid YAML: a mapping value (':') is not allowed here";
    if (off.empty()) {
      notes.push_back("check the indentation of this line against the lines above");
      notes.push_back("a value that contains ': ' must be quoted");
    } else {
      notes.push_back(off);
    }
  } else if (what == YAML::ErrorMsg::BLOCK_ENTRY) {
    message = "invalid YAML: a list item ('- ') is not allowed here";
    notes.push_back(off.empty() ? "check the indentation of this line against the lines above"
                                : off);
  } else if (what == YAML::ErrorMsg::END_OF_MAP || what == YAML::ErrorMsg::END_OF_SEQ) {
    message = fmt::format("invalid YAML: this line does not fit the {} above it",
                          what == YAML::ErrorMsg::END_OF_MAP ? "mapping" : "list");
    notes.push_back(off.empty() ? "check its indentation; keys of one mapping (and items of one "
                                  "list) line up exactly"
                                : off);
  } else if (what == YAML::ErrorMsg::FLOW_END) {
    message = fmt::format("invalid YAML: '{}' closes nothing", here);
  } else if (what == YAML::ErrorMsg::UNKNOWN_TOKEN) {
    message = fmt::format("invalid YAML: a value cannot start with '{}'", here);
    notes.push_back("quote the value");
  } else if (what == YAML::ErrorMsg::UNKNOWN_ANCHOR) {
    message = fmt::format("invalid YAML: alias '{}' names no anchor defined before it",
                          source.word_at(at));
  }
  // Tabs are never indentation in YAML; the parser's complaint rarely says so.
  const auto line_begin = text.rfind('\n', at == 0 ? 0 : at - 1);
  const std::size_t from = line_begin == std::string_view::npos ? 0 : line_begin + 1;
  for (std::size_t i = from; i < text.size() && (text[i] == ' ' || text[i] == '\t'); ++i) {
    if (text[i] == '\t') {
      notes = {"this line is indented with a tab; YAML indents with spaces"};
      break;
    }
  }
  diagnostics.error(source.location(at), "yaml-syntax", std::move(message)).notes =
      std::move(notes);
}

struct LimitExceeded {
  YAML::Mark mark;
  std::string message;
  const char* code = "too-large";
};

class TreeBuilder : public YAML::EventHandler {
 public:
  TreeBuilder(const SourceText& source, Diagnostics& diagnostics, const ReadLimits& limits)
      : source_(source), diagnostics_(diagnostics), limits_(limits) {}

  std::optional<Node> root;
  std::size_t document_start = 0;
  bool unreadable = false;  // an error was reported after which the tree means nothing

  void OnDocumentStart(const YAML::Mark& mark) override { document_start = source_.offset(mark); }
  void OnDocumentEnd() override {}

  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    finish(Node(Node::Kind::kNull, where(mark)), anchor);
  }

  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const auto found = anchors_.find(anchor);
    if (found == anchors_.end()) {
      diagnostics_.error(where(mark), "yaml-alias",
                         fmt::format("alias '{}' refers to a node that contains it",
                                     source_.word_at(source_.offset(mark))));
      finish(Node(Node::Kind::kNull, where(mark)), 0);
      return;
    }
    // Every copied node counts, so an alias bomb stops at the node limit instead of exhausting
    // memory.
    count(mark, found->second.second);
    finish(found->second.first, 0);
  }

  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                const std::string& value) override {
    const std::string_view text = source_.text();
    const std::size_t at = token_start(source_.offset(mark));
    NodeLocation location = source_.node_location(at);
    const bool quoted = tag != "?";
    // The text is verbatim when the file holds exactly it (after the opening quote, if any).
    const char quote = at < text.size() && (text[at] == '"' || text[at] == '\'') ? text[at] : 0;
    const std::size_t begin = at + (quote != 0 ? 1 : 0);
    const std::size_t end = begin + value.size();
    const bool verbatim = end <= text.size() && text.compare(begin, value.size(), value) == 0 &&
                          (quote == 0 || (end < text.size() && text[end] == quote));
    if (!verbatim && quote != 0 && !closed(at)) {
      // yaml-cpp ends an unclosed quoted scalar at the end of the file without complaint; the
      // rest of the file is then inside the string, so nothing after this is worth checking.
      diagnostics_.error(source_.location(at), "yaml-syntax",
                         fmt::format("invalid YAML: this string has no closing {} quote",
                                     quote == '"' ? "double" : "single"));
      unreadable = true;
    }
    count(mark, 1);
    std::string scalar =
        find_invalid_utf8(value) == std::string_view::npos ? value : repair_utf8(value);
    // Most scalars are keys: kept as the entry's key, never built as a node.
    if (anchor == 0 && expecting_key() && (quoted || !plain_null(scalar))) {
      take_key(std::move(scalar), std::move(location));
      return;
    }
    // The opening quote is one character.
    const int text_column = verbatim ? location.column() + (quote != 0 ? 1 : 0) : 0;
    Node node(Node::Kind::kScalar, std::move(location));
    node.set_scalar(std::move(scalar), quoted);
    node.set_text_column(text_column);
    finish(std::move(node), anchor);
  }

  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    open(Node(Node::Kind::kSequence, where(mark)), mark, anchor);
  }
  void OnSequenceEnd() override { close(); }

  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    open(Node(Node::Kind::kMapping, where(mark)), mark, anchor);
  }
  void OnMapEnd() override { close(); }

 private:
  struct Frame {
    Node node;
    YAML::anchor_t anchor = 0;
    std::size_t nodes_before = 0;
    bool has_key = false;
    bool drop_value = false;  // the key was unusable and already reported
    std::string key;
    NodeLocation key_location;
    // Entry indices + 1 by key hash (open addressing, 0 is empty), for mappings too large to
    // search; filled as searches need it. A hash node per key cost 4 % of parsing.
    std::vector<std::uint32_t> index;
    std::size_t indexed = 0;

    const Node::Entry* find(std::string_view key) {
      const auto& entries = node.entries();
      // Most mappings have a handful of keys: a scan beats hashing them.
      constexpr std::size_t kScanned = 16;
      if (entries.size() <= kScanned) {
        for (const auto& entry : entries) {
          if (entry.key == key) return &entry;
        }
        return nullptr;
      }
      if (index.size() < 2 * entries.size()) {
        std::size_t capacity = 64;
        while (capacity < 4 * entries.size()) capacity *= 2;
        index.assign(capacity, 0);
        indexed = 0;
      }
      for (; indexed < entries.size(); ++indexed) {
        index[free_slot(entries[indexed].key)] = static_cast<std::uint32_t>(indexed + 1);
      }
      const std::uint32_t found = index[free_slot(key)];
      return found == 0 ? nullptr : &entries[found - 1];
    }

    // The slot holding `key`, or the empty one where it would go.
    std::size_t free_slot(std::string_view key) const {
      const std::size_t mask = index.size() - 1;
      std::size_t slot = std::hash<std::string_view>{}(key)&mask;
      while (index[slot] != 0 && node.entries()[index[slot] - 1].key != key)
        slot = (slot + 1) & mask;
      return slot;
    }
  };

  // yaml-cpp marks a node at its properties (`!!str`, `&anchor`); the node starts after them.
  std::size_t token_start(std::size_t at) const {
    const std::string_view text = source_.text();
    while (at < text.size() && (text[at] == '!' || text[at] == '&')) {
      while (at < text.size() && !is_blank(text[at])) ++at;
      while (at < text.size() && is_blank(text[at])) ++at;
    }
    return at;
  }

  NodeLocation where(const YAML::Mark& mark) const {
    return source_.node_location(token_start(source_.offset(mark)));
  }

  // Whether the quoted scalar opening at `at` has its closing quote.
  bool closed(std::size_t at) const {
    const std::string_view text = source_.text();
    const char quote = text[at];
    for (std::size_t i = at + 1; i < text.size(); ++i) {
      if (quote == '"' && text[i] == '\\') {
        ++i;
      } else if (text[i] == quote) {
        if (quote == '\'' && i + 1 < text.size() && text[i + 1] == '\'') {
          ++i;  // '' inside single quotes
        } else {
          return true;
        }
      }
    }
    return false;
  }

  void count(const YAML::Mark& mark, std::size_t nodes) {
    node_count_ += nodes;
    if (node_count_ > limits_.max_nodes) {
      throw LimitExceeded{mark, fmt::format("the document has more than {} nodes (after expanding "
                                            "aliases); refusing to read further",
                                            limits_.max_nodes)};
    }
  }

  void open(Node node, const YAML::Mark& mark, YAML::anchor_t anchor) {
    count(mark, 1);
    if (stack_.size() >= limits_.max_depth) {
      throw LimitExceeded{mark, fmt::format("nesting deeper than {} levels", limits_.max_depth),
                          "too-deep"};
    }
    Frame frame;
    frame.node = std::move(node);
    frame.anchor = anchor;
    frame.nodes_before = node_count_ - 1;
    stack_.push_back(std::move(frame));
  }

  void close() {
    Frame frame = std::move(stack_.back());
    stack_.pop_back();
    const std::size_t size = node_count_ - frame.nodes_before;
    if (frame.anchor != 0) anchors_[frame.anchor] = {frame.node, size};
    attach(std::move(frame.node));
  }

  void finish(Node node, YAML::anchor_t anchor) {
    if (anchor != 0) anchors_[anchor] = {node, 1};
    attach(std::move(node));
  }

  void attach(Node node) {
    if (stack_.empty()) {
      root = std::move(node);
      return;
    }
    Frame& parent = stack_.back();
    if (parent.node.is_sequence()) {
      parent.node.push_item(std::move(node));
      return;
    }
    if (!parent.has_key) {
      if (!node.is_scalar() || node.reads_as_null()) {
        parent.has_key = true;
        parent.drop_value = true;
        diagnostics_.error(node.location(), "bad-key",
                           fmt::format("a mapping key must be a name, found {}", node.describe()));
        return;
      }
      take_key(node.text(), node.node_location());
      return;
    }
    parent.has_key = false;
    if (!parent.drop_value) {
      parent.node.add_entry(std::move(parent.key), std::move(parent.key_location), std::move(node));
    }
  }

  bool expecting_key() const {
    return !stack_.empty() && stack_.back().node.is_mapping() && !stack_.back().has_key;
  }

  // The innermost mapping's next key; its value is dropped when the key repeats an earlier one.
  void take_key(std::string key, NodeLocation location) {
    Frame& parent = stack_.back();
    parent.has_key = true;
    parent.drop_value = false;
    if (const Node::Entry* first = parent.find(key)) {
      const auto& where = first->key_location;
      diagnostics_.error(location, "duplicate-key", fmt::format("duplicate key '{}'", key))
          .notes.push_back(
              {fmt::format("first defined at {}; the second is ignored", to_string(where.get())),
               where.get()});
      parent.drop_value = true;
      return;
    }
    parent.key = std::move(key);
    parent.key_location = std::move(location);
  }

  const SourceText& source_;
  Diagnostics& diagnostics_;
  const ReadLimits& limits_;
  std::vector<Frame> stack_;
  std::map<YAML::anchor_t, std::pair<Node, std::size_t>> anchors_;
  std::size_t node_count_ = 0;
};

}  // namespace

std::optional<Node> parse_document(std::string_view text, const std::string& file,
                                   DocumentFormat format, Diagnostics& diagnostics,
                                   const ReadLimits& limits) {
  const SourceText source(text, file);
  if (text.rfind("\xFF\xFE", 0) == 0 || text.rfind("\xFE\xFF", 0) == 0) {
    diagnostics.error({file, 1, 1}, "invalid-utf8",
                      "the file is UTF-16 (it starts with a UTF-16 byte order mark); a config is "
                      "UTF-8 text");
    return std::nullopt;
  }
  if (const auto nul = text.find('\0'); nul != std::string_view::npos) {
    diagnostics.error(source.location(nul), "binary-file",
                      "the file contains a NUL byte; a config is UTF-8 text");
    return std::nullopt;
  }
  if (const auto bad = find_invalid_utf8(text); bad != std::string_view::npos) {
    diagnostics.error(source.location(bad), "invalid-utf8",
                      "invalid UTF-8; a config is UTF-8 text");
    return std::nullopt;
  }
  // An empty JSON file is reported like an empty YAML one, as an empty document.
  const bool blank = std::all_of(text.begin(), text.end(), is_blank);
  if (format == DocumentFormat::kJson && !blank &&
      !detail::check_json(source, diagnostics, limits)) {
    return std::nullopt;
  }

  std::istringstream stream{std::string(text)};
  TreeBuilder builder(source, diagnostics, limits);
  try {
    YAML::Parser parser(stream);
    if (!parser.HandleNextDocument(builder))
      return Node(Node::Kind::kNull, source.node_location(0));
    Diagnostics ignored;  // the second document's own problems do not matter
    TreeBuilder extra(source, ignored, limits);
    if (parser.HandleNextDocument(extra) && extra.root) {
      if (text.substr(extra.document_start, 3) == "---") {
        diagnostics.error(source.location(extra.document_start), "multiple-documents",
                          "a config holds one YAML document; found a second one here");
      } else {
        // yaml-cpp starts a new document where the first one cannot go on (`- a` then `b: 1`).
        diagnostics
            .error(extra.root->location(), "yaml-syntax",
                   "invalid YAML: this line does not continue the document above it")
            .notes.push_back(
                "check its indentation, and whether the document mixes a "
                "top-level list with top-level keys");
      }
    }
  } catch (const LimitExceeded& limit) {
    diagnostics.error(source.location(limit.mark), limit.code, limit.message);
    return std::nullopt;
  } catch (const YAML::DeepRecursion& error) {
    diagnostics.error(source.location(error.mark), "too-deep",
                      "nesting too deep for the YAML parser");
    return std::nullopt;
  } catch (const YAML::Exception& error) {
    report_yaml_error(source, error, diagnostics);
    return std::nullopt;
  }
  if (builder.unreadable) return std::nullopt;
  if (!builder.root) return Node(Node::Kind::kNull, source.node_location(0));
  return std::move(builder.root);
}

}  // namespace arbiter

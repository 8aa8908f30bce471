#include "arbiter/document.hpp"

#include <fmt/format.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/exceptions.h>
#include <yaml-cpp/mark.h>
#include <yaml-cpp/parser.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <system_error>

namespace arbiter {

const Node* Node::find(std::string_view key) const {
  for (const auto& entry : entries_) {
    if (entry.key == key) return &entry.value;
  }
  return nullptr;
}

namespace {

// The core schema's null, written as a plain scalar.
bool plain_null(std::string_view text) {
  return text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL";
}

}  // namespace

const std::string& NodeLocation::file() const {
  static const std::string kNone;
  return file_ ? *file_ : kNone;
}

bool Node::reads_as_null() const {
  if (kind_ == Kind::kNull) return true;
  if (kind_ != Kind::kScalar || quoted_) return false;
  return plain_null(text_);
}

std::optional<bool> Node::as_bool() const {
  if (kind_ != Kind::kScalar || quoted_) return std::nullopt;
  if (text_ == "true" || text_ == "True" || text_ == "TRUE") return true;
  if (text_ == "false" || text_ == "False" || text_ == "FALSE") return false;
  return std::nullopt;
}

namespace {

bool all_of(std::string_view text, int (*predicate)(int)) {
  if (text.empty()) return false;
  for (char c : text) {
    if (predicate(static_cast<unsigned char>(c)) == 0) return false;
  }
  return true;
}

int is_octal(int c) {
  return c >= '0' && c <= '7' ? 1 : 0;
}

// The YAML 1.2 core schema's float pattern, without the special values.
bool looks_like_decimal(std::string_view text) {
  std::size_t i = 0;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  std::size_t digits = 0;
  while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])) != 0) ++i, ++digits;
  if (i < text.size() && text[i] == '.') {
    ++i;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])) != 0) ++i, ++digits;
  }
  if (digits == 0) return false;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
    if (!all_of(text.substr(i), [](int c) { return std::isdigit(c); })) return false;
    i = text.size();
  }
  return i == text.size();
}

}  // namespace

std::optional<long long> Node::as_int() const {
  if (kind_ != Kind::kScalar || quoted_) return std::nullopt;
  std::string_view text = text_;
  int base = 10;
  std::string_view digits = text;
  if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'o')) {
    base = text[1] == 'x' ? 16 : 8;
    digits = text.substr(2);
    if (!all_of(digits, base == 16 ? [](int c) { return std::isxdigit(c); } : is_octal)) {
      return std::nullopt;
    }
  } else {
    std::string_view unsigned_part = text;
    if (!text.empty() && (text[0] == '-' || text[0] == '+')) unsigned_part = text.substr(1);
    if (!all_of(unsigned_part, [](int c) { return std::isdigit(c); })) return std::nullopt;
  }
  errno = 0;
  const std::string copy(digits);
  char* end = nullptr;
  const long long value = std::strtoll(copy.c_str(), &end, base);
  if (errno == ERANGE || end != copy.c_str() + copy.size()) return std::nullopt;
  return value;
}

std::optional<double> Node::as_double() const {
  if (kind_ != Kind::kScalar || quoted_) return std::nullopt;
  const std::string& t = text_;
  if (t == ".inf" || t == ".Inf" || t == ".INF" || t == "+.inf" || t == "+.Inf" || t == "+.INF") {
    return HUGE_VAL;
  }
  if (t == "-.inf" || t == "-.Inf" || t == "-.INF") return -HUGE_VAL;
  if (t == ".nan" || t == ".NaN" || t == ".NAN") return std::nan("");
  if (auto integer = as_int()) return static_cast<double>(*integer);
  if (!looks_like_decimal(t)) return std::nullopt;
  // strtod turns overflow into inf, which validation then reports as out of range.
  return std::strtod(t.c_str(), nullptr);
}

std::string Node::describe() const {
  switch (kind_) {
    case Kind::kNull:
      return "null";
    case Kind::kSequence:
      if (items_.empty()) return "an empty list";
      if (items_.size() == 1) return "a list of 1 item";
      return fmt::format("a list of {} items", items_.size());
    case Kind::kMapping:
      return entries_.empty() ? "an empty mapping" : "a mapping";
    case Kind::kScalar:
      break;
  }
  if (reads_as_null()) return "null";
  if (as_bool()) return fmt::format("the boolean {}", text_);
  if (as_double()) return fmt::format("the number {}", text_);
  return fmt::format("the string '{}'", text_);
}

SourceLocation Node::text_location(std::size_t offset) const {
  if (text_column_ == 0 || offset > text_.size()) return location_;
  int characters = 0;
  for (std::size_t i = 0; i < offset; ++i) {
    if ((static_cast<unsigned char>(text_[i]) & 0xC0) != 0x80) ++characters;
  }
  return {location_.file(), location_.line(), text_column_ + characters};
}

void Node::set_scalar(std::string text, bool quoted) {
  kind_ = Kind::kScalar;
  text_ = std::move(text);
  quoted_ = quoted;
}

Node& Node::push_item(Node item) {
  return items_.emplace_back(std::move(item));
}

Node::Entry& Node::add_entry(std::string key, NodeLocation key_location, Node value) {
  return entries_.emplace_back(Entry{std::move(key), std::move(key_location), std::move(value)});
}

DocumentFormat format_of(std::string_view path) {
  const auto dot = path.rfind('.');
  if (dot != std::string_view::npos && path.substr(dot) == ".json") return DocumentFormat::kJson;
  return DocumentFormat::kYaml;
}

namespace {

bool is_continuation_byte(char c) {
  return (static_cast<unsigned char>(c) & 0xC0) == 0x80;
}

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/// The text being parsed, with a line index: turns byte offsets and yaml-cpp marks (whose
/// columns count bytes) into locations whose columns count characters.
class SourceText {
 public:
  SourceText(std::string_view text, const std::string& file)
      : text_(text), file_(file), shared_file_(std::make_shared<const std::string>(file)) {
    line_starts_.push_back(0);
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '\n') line_starts_.push_back(i + 1);
    }
  }

  std::string_view text() const { return text_; }
  const std::string& file() const { return file_; }

  std::size_t offset(const YAML::Mark& mark) const {
    if (mark.line < 0) return 0;
    if (static_cast<std::size_t>(mark.line) >= line_starts_.size()) return text_.size();
    const std::size_t column = mark.column > 0 ? static_cast<std::size_t>(mark.column) : 0;
    return std::min(text_.size(), line_starts_[static_cast<std::size_t>(mark.line)] + column);
  }

  SourceLocation location(std::size_t offset) const {
    const Place place = locate(offset);
    return {file_, place.line, place.column};
  }
  SourceLocation location(const YAML::Mark& mark) const { return location(offset(mark)); }

  /// The same place as a Document node keeps it, naming the file without copying its name.
  NodeLocation node_location(std::size_t offset) const {
    const Place place = locate(offset);
    return {shared_file_, place.line, place.column};
  }

  /// "line 5, column 17", for notes about a place in the same file.
  std::string describe(std::size_t offset) const {
    const auto where = location(offset);
    return fmt::format("line {}, column {}", where.line, where.column);
  }

  /// The whitespace-delimited word at `offset`, for messages.
  std::string_view word_at(std::size_t offset) const {
    std::size_t end = offset;
    while (end < text_.size() && !is_blank(text_[end])) ++end;
    return text_.substr(offset, end - offset);
  }

 private:
  struct Place {
    int line;
    int column;
  };

  Place locate(std::size_t offset) const {
    offset = std::min(offset, text_.size());
    // Nodes are located mostly in file order, so the line is usually the last one located or the
    // next; counting on from the last place located on the same line keeps a long line (a whole
    // file of flow style) linear rather than quadratic.
    std::size_t line = cached_line_;
    if (!on_line(line, offset)) {
      line = on_line(line + 1, offset)
                 ? line + 1
                 : static_cast<std::size_t>(
                       std::upper_bound(line_starts_.begin(), line_starts_.end(), offset) -
                       line_starts_.begin() - 1);
    }
    const std::size_t start = line_starts_[line];
    std::size_t from = start;
    int column = 1;
    if (cached_line_ == line && cached_offset_ <= offset) {
      from = cached_offset_;
      column = cached_column_;
    }
    for (std::size_t i = from; i < offset; ++i) {
      if (!is_continuation_byte(text_[i])) ++column;
    }
    cached_line_ = line;
    cached_offset_ = offset;
    cached_column_ = column;
    return {static_cast<int>(line + 1), column};
  }

  // Whether `offset` lies on the line of index `line` (its newline included).
  bool on_line(std::size_t line, std::size_t offset) const {
    return line < line_starts_.size() && line_starts_[line] <= offset &&
           (line + 1 == line_starts_.size() || offset < line_starts_[line + 1]);
  }

  std::string_view text_;
  const std::string& file_;
  std::shared_ptr<const std::string> shared_file_;
  std::vector<std::size_t> line_starts_;
  mutable std::size_t cached_line_ = 0;
  mutable std::size_t cached_offset_ = 0;
  mutable int cached_column_ = 1;
};

// Returns the offset of the first byte that is not valid UTF-8, or npos.
std::size_t find_invalid_utf8(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto byte = static_cast<unsigned char>(text[i]);
    std::size_t length = 0;
    std::uint32_t code = 0;
    if (byte < 0x80) {
      ++i;
      continue;
    } else if ((byte & 0xE0) == 0xC0) {
      length = 2, code = byte & 0x1F;
    } else if ((byte & 0xF0) == 0xE0) {
      length = 3, code = byte & 0x0F;
    } else if ((byte & 0xF8) == 0xF0) {
      length = 4, code = byte & 0x07;
    } else {
      return i;
    }
    if (i + length > text.size()) return i;
    for (std::size_t k = 1; k < length; ++k) {
      const auto next = static_cast<unsigned char>(text[i + k]);
      if ((next & 0xC0) != 0x80) return i;
      code = (code << 6) | (next & 0x3F);
    }
    const bool overlong = (length == 2 && code < 0x80) || (length == 3 && code < 0x800) ||
                          (length == 4 && code < 0x10000);
    if (overlong || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return i;
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

// --- strict JSON --------------------------------------------------------------------------------

// Strict JSON: yaml-cpp alone would accept `{"a": 1,}` and `tru`.
class JsonChecker : public nlohmann::json::json_sax_t {
 public:
  explicit JsonChecker(std::size_t max_depth) : max_depth_(max_depth) {}
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return enter(); }
  bool key(string_t&) override { return true; }
  bool end_object() override { return leave(); }
  bool start_array(std::size_t) override { return enter(); }
  bool end_array() override { return leave(); }
  bool parse_error(std::size_t position, const std::string&,
                   const nlohmann::detail::exception& error) override {
    error_position = position;
    error_message = error.what();
    return false;
  }

  std::size_t error_position = 0;
  std::string error_message;
  bool too_deep = false;

 private:
  bool enter() {
    if (++depth_ > max_depth_) too_deep = true;
    return !too_deep;
  }
  bool leave() {
    --depth_;
    return true;
  }
  std::size_t max_depth_;
  std::size_t depth_ = 0;
};

struct JsonToken {
  std::size_t begin = 0;
  std::size_t end = 0;
};

/// A minimal JSON tokenizer, enough to name the token nlohmann stopped at and the brackets that
/// were open there (nlohmann reports only how many bytes it had read).
struct JsonScan {
  std::optional<JsonToken> token;       // the token containing `stop`, or the last one before it
  std::optional<JsonToken> previous;    // the token before that
  std::vector<std::size_t> open;        // offsets of the brackets still open before `token`
  std::optional<std::size_t> too_deep;  // the first bracket nested deeper than the limit

  JsonScan(std::string_view text, std::size_t stop, std::size_t max_depth) {
    std::size_t i = 0;
    while (i < text.size()) {
      if (is_blank(text[i])) {
        ++i;
        continue;
      }
      if (i > stop) break;
      const std::size_t begin = i;
      const char c = text[i];
      if (c == '"') {
        for (++i; i < text.size() && text[i] != '"'; ++i) {
          if (text[i] == '\\') ++i;
        }
        i = std::min(i + 1, text.size());
      } else if (std::string_view("{}[]:,").find(c) != std::string_view::npos) {
        ++i;
      } else {
        while (i < text.size() && !is_blank(text[i]) &&
               std::string_view("{}[]:,\"").find(text[i]) == std::string_view::npos) {
          ++i;
        }
      }
      previous = token;
      token = JsonToken{begin, i};
      if (begin == stop) break;  // the offending token: `open` stays as it was before it
      if (c == '{' || c == '[') {
        open.push_back(begin);
        if (open.size() > max_depth && !too_deep) too_deep = begin;
      } else if ((c == '}' || c == ']') && !open.empty()) {
        open.pop_back();
      }
    }
  }
};

// "[json.exception.parse_error.101] parse error at line 1, column 2: syntax error while parsing
// value - invalid literal; last read: 'tru'; expected ..." → "invalid literal; expected ...".
std::string plain_json_message(std::string message) {
  // "[json.exception.out_of_range.406] number overflow parsing '1e999999'"
  if (message.rfind("[json.exception.", 0) == 0) {
    if (const auto end = message.find("] "); end != std::string::npos) {
      message = message.substr(end + 2);
    }
  }
  if (const auto colon = message.find(": "); colon != std::string::npos) {
    message = message.substr(colon + 2);
  }
  if (const auto dash = message.find(" - ");
      message.rfind("syntax error", 0) == 0 && dash != std::string::npos) {
    message = message.substr(dash + 3);
  }
  if (const auto last = message.find("; last read: '"); last != std::string::npos) {
    const auto rest = message.find("'; ", last + 14);
    message = message.substr(0, last) + (rest == std::string::npos ? "" : message.substr(rest + 1));
  }
  return message;
}

bool check_json(const SourceText& source, Diagnostics& diagnostics, const ReadLimits& limits) {
  const std::string_view text = source.text();
  JsonChecker checker(limits.max_depth);
  if (nlohmann::json::sax_parse(text, &checker)) return true;
  if (checker.too_deep) {
    const JsonScan scan(text, text.size(), limits.max_depth);
    diagnostics.error(source.location(scan.too_deep.value_or(0)), "too-deep",
                      fmt::format("nesting deeper than {} levels", limits.max_depth));
    return false;
  }
  // nlohmann reports how many bytes it had read; the offending token contains the last of them.
  const std::size_t stop = checker.error_position > 0 ? checker.error_position - 1 : 0;
  const JsonScan scan(text, stop, limits.max_depth);
  const std::string message = plain_json_message(checker.error_message);
  std::size_t at = scan.token ? scan.token->begin : stop;
  const std::string_view token =
      scan.token ? text.substr(scan.token->begin, scan.token->end - scan.token->begin) : "";
  std::string explained;
  std::vector<std::string> notes;
  const bool closer = token == "]" || token == "}";
  if (!token.empty() && (token[0] == '/' || token[0] == '#')) {
    explained = "comments are not allowed in JSON";
    notes.push_back("a YAML config (.yaml) may have '#' comments");
  } else if (!token.empty() && token[0] == '\'') {
    explained = "JSON strings are written in double quotes, not single quotes";
  } else if (closer && scan.previous && text.substr(scan.previous->begin, 1) == ",") {
    at = scan.previous->begin;
    explained =
        fmt::format("trailing comma before '{}': JSON allows no ',' after the last item", token);
  } else if (message.rfind("number overflow", 0) == 0) {
    explained = fmt::format("the number {} is out of range (beyond about 1.8e308)", token);
  } else if (message.find("expected end of input") != std::string::npos) {
    explained = fmt::format("unexpected '{}' after the end of the JSON document", token);
  } else if (message.rfind("invalid literal", 0) == 0 && !token.empty() &&
             std::isalpha(static_cast<unsigned char>(token[0])) != 0) {
    explained = fmt::format("invalid literal '{}'; JSON literals are true, false and null", token);
    const auto hint = suggest(token, {"true", "false", "null"});
    if (hint.rfind("did you mean", 0) == 0) notes.push_back(hint.substr(0, hint.find('?') + 1));
  } else if (message.find("unexpected end of input") != std::string::npos && !scan.open.empty()) {
    const std::size_t opener = scan.open.back();
    explained = fmt::format("'{}' is never closed: the file ends before its '{}'", text[opener],
                            text[opener] == '{' ? '}' : ']');
    at = opener;
  } else {
    explained = message;
    if (closer && !scan.open.empty()) {
      const std::size_t opener = scan.open.back();
      notes.push_back(
          fmt::format("the '{}' at {} is not closed", text[opener], source.describe(opener)));
    }
  }
  diagnostics.error(source.location(at), "json-syntax", "invalid JSON: " + explained).notes =
      std::move(notes);
  return false;
}

// --- YAML ---------------------------------------------------------------------------------------

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
  const Candidate* nearest = nullptr;
  std::size_t best = std::string_view::npos;
  for (const auto& candidate : candidates) {
    const std::size_t distance =
        candidate.column > indent ? candidate.column - indent : indent - candidate.column;
    if (distance == 0) return {};
    // A tie goes to the outer block: a key is more often pushed in than pulled out.
    if (distance < best || (distance == best && candidate.column < nearest->column)) {
      best = distance;
      nearest = &candidate;
    }
  }
  if (nearest == nullptr) return {};
  std::size_t word_end = nearest->line_begin + nearest->column;
  while (word_end < text.size() && text[word_end] != ':' && text[word_end] != '\n' &&
         text[word_end] != ' ') {
    ++word_end;
  }
  const std::string_view word = text.substr(nearest->line_begin + nearest->column,
                                            word_end - nearest->line_begin - nearest->column);
  const std::size_t line_number =
      static_cast<std::size_t>(std::count(text.begin(), text.begin() + nearest->line_begin, '\n')) +
      1;
  return fmt::format(
      "this line is indented {} space{} too {} to line up with {} on line {}",
      best == 1 ? std::string("one") : std::to_string(best), best == 1 ? "" : "s",
      nearest->column > indent ? "little" : "much",
      word == "-" || word.empty() ? std::string("the list item") : fmt::format("'{}'", word),
      line_number);
}

/// Turns a yaml-cpp exception into a diagnostic that says what is wrong in the user's terms.
void report_yaml_error(const SourceText& source, const YAML::Exception& error,
                       Diagnostics& diagnostics) {
  const std::string_view text = source.text();
  const std::size_t at = source.offset(error.mark);
  const std::string& what = error.msg;
  const char here = at < text.size() ? text[at] : '\0';
  std::string message = "invalid YAML: " + what;
  std::vector<std::string> notes;
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
        .notes.push_back(fmt::format("the parser reached {} without finding its '{}'",
                                     source.describe(at), text[*opener] == '{' ? '}' : ']'));
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
              fmt::format("first defined at {}; the second is ignored", to_string(where.get())));
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

// Why the last system call failed, as ": Permission denied", or "" when errno says nothing.
std::string reason() {
  return errno == 0 ? std::string() : ": " + std::generic_category().message(errno);
}

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
  if (format == DocumentFormat::kJson && !blank && !check_json(source, diagnostics, limits)) {
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

std::optional<std::string> FileSource::read(const std::string& path, Diagnostics& diagnostics,
                                            const ReadLimits& limits) const {
  namespace fs = std::filesystem;
  std::error_code error;
  const auto status = fs::status(path, error);
  if (status.type() == fs::file_type::not_found) {
    std::error_code link_error;
    if (fs::is_symlink(fs::symlink_status(path, link_error))) {
      diagnostics.error({path, 0, 0}, "file-not-found",
                        "is a symbolic link to a file that does not exist");
    } else {
      diagnostics.error({path, 0, 0}, "file-not-found",
                        "cannot open: " + std::generic_category().message(ENOENT));
    }
    return std::nullopt;
  }
  // The path exists but cannot be looked at: a symbolic link loop, a directory on the way that
  // cannot be searched.
  if (error) {
    diagnostics.error({path, 0, 0}, "unreadable-file",
                      fmt::format("cannot be read: {}", error.message()));
    return std::nullopt;
  }
  if (fs::is_directory(status)) {
    diagnostics.error({path, 0, 0}, "not-a-file", "is a directory, not a config file");
    return std::nullopt;
  }
  // Reading a FIFO or a device could block for ever or never end (/dev/zero).
  if (!fs::is_regular_file(status)) {
    diagnostics.error({path, 0, 0}, "not-a-file",
                      "is not a regular file (a FIFO, socket or device), not a config file");
    return std::nullopt;
  }
  const auto size = fs::file_size(path, error);
  if (!error && size > limits.max_file_bytes) {
    diagnostics.error(
        {path, 0, 0}, "file-too-large",
        fmt::format("the file has {} bytes; the limit is {}", size, limits.max_file_bytes));
    return std::nullopt;
  }
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    diagnostics.error({path, 0, 0}, "unreadable-file", "cannot be opened for reading" + reason());
    return std::nullopt;
  }
  std::string text;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > limits.max_file_bytes) {
      diagnostics.error(
          {path, 0, 0}, "file-too-large",
          fmt::format("the file exceeds the limit of {} bytes", limits.max_file_bytes));
      return std::nullopt;
    }
  }
  if (in.bad()) {
    diagnostics.error({path, 0, 0}, "unreadable-file", "read error" + reason());
    return std::nullopt;
  }
  return text;
}

const FileSource& disk() {
  static const FileSource instance;
  return instance;
}

namespace {

std::string normal(const std::string& path) {
  return std::filesystem::path(path).lexically_normal().string();
}

}  // namespace

void Overlay::set(const std::string& path, std::string text) {
  texts_[normal(path)] = std::move(text);
}

void Overlay::erase(const std::string& path) {
  texts_.erase(normal(path));
}

const std::string* Overlay::find(const std::string& path) const {
  const auto found = texts_.find(normal(path));
  return found == texts_.end() ? nullptr : &found->second;
}

std::optional<std::string> Overlay::read(const std::string& path, Diagnostics& diagnostics,
                                         const ReadLimits& limits) const {
  const std::string* text = find(path);
  if (!text) return FileSource::read(path, diagnostics, limits);
  if (text->size() > limits.max_file_bytes) {
    diagnostics.error(
        {path, 0, 0}, "file-too-large",
        fmt::format("the file has {} bytes; the limit is {}", text->size(), limits.max_file_bytes));
    return std::nullopt;
  }
  return *text;
}

const Node* SourceFiles::read(const std::string& path, Diagnostics& diagnostics) {
  if (const SourceFile* file = find(path)) return file->root ? &*file->root : nullptr;
  auto text = source_->read(path, diagnostics, limits_);
  if (!text) return nullptr;
  auto file = std::make_unique<SourceFile>();
  file->path = path;
  file->text = std::move(*text);
  file->root = parse_document(file->text, path, format_of(path), diagnostics, limits_);
  files_.push_back(std::move(file));
  return files_.back()->root ? &*files_.back()->root : nullptr;
}

const SourceFile* SourceFiles::find(const std::string& path) const {
  for (const auto& file : files_) {
    if (file->path == path) return file.get();
  }
  return nullptr;
}

std::optional<Node> read_document(const std::string& path, Diagnostics& diagnostics,
                                  const ReadLimits& limits) {
  auto text = disk().read(path, diagnostics, limits);
  if (!text) return std::nullopt;
  return parse_document(*text, path, format_of(path), diagnostics, limits);
}

}  // namespace arbiter

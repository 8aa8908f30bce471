// The source-marked node every reader produces: its lookups and the core schema's reading of
// its scalars.

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <cstdlib>

#include "arbiter/document.hpp"
#include "core/document/source_text.hpp"

namespace arbiter {

const Node* Node::find(std::string_view key) const {
  for (const auto& entry : entries_) {
    if (entry.key == key) return &entry.value;
  }
  return nullptr;
}

namespace detail {

// The core schema's null, written as a plain scalar.
bool plain_null(std::string_view text) {
  return text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL";
}

}  // namespace detail

const std::string& NodeLocation::file() const {
  static const std::string kNone;
  return file_ ? *file_ : kNone;
}

bool Node::reads_as_null() const {
  if (kind_ == Kind::kNull) return true;
  if (kind_ != Kind::kScalar || quoted_) return false;
  return detail::plain_null(text_);
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

}  // namespace arbiter

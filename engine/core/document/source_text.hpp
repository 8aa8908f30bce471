#pragma once
// What the YAML and the JSON readers share: the text being parsed with its line index. Internal to
// the engine.

#include <fmt/format.h>
#include <yaml-cpp/mark.h>

#include <algorithm>

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/document.hpp"

namespace arbiter::detail {

inline bool is_continuation_byte(char c) {
  return (static_cast<unsigned char>(c) & 0xC0) == 0x80;
}

inline bool is_blank(char c) {
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

/// The core schema's null, written as a plain scalar.
bool plain_null(std::string_view text);

/// Strict JSON: yaml-cpp alone would accept `{"a": 1,}` and `tru`. Reports the first syntax error
/// at its place and returns false.
bool check_json(const SourceText& source, Diagnostics& diagnostics, const ReadLimits& limits);

}  // namespace arbiter::detail

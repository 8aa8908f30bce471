#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/document/source_text.hpp"

namespace arbiter::detail {

namespace {

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
  std::optional<JsonToken> token;     // the token containing `stop`, or the last one before it
  std::optional<JsonToken> previous;  // the token before that
  std::vector<std::size_t> open;      // offsets of the brackets still open before `token`

  JsonScan(std::string_view text, std::size_t stop) {
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

}  // namespace

bool check_json(const SourceText& source, Diagnostics& diagnostics, const ReadLimits& limits) {
  const std::string_view text = source.text();
  JsonChecker checker(limits.max_depth);
  if (nlohmann::json::sax_parse(text, &checker)) return true;
  if (checker.too_deep) {
    diagnostics.error(source.location(find_too_deep_json(text, limits.max_depth).value_or(0)),
                      "too-deep", fmt::format("nesting deeper than {} levels", limits.max_depth));
    return false;
  }
  // nlohmann reports how many bytes it had read; the offending token contains the last of them.
  const std::size_t stop = checker.error_position > 0 ? checker.error_position - 1 : 0;
  const JsonScan scan(text, stop);
  const std::string message = plain_json_message(checker.error_message);
  std::size_t at = scan.token ? scan.token->begin : stop;
  const std::string_view token =
      scan.token ? text.substr(scan.token->begin, scan.token->end - scan.token->begin) : "";
  std::string explained;
  std::vector<Note> notes;
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
          {fmt::format("the '{}' at {} is not closed", text[opener], source.describe(opener)),
           source.location(opener)});
    }
  }
  diagnostics.error(source.location(at), "json-syntax", "invalid JSON: " + explained).notes =
      std::move(notes);
  return false;
}

}  // namespace arbiter::detail

namespace arbiter {

std::optional<std::size_t> find_too_deep_json(std::string_view text, std::size_t max_depth) {
  std::size_t depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) return i;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return std::nullopt;
}

}  // namespace arbiter

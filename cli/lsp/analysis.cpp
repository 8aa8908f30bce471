// URIs and paths, a config's index (engine/tools/edit) with its files' lines, and the text
// readings the request handlers share.

#include "lsp/analysis.hpp"

#include <fmt/format.h>

#include <cctype>
#include <filesystem>
#include <utility>

namespace arbiter::lsp {

std::string uri_to_path(const std::string& uri) {
  std::string rest = uri.rfind("file://", 0) == 0 ? uri.substr(7) : uri;
  std::string path;
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (rest[i] == '%' && i + 2 < rest.size() &&
        std::isxdigit(static_cast<unsigned char>(rest[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(rest[i + 2]))) {
      path += static_cast<char>(std::stoi(rest.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      path += rest[i];
    }
  }
  return std::filesystem::path(path).lexically_normal().string();
}

std::string path_to_uri(const std::string& path) {
  std::string uri = "file://";
  for (unsigned char c : path) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') {
      uri += static_cast<char>(c);
    } else {
      uri += fmt::format("%{:02X}", c);
    }
  }
  return uri;
}

void index_config(Analysis& analysis) {
  for (const auto& file : analysis.loaded.files.files())
    analysis.lines[file->path] = std::make_unique<Lines>(file->text);
  static_cast<ConfigIndex&>(analysis) =
      arbiter::index_config(analysis.loaded, analysis.registry.get());
}

json range_json(int line, int character) {
  return {{"start", {{"line", line}, {"character", character}}},
          {"end", {{"line", line}, {"character", character}}}};
}

Cursor cursor_of(const json& params, const Analysis* analysis) {
  Cursor cursor;
  cursor.path = uri_to_path(params.at("textDocument").at("uri"));
  if (analysis) {
    if (const Lines* lines = analysis->lines_of(cursor.path))
      cursor.offset = lines->offset(params.at("position"));
  }
  return cursor;
}

json location_json(const Analysis& analysis, const std::string& file, std::size_t begin,
                   std::size_t end) {
  const Lines* lines = analysis.lines_of(file);
  return {{"uri", path_to_uri(file)},
          {"range", lines ? lines->range(begin, end) : range_json(0, 0)}};
}

void add_changes(const Analysis& analysis, const std::vector<TextEdit>& edits, json& changes) {
  for (const auto& edit : edits) {
    const Lines* lines = analysis.lines_of(edit.file);
    if (!lines) continue;
    changes[path_to_uri(edit.file)].push_back(
        {{"range", lines->range(edit.begin, edit.end)}, {"newText", edit.text}});
  }
}

bool name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '$' ||
         c == '-';
}

YamlLine parse_yaml_line(const std::string& line) {
  YamlLine result;
  std::size_t at = 0;
  while (at < line.size() && line[at] == ' ') ++at;
  if (at >= line.size() || line[at] == '#' || line[at] == '\r') return result;
  result.blank = false;
  if (line[at] == '-' && (at + 1 == line.size() || line[at + 1] == ' ')) {
    result.dash = static_cast<int>(at);
    ++at;
    while (at < line.size() && line[at] == ' ') ++at;
  }
  result.content = static_cast<int>(at);
  std::size_t end = at;
  const bool quoted = at < line.size() && (line[at] == '"' || line[at] == '\'');
  if (quoted) ++end;
  while (end < line.size() && name_char(line[end])) ++end;
  std::size_t colon = end;
  if (quoted && colon < line.size() && line[colon] == line[at]) ++colon;
  if (colon < line.size() && line[colon] == ':' &&
      (colon + 1 == line.size() || line[colon + 1] == ' ' || line[colon + 1] == '\r')) {
    result.key = line.substr(at + (quoted ? 1 : 0), end - at - (quoted ? 1 : 0));
  }
  return result;
}

}  // namespace arbiter::lsp

#include "lsp/server.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <regex>
#include <set>

#include "arbiter/catalog.hpp"
#include "arbiter/schema.hpp"
#include "lsp/framing.hpp"

namespace arbiter::lsp {

using json = nlohmann::json;

namespace {

// JSON-RPC and LSP error codes.
constexpr int kParseError = -32700;
constexpr int kInvalidRequest = -32600;
constexpr int kMethodNotFound = -32601;
constexpr int kInvalidParams = -32602;
constexpr int kServerNotInitialized = -32002;
constexpr int kRequestFailed = -32803;

// Bounds on the search for the config that includes an open file: the files looked at, and the
// size of a file read to check it.
constexpr std::size_t kMaxScanned = 20000;
constexpr std::uintmax_t kMaxScannedBytes = 4u << 20;
constexpr std::size_t kMaxScannedDepth = 8;  // folders below the one searched

struct RequestError {
  int code;
  std::string message;
};

// ---- URIs and positions ----

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

bool continuation(unsigned char c) {
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
  std::size_t token_end(std::size_t begin) const {
    if (begin >= text_.size()) return begin;
    const char first = text_[begin];
    if (first == '"' || first == '\'') {
      for (std::size_t at = begin + 1; at < text_.size() && text_[at] != '\n'; ++at) {
        if (text_[at] == '\\' && first == '"') {
          ++at;
        } else if (text_[at] == first) {
          return at + 1;
        }
      }
      return begin + 1;
    }
    std::size_t at = begin;
    while (at < text_.size()) {
      const auto c = static_cast<unsigned char>(text_[at]);
      const bool name = std::isalnum(c) || c == '_' || c == '.' || c == '$' || c == '/' ||
                        c >= 0x80 || (c == '-' && at + 1 < text_.size() && text_[at + 1] != '>');
      if (!name) break;
      ++at;
    }
    return at == begin ? std::min(begin + 1, line_end(line_of(begin))) : at;
  }

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

}  // namespace

// ---- what a config declares and uses, by place ----

enum class Kind { kBehaviour, kActuator, kState, kMachine, kLayer, kClass, kInclude };

struct Occurrence {
  Kind kind;
  std::string scope;  // a behaviour's layer, a state's machine
  std::string name;
  std::string file;
  std::size_t begin = 0;  // bytes of the name in the file's text
  std::size_t end = 0;
  bool definition = false;
  std::string detail;  // a definition's class or type
};

struct InhibitionSite {
  std::string layer;
  std::string inhibitor;
  std::string inhibited;
  bool chaining = false;
  std::string file;
  std::size_t begin = 0;  // the whole item
  std::size_t end = 0;
};

struct Analysis {
  std::string root;
  // Before `loaded`, so destroyed after it: the program holds the registry's plugin code.
  std::unique_ptr<Registry> registry;
  Loaded loaded;
  std::map<std::string, std::unique_ptr<Lines>> lines;  // by file
  std::vector<Occurrence> occurrences;
  std::vector<InhibitionSite> inhibitions;

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

namespace {

class Indexer {
 public:
  explicit Indexer(Analysis& analysis) : a_(analysis) {}

  void run() {
    for (const auto& file : a_.loaded.files.files()) {
      a_.lines[file->path] = std::make_unique<Lines>(file->text);
    }
    for (const auto& file : a_.loaded.files.files()) {
      if (file->root && file->root->is_mapping()) read_file(*file->root);
    }
  }

 private:
  // The bytes of a scalar's text in its file (when written verbatim), else of its node.
  std::pair<std::size_t, std::size_t> span(const Node& node, std::size_t from = 0,
                                           std::size_t length = std::string::npos) {
    const SourceLocation where = node.text_location(from);
    const Lines* lines = a_.lines_of(where.file);
    if (!lines) return {0, 0};
    const std::size_t begin = lines->offset(where.line, where.column);
    if (where.line == node.location().line && where.column == node.location().column && from == 0 &&
        node.quoted())
      return {begin, lines->token_end(begin)};
    const std::size_t size =
        std::min(length, node.text().size() - std::min(from, node.text().size()));
    return {begin, begin + size};
  }
  std::pair<std::size_t, std::size_t> key_span(const Node::Entry& entry) {
    const SourceLocation where = entry.key_location;
    const Lines* lines = a_.lines_of(where.file);
    if (!lines) return {0, 0};
    std::size_t begin = lines->offset(where.line, where.column);
    const auto& text = lines->text();
    if (begin < text.size() && (text[begin] == '"' || text[begin] == '\'')) ++begin;
    return {begin, begin + entry.key.size()};
  }

  void add(Kind kind, std::string scope, const std::string& name, const std::string& file,
           std::pair<std::size_t, std::size_t> at, bool definition, std::string detail = {}) {
    a_.occurrences.push_back(
        {kind, std::move(scope), name, file, at.first, at.second, definition, std::move(detail)});
  }

  static std::string type_of(const Node& value) {
    if (value.is_scalar()) return value.text();
    if (const Node* type = value.find("type"); type && type->is_scalar()) return type->text();
    return {};
  }

  void read_file(const Node& root) {
    const std::string file = root.location().file;
    if (const Node* include = root.find("include"); include && include->is_sequence()) {
      for (const auto& item : include->items()) {
        if (!item.is_scalar()) continue;
        const auto path =
            (std::filesystem::path(file).parent_path() / item.text()).lexically_normal().string();
        add(Kind::kInclude, {}, path, file, span(item), false);
      }
    }
    if (const Node* layers = root.find("layers"); layers && layers->is_sequence()) {
      for (const auto& layer : layers->items()) read_layer(layer, file);
    }
    if (const Node* machines = root.find("state_machines"); machines && machines->is_mapping()) {
      for (const auto& machine : machines->entries()) read_machine(machine, file);
    }
  }

  void read_ports(const Node* ports, const std::string& file) {
    if (!ports || !ports->is_mapping()) return;
    for (const auto& port : ports->entries()) {
      if (port.value.is_scalar())
        add(Kind::kActuator, {}, port.value.text(), file, span(port.value), false);
    }
  }

  void read_layer(const Node& layer, const std::string& file) {
    if (!layer.is_mapping()) return;
    const Node* name = layer.find("name");
    const std::string layer_name = name && name->is_scalar() ? name->text() : std::string();
    if (name && name->is_scalar()) add(Kind::kLayer, {}, layer_name, file, span(*name), true);
    if (const Node* interface = layer.find("interface"); interface && interface->is_scalar()) {
      add(Kind::kClass, {}, interface->text(), file, span(*interface), false);
    }
    read_ports(layer.find("ports"), file);
    if (const Node* actuators = layer.find("actuators"); actuators && actuators->is_mapping()) {
      for (const auto& actuator : actuators->entries()) {
        add(Kind::kActuator, {}, actuator.key, file, key_span(actuator), true,
            type_of(actuator.value));
      }
    }
    if (const Node* sensors = layer.find("sensors"); sensors && sensors->is_sequence()) {
      for (const auto& sensor : sensors->items()) {
        if (sensor.is_scalar())
          add(Kind::kActuator, {}, sensor.text(), file, span(sensor), false, "sensor");
      }
    }
    if (const Node* behaviours = layer.find("behaviours"); behaviours && behaviours->is_mapping()) {
      for (const auto& behaviour : behaviours->entries()) {
        add(Kind::kBehaviour, layer_name, behaviour.key, file, key_span(behaviour), true,
            type_of(behaviour.value));
        const Node& value = behaviour.value;
        if (value.is_scalar()) add(Kind::kClass, {}, value.text(), file, span(value), false);
        if (!value.is_mapping()) continue;
        if (const Node* type = value.find("type"); type && type->is_scalar()) {
          add(Kind::kClass, {}, type->text(), file, span(*type), false);
        }
        read_ports(value.find("ports"), file);
        if (const Node* params = value.find("params"); params && params->is_mapping()) {
          if (const Node* machine = params->find("machine"); machine && machine->is_scalar()) {
            add(Kind::kMachine, {}, machine->text(), file, span(*machine), false);
          }
        }
      }
    }
    if (const Node* inhibitions = layer.find("inhibitions");
        inhibitions && inhibitions->is_sequence()) {
      for (const auto& item : inhibitions->items()) read_inhibition(item, layer_name, file);
    }
  }

  void read_inhibition(const Node& item, const std::string& layer, const std::string& file) {
    InhibitionSite site{layer, {}, {}, false, file, 0, 0};
    const Lines* lines = a_.lines_of(file);
    if (!lines) return;
    const std::size_t start = lines->offset(item.location().line, item.location().column);
    if (item.is_scalar()) {
      const std::string& text = item.text();
      std::size_t arrow = text.find("=>");
      site.chaining = arrow != std::string::npos;
      if (!site.chaining) arrow = text.find("->");
      if (arrow == std::string::npos) return;
      auto trimmed = [&](std::size_t from, std::size_t to) {
        while (from < to && text[from] == ' ') ++from;
        while (to > from && text[to - 1] == ' ') --to;
        return std::make_pair(from, to);
      };
      const auto left = trimmed(0, arrow);
      const auto right = trimmed(arrow + 2, text.size());
      site.inhibitor = text.substr(left.first, left.second - left.first);
      site.inhibited = text.substr(right.first, right.second - right.first);
      add(Kind::kBehaviour, layer, site.inhibitor, file,
          span(item, left.first, left.second - left.first), false);
      add(Kind::kBehaviour, layer, site.inhibited, file,
          span(item, right.first, right.second - right.first), false);
      site.begin = start;
      site.end = item.quoted() ? lines->token_end(start) : span(item).second;
    } else if (item.is_mapping()) {
      const Node* inhibitor = item.find("inhibitor");
      const Node* inhibited = item.find("inhibited");
      if (!inhibitor || !inhibited || !inhibitor->is_scalar() || !inhibited->is_scalar()) return;
      site.inhibitor = inhibitor->text();
      site.inhibited = inhibited->text();
      const Node* chaining = item.find("chaining");
      site.chaining = chaining && chaining->as_bool().value_or(false);
      add(Kind::kBehaviour, layer, site.inhibitor, file, span(*inhibitor), false);
      add(Kind::kBehaviour, layer, site.inhibited, file, span(*inhibited), false);
      site.begin = start;
      site.end = start;
    } else {
      return;
    }
    a_.inhibitions.push_back(std::move(site));
  }

  void read_machine(const Node::Entry& machine, const std::string& file) {
    add(Kind::kMachine, {}, machine.key, file, key_span(machine), true);
    if (!machine.value.is_mapping()) return;
    if (const Node* states = machine.value.find("states"); states && states->is_mapping()) {
      for (const auto& state : states->entries()) {
        add(Kind::kState, machine.key, state.key, file, key_span(state), true,
            type_of(state.value));
        if (state.value.is_scalar())
          add(Kind::kClass, {}, state.value.text(), file, span(state.value), false);
        if (!state.value.is_mapping()) continue;
        if (const Node* type = state.value.find("type"); type && type->is_scalar()) {
          add(Kind::kClass, {}, type->text(), file, span(*type), false);
        }
        if (const Node* child = state.value.find("machine"); child && child->is_scalar()) {
          add(Kind::kMachine, {}, child->text(), file, span(*child), false);
        }
      }
    }
    auto queue_entry = [&](const Node& entry) {
      if (entry.is_scalar()) {
        add(Kind::kState, machine.key, entry.text(), file, span(entry), false);
      } else if (entry.is_mapping() && entry.size() == 1) {
        const auto& only = entry.entries().front();
        add(Kind::kState, machine.key, only.key, file, key_span(only), false);
      }
    };
    if (const Node* queue = machine.value.find("queue"); queue && queue->is_sequence()) {
      for (const auto& entry : queue->items()) queue_entry(entry);
    }
    if (const Node* preempt = machine.value.find("preempt"); preempt && preempt->is_sequence()) {
      for (const auto& item : preempt->items()) {
        if (const Node* go_to = item.is_mapping() ? item.find("go_to") : nullptr)
          queue_entry(*go_to);
      }
    }
  }

  Analysis& a_;
};

json diagnostic_json(const Diagnostic& item, const Lines* lines) {
  json range = {{"start", {{"line", 0}, {"character", 0}}},
                {"end", {{"line", 0}, {"character", 0}}}};
  if (lines && item.location.line > 0) {
    const std::size_t begin = lines->offset(item.location.line, std::max(1, item.location.column));
    range = lines->range(begin, lines->token_end(begin));
  }
  json result = {{"range", range},
                 {"severity", item.severity == Severity::kError ? 1 : 2},
                 {"code", item.code},
                 {"source", "arbiter"},
                 {"message", item.message}};
  return result;
}

json range_json(int line, int character) {
  return {{"start", {{"line", line}, {"character", character}}},
          {"end", {{"line", line}, {"character", character}}}};
}

std::optional<std::string> suggestion_of(const json& diagnostic) {
  static const std::regex pattern(R"(did you mean '([^']+)'\?)");
  std::smatch match;
  const std::string message = diagnostic.value("message", "");
  if (std::regex_search(message, match, pattern)) return match[1].str();
  for (const auto& info : diagnostic.value("relatedInformation", json::array())) {
    const std::string text = info.value("message", "");
    if (std::regex_search(text, match, pattern)) return match[1].str();
  }
  return std::nullopt;
}

// ---- completion context ----

/// Where the cursor is in the config's tree: the path of keys (sequence items as "*") to the
/// mapping or sequence that holds it, and whether a key, a value (of `key`) or an item is typed.
struct Context {
  enum class At { kKey, kValue, kItem } at = At::kKey;
  std::vector<std::string> path;
  std::string key;
  std::size_t word_begin = 0;
};

bool name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '$' ||
         c == '-';
}

/// Scans flow text (JSON, or a YAML flow collection) from `begin` to `end` into `context`.
void scan_flow(const std::string& text, std::size_t begin, std::size_t end, Context& context) {
  struct Frame {
    bool object;
    std::string key;
    bool after_colon = false;
  };
  std::vector<Frame> frames;
  std::string last_string;
  for (std::size_t i = begin; i < end; ++i) {
    const char c = text[i];
    if (c == '"' || c == '\'') {
      std::size_t j = i + 1;
      std::string value;
      while (j < end && text[j] != c) {
        if (text[j] == '\\' && c == '"' && j + 1 < end) ++j;
        value += text[j++];
      }
      if (j >= end) break;  // the cursor is inside this string
      last_string = value;
      i = j;
    } else if (c == '{' || c == '[') {
      if (!frames.empty()) {
        context.path.push_back(frames.back().object ? frames.back().key : "*");
      }
      frames.push_back({c == '{', {}, false});
    } else if (c == '}' || c == ']') {
      if (!frames.empty()) frames.pop_back();
      if (!frames.empty() && !context.path.empty()) context.path.pop_back();
    } else if (c == ':' && !frames.empty() && frames.back().object) {
      frames.back().key = last_string;
      frames.back().after_colon = true;
    } else if (c == ',' && !frames.empty()) {
      frames.back().after_colon = false;
    } else if (!frames.empty() && frames.back().object && !frames.back().after_colon &&
               name_char(c)) {
      // an unquoted YAML flow key
      std::size_t j = i;
      while (j < end && name_char(text[j])) ++j;
      last_string = text.substr(i, j - i);
      i = j - 1;
    }
  }
  if (frames.empty()) return;
  if (!frames.back().object) {
    context.at = Context::At::kItem;
  } else if (frames.back().after_colon) {
    context.at = Context::At::kValue;
    context.key = frames.back().key;
  } else {
    context.at = Context::At::kKey;
  }
}

struct YamlLine {
  bool blank = true;
  int dash = -1;
  int content = 0;
  std::string key;
};

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

const std::set<std::string>& scalar_lists() {
  static const std::set<std::string> names = {"sensors", "inhibitions", "queue",
                                              "include", "plugins",     "ignore"};
  return names;
}

Context context_at(const Lines& lines, std::size_t offset, bool json_format) {
  Context context;
  const std::string& text = lines.text();
  std::size_t word = offset;
  while (word > 0 && name_char(text[word - 1])) --word;
  context.word_begin = word;
  if (json_format) {
    scan_flow(text, 0, offset, context);
    return context;
  }
  const std::size_t line = lines.line_of(offset);
  const std::string current = text.substr(lines.line_start(line), offset - lines.line_start(line));
  const YamlLine here = parse_yaml_line(current + "x");
  std::vector<std::string> reversed;
  int column = here.content;
  bool in_sequence = false;
  // The current line: `key: value`, `- item`, `key: [flow` or a key being typed.
  const auto colon = current.find(": ");
  if (!here.key.empty() || colon != std::string::npos) {
    const std::string key = here.key.empty() ? parse_yaml_line(current).key : here.key;
    const std::size_t after = colon == std::string::npos ? current.size() : colon + 1;
    const auto flow = current.find_first_of("[{", after);
    if (flow != std::string::npos) {
      Context inner;
      scan_flow(current, flow, current.size(), inner);
      context.at = inner.at;
      context.key = inner.key;
      inner.path.insert(inner.path.begin(), key);
      context.path = inner.path;
    } else if (colon != std::string::npos) {
      context.at = Context::At::kValue;
      context.key = parse_yaml_line(current.substr(0, colon + 1)).key;
    }
  }
  if (here.dash >= 0) {
    in_sequence = true;
    column = here.dash;
  }
  for (std::size_t l = line; l-- > 0;) {
    const std::string text_line =
        text.substr(lines.line_start(l), lines.line_end(l) - lines.line_start(l));
    const YamlLine up = parse_yaml_line(text_line);
    if (up.blank) continue;
    if (in_sequence) {
      if (up.dash >= 0 && up.dash == column) continue;  // a sibling item
      if (up.content <= column && !up.key.empty()) {
        reversed.push_back("*");
        reversed.push_back(up.key);
        column = up.dash >= 0 ? up.dash : up.content;
        in_sequence = up.dash >= 0;
        if (column == 0 && !in_sequence) break;
      }
      continue;
    }
    if (up.dash >= 0 && up.content == column) {  // the first key of this item's mapping
      in_sequence = true;
      column = up.dash;
      continue;
    }
    if (up.content < column && !up.key.empty()) {
      reversed.push_back(up.key);
      column = up.content;
      if (up.dash >= 0) {
        in_sequence = true;
        column = up.dash;
      }
    }
  }
  if (in_sequence) reversed.push_back("*");
  std::vector<std::string> path(reversed.rbegin(), reversed.rend());
  // A key at the root of the line's own sequence: `- name` under `sensors:` is an item.
  if (here.dash >= 0 && context.path.empty()) {
    // The item's own key (`- name: x`) is within the item's mapping.
    if (context.at == Context::At::kKey && !path.empty() && path.size() >= 2 &&
        scalar_lists().count(path[path.size() - 2])) {
      context.at = Context::At::kItem;
      path.pop_back();
    } else if (context.at == Context::At::kValue) {
      // `- key: value` in a sequence of mappings
    }
  }
  if (!path.empty() && path.back() == "*" && context.at == Context::At::kItem) path.pop_back();
  path.insert(path.end(), context.path.begin(), context.path.end());
  context.path = std::move(path);
  return context;
}

bool matches(const std::vector<std::string>& path, std::initializer_list<const char*> pattern) {
  if (path.size() != pattern.size()) return false;
  std::size_t i = 0;
  for (const char* part : pattern) {
    if (std::string(part) != "*" && path[i] != part) return false;
    ++i;
  }
  return true;
}

// The keys a schema definition allows (following $ref and anyOf).
void schema_keys(const json& schema, const json& definition, std::vector<std::string>& keys,
                 int depth = 0) {
  if (depth > 8 || !definition.is_object()) return;
  if (auto ref = definition.find("$ref"); ref != definition.end() && ref->is_string()) {
    const std::string name = ref->get<std::string>().substr(ref->get<std::string>().rfind('/') + 1);
    if (schema.contains("definitions") && schema["definitions"].contains(name)) {
      schema_keys(schema, schema["definitions"][name], keys, depth + 1);
    }
  }
  if (auto properties = definition.find("properties"); properties != definition.end()) {
    for (const auto& [key, value] : properties->items()) {
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
    }
  }
  for (const char* group : {"anyOf", "oneOf", "allOf"}) {
    if (auto alternatives = definition.find(group); alternatives != definition.end()) {
      for (const auto& alternative : *alternatives)
        schema_keys(schema, alternative, keys, depth + 1);
    }
  }
  for (const char* branch : {"then", "else"}) {
    if (auto part = definition.find(branch); part != definition.end()) {
      schema_keys(schema, *part, keys, depth + 1);
    }
  }
}

std::string param_summary(const json& param) {
  std::string text = param.value("type", "");
  const bool low = param.contains("minimum") && param["minimum"].is_number();
  const bool high = param.contains("maximum") && param["maximum"].is_number();
  if (low && high) {
    text += fmt::format(", {} to {}", param["minimum"].dump(), param["maximum"].dump());
  } else if (low) {
    text += fmt::format(", at least {}", param["minimum"].dump());
  } else if (high) {
    text += fmt::format(", at most {}", param["maximum"].dump());
  }
  if (!param.value("choices", json::array()).empty()) {
    text += ", one of " + param["choices"].dump();
  }
  text += param.value("required", false) ? ", required"
                                         : ", default " + param.value("default", json()).dump();
  return text;
}

std::string class_markdown(const json& cls) {
  std::string text =
      fmt::format("**{}** ({}, {})\n\n{}\n", cls.value("name", ""), cls.value("kind", ""),
                  cls.value("origin", ""), cls.value("description", ""));
  if (!cls.value("params", json::array()).empty()) {
    text += "\nParams:\n";
    for (const auto& param : cls["params"]) {
      text += fmt::format("- `{}`: {} — {}\n", param.value("name", ""), param_summary(param),
                          param.value("description", ""));
    }
  }
  if (!cls.value("ports", json::array()).empty()) {
    text += "\nPorts:\n";
    for (const auto& port : cls["ports"]) {
      text +=
          fmt::format("- `{}`: {} {}{} — {}\n", port.value("name", ""), port.value("direction", ""),
                      port.value("type", ""), port.value("optional", false) ? ", optional" : "",
                      port.value("description", ""));
    }
  }
  return text;
}

/// The top-level keys of a JSON document or a YAML flow mapping, read from its text alone so that
/// a file that does not parse yet is recognised too: each string or name at depth 1 before a ':'.
std::vector<std::pair<std::string, std::string>> flow_top_level(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> keys;  // key, the scalar after it
  int depth = 0;
  std::string last;
  bool value = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '"' || c == '\'') {
      std::size_t j = i + 1;
      std::string token;
      while (j < text.size() && text[j] != c) {
        if (text[j] == '\\' && c == '"' && j + 1 < text.size()) ++j;
        token += text[j++];
      }
      i = j;
      if (depth != 1) continue;
      if (value && !keys.empty()) {
        keys.back().second = token;
        value = false;
      } else {
        last = token;
      }
    } else if (c == '{' || c == '[') {
      ++depth;
      value = false;
    } else if (c == '}' || c == ']') {
      --depth;
    } else if (c == ':' && depth == 1) {
      keys.emplace_back(last, std::string());
      value = true;
    } else if (c == ',') {
      value = false;
    } else if (depth == 1 && name_char(c) && !value) {
      std::size_t j = i;
      while (j < text.size() && name_char(text[j])) ++j;
      last = text.substr(i, j - i);
      i = j - 1;
    }
  }
  return keys;
}

/// What a file is by its text: an Arbiter config (or a file a config includes) has one of the
/// top-level keys only an Arbiter config has (`arbiter`, `layers`, `state_machines`), or its
/// `$schema` (a key, or a YAML language server comment) names a file called `arbiter...`. A
/// package.json, a CI workflow or a docker-compose.yaml has none of these.
ConfigText classify(const std::string& path, const std::string& text) {
  static const std::set<std::string> markers = {"arbiter", "layers", "state_machines"};
  auto arbiter_schema = [](std::string reference) {
    const auto slash = reference.find_last_of("/\\");
    if (slash != std::string::npos) reference = reference.substr(slash + 1);
    return reference.rfind("arbiter", 0) == 0;
  };
  bool config = false;
  bool named = false;
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  const bool flow = format_of(path) == DocumentFormat::kJson ||
                    (first != std::string::npos && text[first] == '{');
  if (flow) {
    for (const auto& [key, value] : flow_top_level(text)) {
      if (markers.count(key) || (key == "$schema" && arbiter_schema(value))) config = true;
      if (key == "name") named = true;
    }
  } else {
    static const std::regex modeline(R"(^#\s*yaml-language-server:\s*\$schema=(\S+))");
    std::size_t start = 0;
    while (start < text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      const std::string line = text.substr(start, end - start);
      start = end + 1;
      std::smatch match;
      if (line.rfind('#', 0) == 0 && std::regex_search(line, match, modeline) &&
          arbiter_schema(match[1].str()))
        config = true;
      const YamlLine parsed = parse_yaml_line(line);
      if (parsed.blank || parsed.content != 0 || parsed.dash >= 0) continue;
      if (markers.count(parsed.key)) config = true;
      if (parsed.key == "name") named = true;
      if (parsed.key == "$schema") {
        std::string value = line.substr(line.find(':') + 1);
        value.erase(0, value.find_first_not_of(" \"'"));
        value = value.substr(0, value.find_first_of(" \"'#\r"));
        if (arbiter_schema(value)) config = true;
      }
    }
  }
  if (!config) return ConfigText::kNone;
  return named ? ConfigText::kConfig : ConfigText::kFragment;
}

}  // namespace

// ---- the server ----

Server::Server(std::function<Registry()> make_registry, LoadOptions options)
    : make_registry_(std::move(make_registry)), options_(std::move(options)) {
  options_.source = &overlay_;
}

Server::~Server() = default;

std::vector<json> Server::handle(const std::string& text) {
  // Before the parse: the message's tree is copied and compared recursively.
  if (const auto deep = find_too_deep_json(text, options_.limits.max_depth)) {
    return {{{"jsonrpc", "2.0"},
             {"id", nullptr},
             {"error",
              {{"code", kParseError},
               {"message", fmt::format("parse error: nesting deeper than {} levels at byte {}",
                                       options_.limits.max_depth, *deep)}}}}};
  }
  json message;
  try {
    message = json::parse(text);
  } catch (const json::exception& error) {
    // Not only syntax errors: a number too large for a double is refused after parsing it.
    return {{{"jsonrpc", "2.0"},
             {"id", nullptr},
             {"error",
              {{"code", kParseError}, {"message", std::string("parse error: ") + error.what()}}}}};
  }
  return handle(message);
}

std::vector<json> Server::handle(const json& message) {
  std::vector<json> out;
  auto error = [&](const json& id, int code, const std::string& text) {
    out.push_back({{"jsonrpc", "2.0"}, {"id", id}, {"error", {{"code", code}, {"message", text}}}});
  };
  if (!message.is_object() || !message.contains("method") || !message["method"].is_string()) {
    // A response to a request of ours (we send none) is ignored; anything else is invalid.
    if (message.is_object() && message.contains("id") &&
        (message.contains("result") || message.contains("error")))
      return out;
    const json id = message.is_object() && message.contains("id") ? message["id"] : json();
    error(id, kInvalidRequest, "not a JSON-RPC request or notification: no 'method'");
    return out;
  }
  const std::string method = message["method"];
  const bool request = message.contains("id");
  const json id = request ? message["id"] : json();
  if (request && !(id.is_number_integer() || id.is_string())) {
    error(nullptr, kInvalidRequest, "'id' must be a number or a string");
    return out;
  }
  const json params = message.value("params", json::object());
  if (method == "exit") {
    exited_ = true;
    return out;
  }
  if (shutdown_ && request) {
    error(id, kInvalidRequest, "the server is shut down: only 'exit' is accepted");
    return out;
  }
  if (!initialized_ && method != "initialize") {
    if (request) error(id, kServerNotInitialized, "the server is not initialized");
    return out;
  }
  try {
    json result = dispatch(method, params, out);
    if (request) {
      if (result.is_object() && result.contains("__method_not_found")) {
        error(id, kMethodNotFound, "unknown method: " + method);
      } else {
        out.insert(out.begin(), json{{"jsonrpc", "2.0"}, {"id", id}, {"result", result}});
      }
    }
  } catch (const RequestError& failure) {
    if (request) error(id, failure.code, failure.message);
  } catch (const json::exception& failure) {
    if (request) error(id, kInvalidParams, std::string("invalid params: ") + failure.what());
  } catch (const std::exception& failure) {
    std::cerr << "arbiter lsp: " << printable(method) << ": " << printable(failure.what()) << "\n";
    if (request) error(id, kRequestFailed, failure.what());
  }
  return out;
}

json Server::dispatch(const std::string& method, const json& params, std::vector<json>& out) {
  if (method == "initialize") {
    initialized_ = true;
    watch_ = params.value("capabilities", json::object())
                 .value("workspace", json::object())
                 .value("didChangeWatchedFiles", json::object())
                 .value("dynamicRegistration", false);
    for (const auto& folder : params.value("workspaceFolders", json())) {
      if (folder.is_object() && folder.contains("uri") && folder["uri"].is_string())
        workspace_.push_back(uri_to_path(folder["uri"]));
    }
    if (workspace_.empty() && params.contains("rootUri") && params["rootUri"].is_string())
      workspace_.push_back(uri_to_path(params["rootUri"]));
    return {{"capabilities",
             {{"textDocumentSync", {{"openClose", true}, {"change", 1}}},
              {"completionProvider",
               {{"triggerCharacters", json::array({":", " ", ">", "[", ",", "\""})}}},
              {"hoverProvider", true},
              {"definitionProvider", true},
              {"referencesProvider", true},
              {"renameProvider", true},
              {"documentSymbolProvider", true},
              {"codeActionProvider", {{"codeActionKinds", json::array({"quickfix"})}}}}},
            {"serverInfo", {{"name", "arbiter"}}}};
  }
  if (method == "initialized") {
    // Included files and the configs that include an open file are read from the disk: a change
    // there changes diagnostics.
    if (watch_) {
      const json registration = {
          {"id", "arbiter-watch"},
          {"method", "workspace/didChangeWatchedFiles"},
          {"registerOptions",
           {{"watchers", json::array({{{"globPattern", "**/*.{yaml,yml,json}"}}})}}}};
      out.push_back({{"jsonrpc", "2.0"},
                     {"id", "arbiter-watch"},
                     {"method", "client/registerCapability"},
                     {"params", {{"registrations", json::array({registration})}}}});
    }
    return nullptr;
  }
  if (method == "workspace/didChangeWatchedFiles") {
    std::set<std::string> paths;
    for (const auto& change : params.at("changes")) {
      const std::string path = uri_to_path(change.at("uri"));
      if (!overlay_.find(path)) paths.insert(path);  // an open buffer wins over the disk
    }
    if (!paths.empty()) update(paths, true, out);
    return nullptr;
  }
  if (method == "$/cancelRequest" || method == "$/setTrace" || method == "textDocument/didSave" ||
      method == "workspace/didChangeConfiguration") {
    return nullptr;
  }
  if (method == "shutdown") {
    shutdown_ = true;
    return nullptr;
  }
  if (method == "textDocument/didOpen") {
    const json& document = params.at("textDocument");
    const std::string uri = document.at("uri");
    Open& open = open_[uri];
    open.path = uri_to_path(uri);
    open.text = document.at("text");
    overlay_.set(open.path, open.text);
    kinds_[open.path] = classify(open.path, open.text);
    update({open.path}, false, out);
    return nullptr;
  }
  if (method == "textDocument/didChange") {
    const std::string uri = params.at("textDocument").at("uri");
    auto found = open_.find(uri);
    if (found == open_.end()) throw RequestError{kInvalidParams, "document not open: " + uri};
    for (const auto& change : params.at("contentChanges")) {
      if (change.contains("range")) {
        const Lines lines(found->second.text);
        const std::size_t begin = lines.offset(change["range"]["start"]);
        const std::size_t end = lines.offset(change["range"]["end"]);
        found->second.text.replace(begin, end - begin, change.at("text").get<std::string>());
      } else {
        found->second.text = change.at("text");
      }
    }
    overlay_.set(found->second.path, found->second.text);
    kinds_[found->second.path] = classify(found->second.path, found->second.text);
    update({found->second.path}, false, out);
    return nullptr;
  }
  if (method == "textDocument/didClose") {
    const std::string uri = params.at("textDocument").at("uri");
    auto found = open_.find(uri);
    if (found != open_.end()) {
      const std::string path = found->second.path;
      overlay_.erase(path);
      open_.erase(found);
      owners_.erase(path);
      kinds_.erase(path);
      update({path}, false, out);
    }
    return nullptr;
  }
  if (method == "textDocument/completion") return completion(params);
  if (method == "textDocument/hover") return hover(params);
  if (method == "textDocument/definition") return definition(params);
  if (method == "textDocument/references") return references(params);
  if (method == "textDocument/rename") return rename(params);
  if (method == "textDocument/documentSymbol") return symbols(params);
  if (method == "textDocument/codeAction") return code_actions(params);
  return {{"__method_not_found", true}};
}

bool Server::is_open(const std::string& path) const {
  return overlay_.find(path) != nullptr;
}

ConfigText Server::kind_of(const std::string& path) const {
  const auto found = kinds_.find(path);
  return found == kinds_.end() ? ConfigText::kNone : found->second;
}

std::string Server::text_on_disk_or_open(const std::string& path) const {
  if (const std::string* text = overlay_.find(path)) return *text;
  std::ifstream in(path, std::ios::binary);
  std::string text;
  if (in) text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return text;
}

std::shared_ptr<const Analysis> Server::analyse(const std::string& root) const {
  auto analysis = std::make_shared<Analysis>();
  analysis->root = root;
  analysis->registry = std::make_unique<Registry>(make_registry_());
  analysis->loaded = load_config(root, *analysis->registry, options_);
  report_plugin_path(*analysis);
  Indexer(*analysis).run();
  return analysis;
}

std::string Server::includer_of(const std::string& path, std::set<std::string>& visited) const {
  namespace fs = std::filesystem;
  // The innermost workspace folder that holds the file, else the folder above the file's own.
  fs::path top = fs::path(path).parent_path().parent_path();
  std::size_t best = 0;
  for (const auto& folder : workspace_) {
    if (path.rfind(folder + "/", 0) == 0 && folder.size() > best) {
      top = folder;
      best = folder.size();
    }
  }
  const std::string name = fs::path(path).filename().string();
  // The folders are walked one at a time, not with a recursive_directory_iterator: that one ends
  // at its first error (libstdc++ leaves it at its end), so a folder removed during the scan would
  // end the search. Here an error ends only the folder it happened in.
  constexpr auto options = fs::directory_options::skip_permission_denied;
  std::error_code error;  // an entry or folder that cannot be read is skipped, not the search
  std::vector<fs::directory_iterator> folders;
  folders.emplace_back(top, options, error);
  std::size_t seen = 0;
  std::string fragment;
  while (!folders.empty()) {
    if (folders.back() == fs::directory_iterator()) {
      folders.pop_back();
      continue;
    }
    const fs::directory_entry item = *folders.back();
    folders.back().increment(error);  // on an error, at the folder's end
    if (++seen > kMaxScanned) break;
    const fs::path& entry = item.path();
    const std::string leaf = entry.filename().string();
    if (item.is_directory(error)) {
      if (!(leaf.empty() || leaf[0] == '.' || leaf == "node_modules" ||
            leaf.rfind("build", 0) == 0 || folders.size() > kMaxScannedDepth ||
            item.is_symlink(error)))
        folders.emplace_back(entry, options, error);  // one that cannot be opened is at its end
      continue;
    }
    const std::string candidate = entry.lexically_normal().string();
    const std::string extension = entry.extension().string();
    if (candidate == path || visited.count(candidate) ||
        !(extension == ".yaml" || extension == ".yml" || extension == ".json") ||
        item.file_size(error) > kMaxScannedBytes)
      continue;
    const std::string text = text_on_disk_or_open(candidate);
    if (text.find(name) == std::string::npos) continue;
    const ConfigText kind = classify(candidate, text);
    if (kind == ConfigText::kNone) continue;
    Registry registry = make_registry_();
    if (!load_config(candidate, registry, options_).files.find(path)) continue;
    if (kind == ConfigText::kConfig) return candidate;
    // A file that is itself included: the config above it, if there is one.
    visited.insert(candidate);
    const std::string above = includer_of(candidate, visited);
    if (!above.empty() && classify(above, text_on_disk_or_open(above)) == ConfigText::kConfig)
      return above;
    if (fragment.empty()) fragment = above.empty() ? candidate : above;
  }
  return fragment;
}

void Server::update(const std::set<std::string>& paths, bool rescan, std::vector<json>& out) {
  // Only the configs these files belong to are loaded again: the others' diagnostics stand.
  std::set<std::string> reload;
  for (const auto& [root, analysis] : analyses_) {
    for (const auto& path : paths) {
      if (root == path || analysis->loaded.files.find(path)) reload.insert(root);
    }
  }
  // A file on disk appeared, went or changed: the config that includes an open file may be
  // another one now.
  if (rescan) owners_.clear();
  std::set<std::string> touched;  // the roots loaded again
  std::set<std::string> gone;     // files of configs no longer checked: their diagnostics go
  auto drop = [&](const std::string& root) {
    for (const auto& file : analyses_[root]->loaded.files.files()) gone.insert(file->path);
    gone.insert(root);
    analyses_.erase(root);
    good_.erase(root);
    compiled_.erase(root);
    reload.erase(root);
  };
  auto load = [&](const std::string& root) {
    auto analysis = analyse(root);
    if (analysis->loaded.document()) good_[root] = analysis;
    if (analysis->loaded.program) compiled_[root] = analysis;
    analyses_[root] = std::move(analysis);
    touched.insert(root);
  };
  // A root is kept while it is an open config, or while an open file is checked through it.
  auto needed = [&](const std::string& root) {
    if (kind_of(root) != ConfigText::kNone) return true;
    for (const auto& file : analyses_[root]->loaded.files.files()) {
      if (file->path != root && is_open(file->path)) return true;
    }
    return false;
  };
  for (const auto& root : std::set<std::string>(reload)) {
    if (needed(root)) {
      load(root);
    } else {
      drop(root);
    }
  }
  // An open included file checked on its own, or through a config that is not open, was found
  // on the disk: a config created or edited there may include it now. When the search finds
  // another one, the file moves there (the files checked through the same root are looked for
  // again below, the root being gone).
  if (rescan) {
    for (const auto& [uri, open] : open_) {
      const std::string& path = open.path;
      const Analysis* current = analysis_of(path);
      if (kind_of(path) != ConfigText::kFragment || !current ||
          kind_of(current->root) == ConfigText::kConfig)
        continue;
      std::set<std::string> visited{path};
      const std::string owner = owners_.emplace(path, includer_of(path, visited)).first->second;
      if (!owner.empty() && owner != current->root) drop(std::string(current->root));
    }
  }
  // Each open config not checked through another: a root of its own, or, for a file meant to be
  // included, checked through the config that includes it on the disk (a file alone otherwise).
  for (const auto& [uri, open] : open_) {
    const std::string& path = open.path;
    if (analysis_of(path) || kind_of(path) == ConfigText::kNone) continue;
    std::string root = path;
    if (kind_of(path) == ConfigText::kFragment) {
      auto owner = owners_.find(path);
      if (owner == owners_.end()) {
        std::set<std::string> visited{path};
        owner = owners_.emplace(path, includer_of(path, visited)).first;
      }
      if (!owner->second.empty()) root = owner->second;
    }
    if (!analyses_.count(root)) load(root);
    if (!analyses_[root]->loaded.files.find(path)) {  // that config no longer includes it
      owners_.erase(path);
      if (!needed(root)) drop(root);
      if (!analyses_.count(path)) load(path);
    }
  }
  for (auto it = analyses_.begin(); it != analyses_.end();) {
    const std::string root = it->first;
    ++it;
    if (!needed(root)) drop(root);
  }
  // A root that another root includes is checked through that one (unless each includes the
  // other: a cycle, checked from the root that came first).
  for (auto it = analyses_.begin(); it != analyses_.end();) {
    bool inside = false;
    for (const auto& [root, analysis] : analyses_) {
      if (root != it->first && analysis->loaded.files.find(it->first) &&
          !it->second->loaded.files.find(root))
        inside = true;
    }
    if (inside) {
      const std::string root = it->first;
      ++it;
      drop(root);
    } else {
      ++it;
    }
  }
  publish(touched, gone, out);
}

void Server::report_plugin_path(Analysis& analysis) const {
  const Node* root = analysis.loaded.document();
  const Node* plugins = root && root->is_mapping() ? root->find("plugins") : nullptr;
  if (!plugins) return;
  for (const auto& dir : options_.plugins.path) {
    std::error_code error;
    if (std::filesystem::is_directory(dir, error)) continue;
    analysis.loaded.diagnostics
        .warning(plugins->location(), "plugin-path-not-found",
                 fmt::format("plugin directory '{}' (--plugin-path) does not exist", dir))
        .notes.push_back("the server was started with it: correct the editor's arbiter command");
  }
  analysis.loaded.diagnostics.sort();
}

void Server::publish(const std::set<std::string>& touched, const std::set<std::string>& gone,
                     std::vector<json>& out) {
  std::set<std::string> files = gone;
  for (const auto& root : touched) {
    const auto found = analyses_.find(root);
    if (found == analyses_.end()) continue;
    files.insert(root);
    for (const auto& file : found->second->loaded.files.files()) files.insert(file->path);
  }
  // Each file's diagnostics from every config that reaches it (a file two configs include
  // gets its problems once).
  std::map<std::string, json> by_file;
  std::set<std::string> seen;
  auto add = [&](const std::string& file, json diagnostic) {
    if (seen.insert(file + diagnostic.dump()).second)
      by_file[file].push_back(std::move(diagnostic));
  };
  for (const auto& [root, analysis] : analyses_) {
    const auto& loaded = analysis->loaded;
    bool relevant = touched.count(root) > 0;
    for (const auto& file : loaded.files.files()) relevant = relevant || files.count(file->path);
    if (!relevant) continue;
    // The files each of the root's includes reaches, for problems in files that are not open.
    std::map<std::string, std::vector<std::string>> includes;
    for (const auto& item : analysis->occurrences) {
      if (item.kind == Kind::kInclude) includes[item.file].push_back(item.name);
    }
    auto reaches = [&](const std::string& from, const std::string& to) {
      std::set<std::string> visited{from};
      std::vector<std::string> stack{from};
      while (!stack.empty()) {
        const std::string at = stack.back();
        stack.pop_back();
        if (at == to) return true;
        for (const auto& next : includes[at]) {
          if (visited.insert(next).second) stack.push_back(next);
        }
      }
      return false;
    };
    for (const auto& item : loaded.diagnostics.items()) {
      if (!files.count(item.location.file)) continue;
      json diagnostic = diagnostic_json(item, analysis->lines_of(item.location.file));
      json related = json::array();
      for (const auto& note : item.notes) {
        // A note without a place of its own is about the diagnostic's.
        json location = {{"uri", path_to_uri(item.location.file)}, {"range", diagnostic["range"]}};
        if (note.location) {
          const std::string path =
              std::filesystem::path(note.location->file).lexically_normal().string();
          const int line = std::max(1, note.location->line);
          const int column = std::max(1, note.location->column);
          json range = range_json(line - 1, column - 1);
          if (const Lines* lines = analysis->lines_of(path); lines && note.location->line > 0) {
            const std::size_t begin = lines->offset(line, column);
            range = lines->range(begin, lines->token_end(begin));
          }
          location = {{"uri", path_to_uri(path)}, {"range", range}};
        }
        related.push_back({{"location", location}, {"message", note.text}});
      }
      if (!related.empty()) diagnostic["relatedInformation"] = related;
      // An error in an included file that is not open shows on the root's include that leads
      // to it, or an editor that shows open files only would show nothing wrong.
      if (item.severity == Severity::kError && item.location.file != root &&
          !is_open(item.location.file)) {
        for (const auto& include : analysis->occurrences) {
          if (include.kind != Kind::kInclude || include.file != root ||
              !reaches(include.name, item.location.file))
            continue;
          json copy = diagnostic;
          const Lines* lines = analysis->lines_of(root);
          copy["range"] = lines ? lines->range(include.begin, include.end) : range_json(0, 0);
          copy["message"] =
              fmt::format("in included file {}: {}",
                          std::filesystem::path(item.location.file)
                              .lexically_relative(std::filesystem::path(root).parent_path())
                              .string(),
                          item.message);
          copy["relatedInformation"] = json::array(
              {{{"location",
                 {{"uri", path_to_uri(item.location.file)}, {"range", diagnostic["range"]}}},
                {"message", item.message}}});
          add(root, std::move(copy));
          break;
        }
      }
      add(item.location.file, std::move(diagnostic));
    }
  }
  for (const auto& file : files) {
    auto found = by_file.find(file);
    const bool any = found != by_file.end();
    // A config, and an open file checked through one, get their (empty) list too, so that an
    // editor knows they were checked.
    if (!any && !published_.count(file) && !analyses_.count(file) &&
        !(is_open(file) && analysis_of(file)))
      continue;
    out.push_back({{"jsonrpc", "2.0"},
                   {"method", "textDocument/publishDiagnostics"},
                   {"params",
                    {{"uri", path_to_uri(file)},
                     {"diagnostics", any ? std::move(found->second) : json::array()}}}});
    if (any) {
      published_.insert(file);
    } else {
      published_.erase(file);
    }
  }
}

const Analysis* Server::analysis_of(const std::string& path) const {
  for (const auto& [root, analysis] : analyses_) {
    if (analysis->loaded.files.find(path) || root == path) return analysis.get();
  }
  return nullptr;
}

const Analysis* Server::good_analysis_of(const std::string& path) const {
  for (const auto& [root, analysis] : good_) {
    if (analysis->loaded.files.find(path) || root == path) return analysis.get();
  }
  return analysis_of(path);
}

const Program* Server::program_of(const std::string& path) const {
  for (const auto& [root, analysis] : compiled_) {
    if (analysis->loaded.files.find(path) || root == path) return &*analysis->loaded.program;
  }
  return nullptr;
}

const std::string* Server::text_of(const std::string& path) const {
  return overlay_.find(path);
}

const Server::Catalog& Server::catalog_of(const Analysis* analysis) const {
  std::unique_ptr<Registry> builtin;
  const Registry* registry = analysis ? analysis->registry.get() : nullptr;
  if (!registry) {
    builtin = std::make_unique<Registry>(make_registry_());
    registry = builtin.get();
  }
  std::string key;
  for (const auto& [name, info] : registry->classes()) key += name.first + ' ' + info.origin + '\n';
  auto found = catalogs_.find(key);
  if (found == catalogs_.end()) {
    found = catalogs_
                .emplace(key, Catalog{json::parse(catalog_json(*registry)),
                                      json::parse(config_schema(*registry))})
                .first;
  }
  return found->second;
}

namespace {

struct Cursor {
  std::string path;
  std::size_t offset = 0;
};

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

}  // namespace

json Server::completion(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const std::string* text = text_of(path);
  // Nothing for the other YAML and JSON files an editor attaches the server to.
  if (!text || (kind_of(path) == ConfigText::kNone && !analysis_of(path))) return json::array();
  const Lines lines(*text);
  const std::size_t offset = lines.offset(params.at("position"));
  const Context context = context_at(lines, offset, format_of(path) == DocumentFormat::kJson);
  const Analysis* analysis = good_analysis_of(path);
  const Catalog& catalog = catalog_of(analysis);
  json items = json::array();
  auto add = [&](const std::string& label, int kind, const std::string& detail,
                 const std::string& documentation = {}) {
    json item = {{"label", label}, {"kind", kind}};
    if (!detail.empty()) item["detail"] = detail;
    if (!documentation.empty())
      item["documentation"] = {{"kind", "markdown"}, {"value", documentation}};
    items.push_back(std::move(item));
  };
  auto keys = [&](const json& definition) {
    std::vector<std::string> names;
    schema_keys(catalog.schema, definition, names);
    for (const auto& name : names) add(name, 10, "key");
  };
  auto definition = [&](const char* name) { return catalog.schema["definitions"][name]; };
  auto classes = [&](const char* kind) {
    for (const auto& cls : catalog.classes["classes"]) {
      if (cls.value("kind", "") == kind)
        add(cls["name"], 7, cls.value("origin", ""), class_markdown(cls));
    }
  };
  auto names = [&](Kind kind, const std::string& scope, bool any_scope) {
    if (!analysis) return;
    std::set<std::string> seen;
    for (const auto& item : analysis->occurrences) {
      if (item.definition && item.kind == kind && (any_scope || item.scope == scope) &&
          seen.insert(item.name).second) {
        add(item.name, kind == Kind::kActuator ? 6 : kind == Kind::kMachine ? 9 : 12, item.detail);
      }
    }
  };
  // The layer the cursor is in: the last layer name declared above it in this file.
  auto layer_here = [&]() -> std::pair<std::string, bool> {
    if (!analysis) return {"", true};
    std::string layer;
    bool found = false;
    for (const auto& item : analysis->occurrences) {
      if (item.kind == Kind::kLayer && item.file == path && item.begin <= offset) {
        layer = item.name;
        found = true;
      }
    }
    return {layer, !found};
  };
  const auto& p = context.path;
  using At = Context::At;
  if (context.at == At::kKey) {
    if (p.empty()) {
      keys(catalog.schema);
    } else if (matches(p, {"layers", "*"})) {
      keys(definition("layer"));
    } else if (matches(p, {"layers", "*", "actuators", "*"})) {
      keys(definition("actuator"));
    } else if (matches(p, {"layers", "*", "behaviours", "*"})) {
      keys(definition("behaviour"));
    } else if (matches(p, {"state_machines", "*"})) {
      keys(definition("state_machine"));
    } else if (matches(p, {"state_machines", "*", "states", "*"})) {
      keys(definition("state"));
    } else if (matches(p, {"state_machines", "*", "queue", "*"})) {
      names(Kind::kState, p[1], false);
    } else if (matches(p, {"layers", "*", "behaviours", "*", "params"}) ||
               matches(p, {"state_machines", "*", "states", "*", "params"})) {
      // The params of the class the enclosing behaviour or state names.
      const Kind kind = p[0] == "layers" ? Kind::kBehaviour : Kind::kState;
      std::string type;
      if (analysis) {
        for (const auto& item : analysis->occurrences) {
          if (item.definition && item.kind == kind && item.name == p[3]) type = item.detail;
        }
      }
      for (const auto& cls : catalog.classes["classes"]) {
        if (cls.value("name", "") != type) continue;
        for (const auto& param : cls["params"]) {
          add(param["name"], 5, param_summary(param), param.value("description", ""));
        }
      }
    }
  } else if (context.at == At::kValue) {
    const std::string& key = context.key;
    if (key == "type" && matches(p, {"layers", "*", "behaviours", "*"})) {
      classes("behaviour");
    } else if (key == "type" && matches(p, {"layers", "*", "actuators", "*"})) {
      for (const auto& type : catalog.classes["value_types"])
        add(type["name"], 22, type.value("origin", ""));
    } else if (key == "interface") {
      classes("interface");
    } else if ((key == "type" && matches(p, {"state_machines", "*", "states", "*"})) ||
               matches(p, {"state_machines", "*", "states"})) {
      classes("state");
    } else if (matches(p, {"layers", "*", "behaviours"})) {
      classes("behaviour");
    } else if (key == "machine") {
      names(Kind::kMachine, {}, true);
    } else if (key == "go_to") {
      if (p.size() >= 2 && p[0] == "state_machines") names(Kind::kState, p[1], false);
    } else if (!p.empty() && p.back() == "ports") {
      names(Kind::kActuator, {}, true);
    } else if (key == "sensors") {
      names(Kind::kActuator, {}, true);
    }
  } else {
    const std::string list = p.empty() ? std::string() : p.back();
    if (list == "inhibitions" || list == "sensors" || list == "queue") {
      if (list == "inhibitions") {
        const auto [layer, any] = layer_here();
        names(Kind::kBehaviour, layer, any);
      } else if (list == "sensors") {
        names(Kind::kActuator, {}, true);
      } else if (p.size() >= 2 && p[0] == "state_machines") {
        names(Kind::kState, p[1], false);
      }
    }
  }
  return {{"isIncomplete", false}, {"items", items}};
}

json Server::hover(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = good_analysis_of(path);
  const Catalog& catalog = catalog_of(analysis);
  if (!analysis) return nullptr;
  const Cursor cursor = cursor_of(params, analysis);
  const Lines* lines = analysis->lines_of(path);
  const Occurrence* item = analysis->at(path, cursor.offset);
  // The last program that compiled: a config being edited is often invalid for a while.
  const Program* program = program_of(path);
  const auto& model = analysis->loaded.model;
  std::string text;
  std::size_t begin = 0, end = 0;
  if (item) {
    begin = item->begin;
    end = item->end;
    if (item->kind == Kind::kClass) {
      for (const auto& cls : catalog.classes["classes"]) {
        if (cls.value("name", "") == item->name) text = class_markdown(cls);
      }
      if (text.empty()) text = fmt::format("unknown class `{}`", item->name);
    } else if (item->kind == Kind::kBehaviour) {
      const Occurrence* definition = analysis->definition_of(*item);
      text = fmt::format("**behaviour** `{}` in layer `{}`", item->name, item->scope);
      if (definition && !definition->detail.empty())
        text += fmt::format(" (class `{}`)", definition->detail);
      text += "\n";
      std::optional<std::uint32_t> index =
          program ? program->find_behaviour(item->scope, item->name) : std::nullopt;
      if (index) {
        auto name = [&](std::uint32_t b) { return program->behaviours[b].name; };
        auto describe = [&](const CompiledInhibition& inhibition) {
          std::string line =
              fmt::format("`{}` {} `{}`", name(inhibition.inhibitor),
                          inhibition.chaining ? "=>" : "->", name(inhibition.inhibited));
          if (inhibition.implicit) {
            std::string chain;
            for (auto b : program->chain(inhibition.inhibitor, inhibition.inhibited)) {
              chain += (chain.empty() ? "" : " => ") + name(b);
            }
            line = fmt::format("`{}` inhibits `{}`, implied by chaining {}",
                               name(inhibition.inhibitor), name(inhibition.inhibited), chain);
          }
          return line;
        };
        text += "\nInhibited by:\n";
        const auto by = program->inhibitions.of(*index);
        if (by.empty()) text += "- nothing\n";
        for (const auto& inhibition : by) text += "- " + describe(inhibition) + "\n";
        text += "\nInhibits:\n";
        bool any = false;
        const auto& layer = program->layers[program->behaviours[*index].layer];
        for (std::uint32_t b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
          for (const auto& inhibition : program->inhibitions.of(b)) {
            if (inhibition.inhibitor != *index) continue;
            text += "- " + describe(inhibition) + "\n";
            any = true;
          }
        }
        if (!any) text += "- nothing\n";
      }
    } else if (item->kind == Kind::kActuator) {
      text = fmt::format("**actuator** `{}`", item->name);
      if (model) {
        if (const ActuatorDecl* actuator = model->find_actuator(item->name)) {
          text += fmt::format(" of layer `{}`, type `{}`{}", actuator->layer,
                              actuator->type ? actuator->type->name : "?",
                              actuator->aggregate ? ", aggregate" : "");
        }
        std::string writers, readers;
        for (const auto& layer : model->layers) {
          for (const auto& port : layer.ports) {
            if (port.target != item->name || !port.port) continue;
            (port.port->direction == PortDirection::kOutput ? writers : readers) += fmt::format(
                "- interface of layer `{}` (port `{}`)\n", layer.name.text, port.port->name);
          }
          for (const auto& sensor : layer.sensors) {
            if (sensor.text == item->name)
              readers += fmt::format("- layer `{}` (sensor)\n", layer.name.text);
          }
          for (const auto& behaviour : layer.behaviours) {
            for (const auto& port : behaviour.ports) {
              if (port.target != item->name || !port.port) continue;
              (port.port->direction == PortDirection::kOutput ? writers : readers) += fmt::format(
                  "- `{}/{}` (port `{}`)\n", layer.name.text, behaviour.name.text, port.port->name);
            }
          }
        }
        text += "\n\nWritten by:\n" + (writers.empty() ? "- nothing\n" : writers);
        text += "\nRead by:\n" + (readers.empty() ? "- nothing\n" : readers);
      }
    } else if (item->kind == Kind::kState) {
      const Occurrence* definition = analysis->definition_of(*item);
      text = fmt::format("**state** `{}` of state machine `{}`", item->name, item->scope);
      if (definition && !definition->detail.empty())
        text += fmt::format(" (class `{}`)", definition->detail);
    } else if (item->kind == Kind::kMachine) {
      text = fmt::format("**state machine** `{}`", item->name);
    } else if (item->kind == Kind::kLayer) {
      text = fmt::format("**layer** `{}`", item->name);
    } else if (item->kind == Kind::kInclude) {
      text = fmt::format("includes `{}`", item->name);
    }
  }
  // An inhibition line: what it implies through chaining.
  for (const auto& site : analysis->inhibitions) {
    if (site.file != path || cursor.offset < site.begin ||
        cursor.offset > std::max(site.end, site.begin) || item)
      continue;
    begin = site.begin;
    end = site.end;
    text = fmt::format("**inhibition** `{}` {} `{}` ({})\n", site.inhibitor,
                       site.chaining ? "=>" : "->", site.inhibited,
                       site.chaining ? "chaining" : "non-chaining");
    if (!program) break;
    const auto from = program->find_behaviour(site.layer, site.inhibitor);
    const auto via = program->find_behaviour(site.layer, site.inhibited);
    if (!from || !via) break;
    std::string implied;
    const auto& layer = program->layers[program->behaviours[*from].layer];
    for (std::uint32_t b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
      for (const auto& inhibition : program->inhibitions.of(b)) {
        if (!inhibition.implicit) continue;
        const auto chain = program->chain(inhibition.inhibitor, inhibition.inhibited);
        for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
          if (chain[i] != *from || chain[i + 1] != *via) continue;
          std::string path_text;
          for (auto c : chain)
            path_text += (path_text.empty() ? "" : " => ") + program->behaviours[c].name;
          implied += fmt::format("- `{}` inhibits `{}` ({})\n",
                                 program->behaviours[inhibition.inhibitor].name,
                                 program->behaviours[inhibition.inhibited].name, path_text);
          break;
        }
      }
    }
    text += "\nImplies through chaining:\n" + (implied.empty() ? "- nothing\n" : implied);
    break;
  }
  if (text.empty()) return nullptr;
  json result = {{"contents", {{"kind", "markdown"}, {"value", text}}}};
  if (lines) result["range"] = lines->range(begin, end);
  return result;
}

json Server::definition(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = good_analysis_of(path);
  if (!analysis) return nullptr;
  const Cursor cursor = cursor_of(params, analysis);
  const Occurrence* item = analysis->at(path, cursor.offset);
  if (!item) return nullptr;
  if (item->kind == Kind::kInclude)
    return {{"uri", path_to_uri(item->name)}, {"range", range_json(0, 0)}};
  const Occurrence* definition = analysis->definition_of(*item);
  if (!definition) return nullptr;
  return location_json(*analysis, definition->file, definition->begin, definition->end);
}

json Server::references(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = good_analysis_of(path);
  json result = json::array();
  if (!analysis) return result;
  const Cursor cursor = cursor_of(params, analysis);
  const Occurrence* item = analysis->at(path, cursor.offset);
  if (!item || item->kind == Kind::kInclude) return result;
  const bool declaration =
      params.value("context", json::object()).value("includeDeclaration", true);
  for (const auto& other : analysis->occurrences) {
    if (other.kind != item->kind || other.scope != item->scope || other.name != item->name)
      continue;
    if (other.definition && !declaration) continue;
    result.push_back(location_json(*analysis, other.file, other.begin, other.end));
  }
  return result;
}

json Server::rename(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = analysis_of(path);
  if (!analysis) throw RequestError{kRequestFailed, "the file is not open"};
  const Cursor cursor = cursor_of(params, analysis);
  const Occurrence* item = analysis->at(path, cursor.offset);
  if (!item || item->kind == Kind::kClass || item->kind == Kind::kInclude) {
    throw RequestError{kRequestFailed,
                       "only a behaviour, actuator, layer, state or state machine can be renamed"};
  }
  const std::string name = params.at("newName");
  if (!is_identifier(name)) {
    throw RequestError{kRequestFailed,
                       fmt::format("'{}' is not a valid name: names are [a-z_][a-z0-9_]*", name)};
  }
  for (const auto& other : analysis->occurrences) {
    if (other.definition && other.kind == item->kind && other.scope == item->scope &&
        other.name == name) {
      throw RequestError{kRequestFailed, fmt::format("'{}' is already taken", name)};
    }
  }
  json changes = json::object();
  for (const auto& other : analysis->occurrences) {
    if (other.kind != item->kind || other.scope != item->scope || other.name != item->name)
      continue;
    const Lines* lines = analysis->lines_of(other.file);
    if (!lines) continue;
    changes[path_to_uri(other.file)].push_back(
        {{"range", lines->range(other.begin, other.end)}, {"newText", name}});
  }
  return {{"changes", changes}};
}

json Server::symbols(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = good_analysis_of(path);
  json result = json::array();
  if (!analysis) return result;
  const Lines* lines = analysis->lines_of(path);
  if (!lines) return result;
  auto symbol = [&](const Occurrence& item, int kind, const std::string& detail) {
    json range = lines->range(item.begin, item.end);
    return json{{"name", item.name},       {"kind", kind},
                {"detail", detail},        {"range", range},
                {"selectionRange", range}, {"children", json::array()}};
  };
  json* layer = nullptr;
  json* machine = nullptr;
  std::string machine_name;
  for (const auto& item : analysis->occurrences) {
    if (item.file != path) continue;
    if (item.kind == Kind::kLayer) {
      result.push_back(symbol(item, 3, "layer"));
      layer = &result.back();
      machine = nullptr;
    } else if (item.kind == Kind::kMachine && item.definition) {
      result.push_back(symbol(item, 23, "state machine"));
      machine = &result.back();
      machine_name = item.name;
      layer = nullptr;
    } else if (item.kind == Kind::kBehaviour && item.definition && layer) {
      (*layer)["children"].push_back(symbol(item, 5, item.detail));
    } else if (item.kind == Kind::kActuator && item.definition && layer) {
      (*layer)["children"].push_back(symbol(item, 8, "actuator " + item.detail));
    } else if (item.kind == Kind::kActuator && item.detail == "sensor" && layer) {
      (*layer)["children"].push_back(symbol(item, 13, "sensor"));
    } else if (item.kind == Kind::kState && item.definition && machine &&
               item.scope == machine_name) {
      (*machine)["children"].push_back(symbol(item, 12, item.detail));
    }
  }
  return result;
}

json Server::code_actions(const json& params) const {
  const std::string uri = params.at("textDocument").at("uri");
  const std::string path = uri_to_path(uri);
  const std::string* text = text_of(path);
  json actions = json::array();
  if (!text) return actions;
  const Lines lines(*text);
  for (const auto& diagnostic :
       params.value("context", json::object()).value("diagnostics", json::array())) {
    if (diagnostic.value("source", "") != "arbiter") continue;
    if (auto name = suggestion_of(diagnostic)) {
      actions.push_back(
          {{"title", fmt::format("Change to '{}'", *name)},
           {"kind", "quickfix"},
           {"diagnostics", json::array({diagnostic})},
           {"isPreferred", true},
           {"edit",
            {{"changes",
              {{uri, json::array({{{"range", diagnostic["range"]}, {"newText", *name}}})}}}}}});
    }
    if (diagnostic.value("code", "") == "redundant-inhibition") {
      const std::size_t begin = lines.offset(diagnostic["range"]["start"]);
      std::size_t end = lines.token_end(begin);
      const std::size_t line = lines.line_of(begin);
      // The item's extent: to the end of the line in a block sequence, else the flow item.
      std::size_t from = begin, to = end;
      const std::string before =
          text->substr(lines.line_start(line), begin - lines.line_start(line));
      const bool block = before.find_first_not_of(' ') != std::string::npos &&
                         before.substr(before.find_first_not_of(' ')).rfind("- ", 0) == 0 &&
                         before.find_first_not_of(" -") == std::string::npos;
      if (block) {
        from = lines.line_start(line);
        to = line + 1 < lines.line_count() ? lines.line_start(line + 1) : text->size();
      } else {
        if (!(text->at(begin) == '"' || text->at(begin) == '\'')) {
          // an unquoted flow item runs to the next ',' or ']'
          to = text->find_first_of(",]\n", begin);
          while (to > begin && (*text)[to - 1] == ' ') --to;
        }
        // With the comma before it (or, for the first item, the one after it).
        const auto space = [&](std::size_t at) {
          return std::isspace(static_cast<unsigned char>((*text)[at])) != 0;
        };
        std::size_t back = from;
        while (back > 0 && space(back - 1)) --back;
        if (back > 0 && (*text)[back - 1] == ',') {
          from = back - 1;
        } else {
          std::size_t after = to;
          while (after < text->size() && space(after)) ++after;
          if (after < text->size() && (*text)[after] == ',') {
            to = after + 1;
            while (to < text->size() && space(to)) ++to;
          }
        }
      }
      actions.push_back(
          {{"title", "Remove the inhibition: chaining already implies it"},
           {"kind", "quickfix"},
           {"diagnostics", json::array({diagnostic})},
           {"edit",
            {{"changes",
              {{uri, json::array({{{"range", lines.range(from, to)}, {"newText", ""}}})}}}}}});
    }
  }
  return actions;
}

int run(std::istream& in, std::ostream& out, std::function<Registry()> make_registry,
        LoadOptions options) {
  Server server(std::move(make_registry), std::move(options));
  std::string ended;
  while (auto frame = read_frame(in, &ended)) {
    std::vector<json> replies;
    if (!frame->skipped.empty()) {
      std::cerr << "arbiter lsp: skipped bytes that are not a message: " << frame->skipped << "\n";
    }
    if (!frame->error.empty()) {
      std::cerr << "arbiter lsp: " << printable(frame->error) << "\n";
      replies.push_back({{"jsonrpc", "2.0"},
                         {"id", nullptr},
                         {"error", {{"code", kInvalidRequest}, {"message", frame->error}}}});
    } else {
      replies = server.handle(frame->body);
    }
    for (const auto& reply : replies) {
      write_frame(out, reply.dump(-1, ' ', false, json::error_handler_t::replace));
    }
    if (server.exited()) return server.exit_code();
  }
  if (!ended.empty()) std::cerr << "arbiter lsp: " << ended << "\n";
  return server.exited() ? server.exit_code() : 1;
}

}  // namespace arbiter::lsp

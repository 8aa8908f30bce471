// The documents the server checks: which files are configs (by their text), the config that
// includes an open file, loading again what an edit or a change on the disk touches, and the
// analyses and class catalogs the requests read.

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>

#include "arbiter/catalog.hpp"
#include "arbiter/schema.hpp"
#include "lsp/analysis.hpp"
#include "lsp/server.hpp"

namespace arbiter::lsp {

namespace {

// Bounds on the search for the config that includes an open file: the files looked at, and the
// size of a file read to check it.
constexpr std::size_t kMaxScanned = 20000;
constexpr std::uintmax_t kMaxScannedBytes = 4u << 20;
constexpr std::size_t kMaxScannedDepth = 8;  // folders below the one searched

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

}  // namespace

// An Arbiter config (or a file a config includes) has one of the top-level keys only an Arbiter
// config has (`arbiter`, `layers`, `state_machines`), or its `$schema` (a key, or a YAML language
// server comment) names a file called `arbiter...`. A package.json, a CI workflow or a
// docker-compose.yaml has none of these.
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
  index_config(*analysis);
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
  for (const auto& [name, info] : registry->classes())
    key += name.first + ' ' + info->origin + '\n';
  auto found = catalogs_.find(key);
  if (found == catalogs_.end()) {
    found = catalogs_
                .emplace(key, Catalog{json::parse(catalog_json(*registry)),
                                      json::parse(config_schema(*registry))})
                .first;
  }
  return found->second;
}

}  // namespace arbiter::lsp

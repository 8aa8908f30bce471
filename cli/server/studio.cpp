#include "server/studio.hpp"

#include <fmt/format.h>
#include <httplib.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>

#include "arbiter/catalog.hpp"
#include "arbiter/dump.hpp"
#include "arbiter/reload.hpp"
#include "commands/output_file.hpp"

namespace arbiter::cli {

namespace {

using Json = nlohmann::ordered_json;

/// Texts and messages quote what was read: bytes that are not UTF-8 are replaced, not thrown on.
std::string dump(const Json& json) {
  return json.dump(-1, ' ', false, Json::error_handler_t::replace);
}

Reply json_reply(int status, const Json& body) {
  return {status, dump(body)};
}

Reply refusal(int status, const std::string& message) {
  return json_reply(status, Json{{"error", message}});
}

std::optional<std::string> read_disk(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return std::nullopt;
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

/// The config loaded from `texts` (the disk for a file they do not hold).
EditedConfig load_texts(const std::string& config, const std::map<std::string, std::string>& texts,
                        Registry& registry, LoadOptions options) {
  EditedConfig loaded;
  loaded.texts = std::make_unique<Overlay>();
  for (const auto& [path, text] : texts) loaded.texts->set(path, text);
  options.source = loaded.texts.get();
  loaded.loaded = load_config(config, registry, options);
  return loaded;
}

}  // namespace

std::string new_config_text(const std::string& path) {
  // The manager's name from the file's: an identifier, as names must be.
  const auto slash = path.rfind('/');
  std::string stem = path.substr(slash == std::string::npos ? 0 : slash + 1);
  stem = stem.substr(0, stem.find('.'));
  std::string name;
  for (const char c : stem) {
    const char lower = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    name += (std::islower(static_cast<unsigned char>(lower)) ||
             std::isdigit(static_cast<unsigned char>(lower)) || lower == '_')
                ? lower
                : '_';
  }
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name.front()))) name.insert(0, "_");
  if (format_of(path) == DocumentFormat::kJson)
    return fmt::format("{{\n  \"arbiter\": 1,\n  \"name\": \"{}\",\n  \"layers\": []\n}}\n", name);
  return fmt::format("arbiter: 1\nname: {}\nlayers: []\n", name);
}

Studio::Studio(std::string config, Registry& registry, LoadOptions options)
    : config_(std::move(config)), registry_(registry), options_(std::move(options)) {
  // A config that does not exist yet, or is empty, opens as the smallest valid one, to be built
  // in the studio: nothing is written before the first save.
  const auto on_disk = read_disk(config_);
  if (!on_disk || on_disk->find_first_not_of(" \t\r\n") == std::string::npos) {
    order_.push_back(config_);
    texts_[config_] = new_config_text(config_);
    disk_[config_] = on_disk.value_or("");
  }
  reload();
  saved_ = load_texts(config_, disk_, registry_, options_);
}

void Studio::reload() {
  adopt(load_texts(config_, texts_, registry_, options_));
}

void Studio::adopt(EditedConfig loaded) {
  current_ = std::move(loaded);
  for (const auto& file : current_.loaded.files.files()) {
    if (texts_.count(file->path) != 0) continue;
    order_.push_back(file->path);
    texts_[file->path] = file->text;
    disk_[file->path] = read_disk(file->path).value_or(file->text);
  }
}

bool Studio::read_now(const std::string& path) const {
  if (path == config_) return true;
  const auto& files = current_.loaded.files.files();
  return std::any_of(files.begin(), files.end(),
                     [&](const auto& file) { return file->path == path; });
}

std::string Studio::state_json(const std::string& extra_key, const std::string& extra) {
  Json state;
  state["config"] = config_;
  Json files = Json::array();
  for (const auto& path : order_) {
    const std::string on_disk = read_disk(path).value_or("");
    files.push_back({{"path", path},
                     {"text", texts_[path]},
                     {"base", disk_[path]},
                     {"edited", texts_[path] != disk_[path]},
                     // Changed by someone else since it was read or saved: a save would conflict.
                     {"changed_on_disk", on_disk != disk_[path]}});
  }
  state["files"] = std::move(files);
  const Loaded& loaded = current_.loaded;
  state["messages"] = format(loaded.diagnostics);
  // What the Structure panel offers to add: a plugin the config names already is not offered.
  Json plugins = Json::array();
  for (auto& name : plugins_on_path(options_.plugins)) {
    const bool named =
        loaded.model && std::any_of(loaded.model->plugins.begin(), loaded.model->plugins.end(),
                                    [&](const Name& n) { return n.text == name; });
    if (!named) plugins.push_back(std::move(name));
  }
  state["plugins_to_add"] = std::move(plugins);
  const Loaded& base = saved_.loaded;
  if (loaded.program && base.program) {
    state["review"] = format(config_diff(*base.program, *loaded.program), "");
  } else {
    state["review"] = nullptr;
  }
  // The dump and the diagnostics are JSON already: spliced in as they are, not parsed again.
  std::string out = dump(state);
  out.pop_back();  // its closing brace
  out += R"(,"graph":)";
  out += loaded.program ? dump_json(*loaded.program, {}, -1) : "null";
  out += R"(,"diagnostics":)";
  out += format_json(loaded.diagnostics);
  if (!extra_key.empty()) out += fmt::format(R"(,"{}":{})", extra_key, extra);
  out += '}';
  return out;
}

Reply Studio::state() {
  std::lock_guard lock(mutex_);
  return {200, state_json()};
}

Reply Studio::classes() {
  std::lock_guard lock(mutex_);
  return {200, catalog_json(registry_)};
}

Reply Studio::edit(const std::string& body) {
  std::lock_guard lock(mutex_);
  const Loaded& loaded = current_.loaded;
  OperationResult operation = apply_operation(loaded, body, &registry_);
  if (!operation.invalid.empty()) return refusal(400, operation.invalid);
  EditResult result = std::move(operation.result);
  // The same check every operation gets: an edit that would leave an error the config did not
  // have is refused with that error, as `arbiter validate` words it.
  EditedConfig edited;
  result = checked(loaded, std::move(result), registry_, options_, &edited);
  if (!result.ok()) {
    return {422, state_json("refused", dump(Json(result.refused)))};
  }
  Json edits = Json::array();
  for (const auto& edit : result.edits) {
    edits.push_back(
        {{"file", edit.file}, {"begin", edit.begin}, {"end", edit.end}, {"text", edit.text}});
  }
  for (auto& [path, text] : texts_) text = apply_edits(text, path, result.edits);
  // The check loaded the edited texts already (unless the texts had errors to begin with).
  if (edited.texts) {
    adopt(std::move(edited));
  } else {
    reload();
  }
  return {200, state_json("edits", dump(edits))};
}

Reply Studio::set_texts(const std::string& body) {
  const Json request = Json::parse(body, nullptr, false);
  if (!request.is_object() || !request.contains("texts") || !request["texts"].is_object())
    return refusal(400, R"(the body is not {"texts": {PATH: TEXT, ...}})");
  std::lock_guard lock(mutex_);
  for (const auto& [path, text] : request["texts"].items()) {
    if (texts_.count(path) == 0)
      return refusal(403, fmt::format("refused: '{}' is not one of the config's files", path));
    if (!text.is_string())
      return refusal(400, fmt::format("the text of '{}' is not a string", path));
  }
  for (const auto& [path, text] : request["texts"].items()) texts_[path] = text.get<std::string>();
  reload();
  return {200, state_json()};
}

Reply Studio::revert() {
  std::lock_guard lock(mutex_);
  for (const auto& path : order_) {
    if (auto on_disk = read_disk(path)) {
      disk_[path] = *on_disk;
      texts_[path] = std::move(*on_disk);
    }
  }
  reload();
  saved_ = load_texts(config_, disk_, registry_, options_);
  return {200, state_json()};
}

Reply Studio::save(const std::string& body) {
  const Json request = Json::parse(body, nullptr, false);
  if (!request.is_object() || !request.contains("files") || !request["files"].is_array())
    return refusal(400, R"(the body is not {"files": [{"path", "text", "base"}, ...]})");
  std::lock_guard lock(mutex_);
  // Every file is checked before any is written: a refusal writes nothing.
  std::vector<std::pair<std::string, std::string>> writes;
  for (const auto& file : request["files"]) {
    if (!file.is_object() || !file.contains("path") || !file["path"].is_string() ||
        !file.contains("text") || !file["text"].is_string() || !file.contains("base") ||
        !file["base"].is_string())
      return refusal(400, "each file needs 'path', 'text' and 'base', as strings");
    const std::string path = file["path"].get<std::string>();
    // Only the config and the files its load reads now, as it wrote them: no other file,
    // however named, nor one that an include no longer names (the studio still holds its text).
    // Both: read_now() holds for the config by its name even when its load could not read it (too
    // big, unreadable), and then the studio holds no text of it, has shown none, and writes none.
    if (texts_.count(path) == 0 || !read_now(path))
      return refusal(403, fmt::format("refused: '{}' is not one of the config's files", path));
    // A new config's base is "": the file is not there yet, or is empty.
    if (read_disk(path).value_or("") != file["base"].get<std::string>()) {
      return refusal(409, fmt::format("conflict: {} changed on the disk since it was opened; "
                                      "nothing was written (reload it to see the change)",
                                      path));
    }
    writes.emplace_back(path, file["text"].get<std::string>());
  }
  for (const auto& [path, text] : writes) {
    std::string error;
    if (!write_atomically(path, text, error)) return refusal(500, error);
    disk_[path] = text;
    texts_[path] = text;
  }
  reload();
  saved_ = load_texts(config_, disk_, registry_, options_);
  const std::string applied = after_save_ ? after_save_() : "null";
  return {200, state_json("applied", applied)};
}

void Studio::attach(httplib::Server& http) {
  const auto send = [](httplib::Response& response, const Reply& reply) {
    response.status = reply.first;
    response.set_content(reply.second, "application/json");
  };
  http.Get("/studio/state", [this, send](const httplib::Request&, httplib::Response& response) {
    send(response, state());
  });
  http.Get("/studio/classes", [this, send](const httplib::Request&, httplib::Response& response) {
    send(response, classes());
  });
  http.Post("/studio/edit",
            [this, send](const httplib::Request& request, httplib::Response& response) {
              send(response, edit(request.body));
            });
  http.Post("/studio/texts",
            [this, send](const httplib::Request& request, httplib::Response& response) {
              send(response, set_texts(request.body));
            });
  http.Post("/studio/revert", [this, send](const httplib::Request&, httplib::Response& response) {
    send(response, revert());
  });
  http.Post("/studio/save",
            [this, send](const httplib::Request& request, httplib::Response& response) {
              send(response, save(request.body));
            });
}

}  // namespace arbiter::cli

#include "server/studio.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <httplib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>

#include "arbiter/catalog.hpp"
#include "arbiter/dump.hpp"
#include "arbiter/reload.hpp"

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

SymbolKind kind_named(const std::string& name, bool& known) {
  known = true;
  if (name == "behaviour") return SymbolKind::kBehaviour;
  if (name == "actuator") return SymbolKind::kActuator;
  if (name == "layer") return SymbolKind::kLayer;
  if (name == "state") return SymbolKind::kState;
  if (name == "machine") return SymbolKind::kMachine;
  known = false;
  return SymbolKind::kBehaviour;
}

/// A string member of a request, or "" (and `missing` names it).
std::string field(const Json& request, const char* key, std::string& missing) {
  const auto found = request.find(key);
  if (found == request.end() || !found->is_string() || found->get<std::string>().empty()) {
    if (missing.empty()) missing = key;
    return "";
  }
  return found->get<std::string>();
}

/// A position (an integer from 0) of a request, or nullopt (and `missing` names it).
std::optional<std::size_t> position(const Json& request, const char* key, std::string& missing) {
  const auto found = request.find(key);
  if (found == request.end() || !found->is_number_unsigned()) {
    if (missing.empty()) missing = key;
    return std::nullopt;
  }
  return found->get<std::size_t>();
}

/// Why a request lacks a member, saying how the new operations' members are written.
std::string needs(const std::string& op, const std::string& missing) {
  return fmt::format("{} needs '{}' (names as strings, positions as integers from 0)", op, missing);
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

bool write_atomically(const std::string& path, const std::string& text, std::string& error) {
  const auto slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  std::string temp = fmt::format("{}/.{}.arbiter-XXXXXX", dir, name);
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) {
    error = fmt::format("cannot write in {}: {}", dir, std::strerror(errno));
    return false;
  }
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0) ::fchmod(fd, info.st_mode & 07777);
  std::size_t done = 0;
  bool ok = true;
  while (ok && done < text.size()) {
    const auto written = ::write(fd, text.data() + done, text.size() - done);
    if (written < 0 && errno == EINTR) continue;
    ok = written > 0;
    if (ok) done += static_cast<std::size_t>(written);
  }
  ok = ok && ::fsync(fd) == 0;
  const int saved_errno = errno;
  ok = ::close(fd) == 0 && ok;
  if (ok && ::rename(temp.c_str(), path.c_str()) == 0) return true;
  error = fmt::format("cannot write {}: {}", path, std::strerror(ok ? errno : saved_errno));
  ::unlink(temp.c_str());
  return false;
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
  const Json request = Json::parse(body, nullptr, false);
  if (!request.is_object()) return refusal(400, "the body is not a JSON object");
  std::string missing;
  const std::string op = field(request, "op", missing);
  std::lock_guard lock(mutex_);
  const Loaded& loaded = current_.loaded;
  EditResult result;
  if (op == "add_inhibition" || op == "remove_inhibition" || op == "flip_chaining") {
    InhibitionRef inhibition{field(request, "layer", missing), field(request, "inhibitor", missing),
                             field(request, "inhibited", missing)};
    if (!missing.empty()) return refusal(400, fmt::format("{} needs '{}'", op, missing));
    if (op == "add_inhibition") {
      result = add_inhibition(loaded, inhibition, request.value("chaining", true));
    } else if (op == "remove_inhibition") {
      result = remove_inhibition(loaded, inhibition);
    } else {
      result = flip_chaining(loaded, inhibition);
    }
  } else if (op == "set_param") {
    const std::string layer = field(request, "layer", missing);
    const std::string behaviour = field(request, "behaviour", missing);
    const std::string param = field(request, "param", missing);
    if (!request.contains("value") && missing.empty()) missing = "value";
    if (!missing.empty()) return refusal(400, fmt::format("{} needs '{}'", op, missing));
    // JSON is a YAML flow value too: one text serves both formats.
    result = set_param(loaded, layer, behaviour, param, dump(request["value"]));
  } else if (op == "add_behaviour" || op == "remove_behaviour") {
    const std::string layer = field(request, "layer", missing);
    const std::string name = field(request, "name", missing);
    const std::string type = op == "add_behaviour" ? field(request, "type", missing) : "";
    if (!missing.empty()) return refusal(400, fmt::format("{} needs '{}'", op, missing));
    result = op == "add_behaviour" ? add_behaviour(loaded, layer, name, type)
                                   : remove_behaviour(loaded, layer, name);
  } else if (op == "rename") {
    const std::string kind_name = field(request, "kind", missing);
    const std::string name = field(request, "name", missing);
    const std::string to = field(request, "to", missing);
    if (!missing.empty()) return refusal(400, fmt::format("{} needs '{}'", op, missing));
    bool known = false;
    const SymbolKind kind = kind_named(kind_name, known);
    if (!known) {
      return refusal(400, fmt::format("cannot rename a '{}': a behaviour, actuator, layer, state "
                                      "or machine can be renamed",
                                      kind_name));
    }
    const std::string scope = request.value("scope", "");
    const ConfigIndex index = index_config(loaded, &registry_);
    const Occurrence* symbol = nullptr;
    for (const auto& occurrence : index.occurrences) {
      if (occurrence.definition && occurrence.kind == kind && occurrence.name == name &&
          (scope.empty() || occurrence.scope == scope)) {
        symbol = &occurrence;
        break;
      }
    }
    if (symbol == nullptr) {
      result.refused = scope.empty() ? fmt::format("no {} '{}' is declared", kind_name, name)
                                     : fmt::format("no {} '{}' in '{}'", kind_name, name, scope);
    } else {
      result = rename_symbol(loaded, index, *symbol, to);
    }
  } else if (op == "move_behaviour") {
    const std::string layer = field(request, "layer", missing);
    const std::string name = field(request, "name", missing);
    const auto index = position(request, "index", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = move_behaviour(loaded, layer, name, request.value("to_layer", ""), *index);
  } else if (op == "move_layer") {
    const std::string layer = field(request, "layer", missing);
    const auto index = position(request, "index", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = move_layer(loaded, layer, *index);
  } else if (op == "add_layer") {
    const std::string name = field(request, "name", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    std::size_t index = kAtEnd;
    if (request.contains("index")) {
      const auto given = position(request, "index", missing);
      if (!given) return refusal(400, needs(op, missing));
      index = *given;
    }
    result = add_layer(loaded, name, index, request.value("interface", ""));
  } else if (op == "remove_layer") {
    const std::string name = field(request, "name", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = remove_layer(loaded, name);
  } else if (op == "add_sensor" || op == "remove_sensor") {
    const std::string layer = field(request, "layer", missing);
    const std::string name = field(request, "name", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result =
        op == "add_sensor" ? add_sensor(loaded, layer, name) : remove_sensor(loaded, layer, name);
  } else if (op == "add_plugin") {
    const std::string name = field(request, "name", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = add_plugin(loaded, name);
  } else if (op == "add_state_machine" || op == "remove_state_machine") {
    const std::string name = field(request, "name", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = op == "add_state_machine"
                 ? add_state_machine(loaded, name)
                 : remove_state_machine(loaded, index_config(loaded, &registry_), name);
  } else if (op == "add_actuator" || op == "remove_actuator") {
    const std::string layer = field(request, "layer", missing);
    const std::string name = field(request, "name", missing);
    const std::string type = op == "add_actuator" ? field(request, "type", missing) : "";
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = op == "add_actuator" ? add_actuator(loaded, layer, name, type)
                                  : remove_actuator(loaded, layer, name);
  } else if (op == "wire_port") {
    const std::string layer = field(request, "layer", missing);
    const std::string behaviour = field(request, "behaviour", missing);
    const std::string port = field(request, "port", missing);
    const std::string target = field(request, "target", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = wire_port(loaded, layer, behaviour, port, target);
  } else if (op == "add_queue_entry") {
    const std::string machine = field(request, "machine", missing);
    const std::string state = field(request, "state", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    std::vector<std::pair<std::string, std::string>> params;
    if (request.contains("params")) {
      if (!request["params"].is_object())
        return refusal(400, "add_queue_entry's 'params' is not an object of param values");
      // JSON is a YAML flow value too: one text serves both formats.
      for (const auto& [param, value] : request["params"].items())
        params.emplace_back(param, dump(value));
    }
    std::size_t index = kAtEnd;
    if (request.contains("index")) {
      const auto given = position(request, "index", missing);
      if (!given) return refusal(400, needs(op, missing));
      index = *given;
    }
    result = add_queue_entry(loaded, machine, state, params, index);
  } else if (op == "remove_queue_entry") {
    const std::string machine = field(request, "machine", missing);
    const auto index = position(request, "index", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = remove_queue_entry(loaded, machine, *index);
  } else if (op == "add_state" || op == "remove_state") {
    const std::string machine = field(request, "machine", missing);
    const std::string name = field(request, "name", missing);
    const std::string type = op == "add_state" ? field(request, "type", missing) : "";
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = op == "add_state"
                 ? add_state(loaded, machine, name, type)
                 : remove_state(loaded, index_config(loaded, &registry_), machine, name);
  } else if (op == "move_queue_entry") {
    const std::string machine = field(request, "machine", missing);
    const auto from = position(request, "from", missing);
    const auto to = position(request, "to", missing);
    if (!missing.empty()) return refusal(400, needs(op, missing));
    result = move_queue_entry(loaded, machine, *from, *to);
  } else if (!missing.empty()) {
    return refusal(400, "an operation needs 'op'");
  } else {
    return refusal(400, fmt::format("no operation '{}': add_inhibition, remove_inhibition, "
                                    "flip_chaining, set_param, add_behaviour, "
                                    "remove_behaviour, rename, move_behaviour, move_layer, "
                                    "add_layer, remove_layer, add_actuator, remove_actuator, "
                                    "add_sensor, remove_sensor, wire_port, add_plugin, "
                                    "add_state_machine, "
                                    "remove_state_machine, "
                                    "add_state, remove_state, add_queue_entry, "
                                    "remove_queue_entry or move_queue_entry",
                                    op));
  }
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
    // Only the paths the config's load read, as it wrote them: no other file, however named.
    if (texts_.count(path) == 0)
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

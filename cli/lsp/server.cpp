// The protocol: a message in, the responses and notifications out. Handle parses and checks it,
// dispatch routes a request to its handler (documents.cpp, publish.cpp, completion.cpp,
// navigation.cpp), and run() connects the server to a framed stream.

#include "lsp/server.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <set>

#include "lsp/analysis.hpp"
#include "lsp/framing.hpp"

namespace arbiter::lsp {

namespace {

// JSON-RPC and LSP error codes (kRequestFailed: analysis.hpp).
constexpr int kParseError = -32700;
constexpr int kInvalidRequest = -32600;
constexpr int kMethodNotFound = -32601;
constexpr int kInvalidParams = -32602;
constexpr int kServerNotInitialized = -32002;

}  // namespace

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
    error(nullptr, kInvalidRequest, "'id' must be an integer or a string");
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
    // nlohmann's text without its "[json.exception.type_error.302] ", which tells a client
    // nothing: "type must be string, but is number".
    std::string_view text = failure.what();
    if (const auto end = text.find("] ");
        !text.empty() && text.front() == '[' && end != text.npos) {
      text.remove_prefix(end + 2);
    }
    const std::string why = "invalid params: " + std::string(text);
    // A notification has no answer to carry it: a malformed didOpen would leave the document
    // without diagnostics, and nobody told why.
    if (request) {
      error(id, kInvalidParams, why);
    } else {
      std::cerr << "arbiter lsp: " << printable(method) << ": " << printable(why) << "\n";
    }
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
              {"codeActionProvider",
               {{"codeActionKinds", json::array({"quickfix", "refactor.rewrite"})},
                {"resolveProvider", true}}}}},
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
  if (method == "codeAction/resolve") return resolve_code_action(params);
  return {{"__method_not_found", true}};
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

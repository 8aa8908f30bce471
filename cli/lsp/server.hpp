#pragma once
// `arbiter lsp`: a Language Server Protocol server over the engine's own load pipeline. The
// Server handles decoded messages and returns what to send, with no I/O of its own, so that
// tests and benchmarks drive it directly; run() connects it to a framed stream (framing.hpp).

#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "arbiter/load.hpp"
#include "arbiter/registry.hpp"

namespace arbiter::lsp {

struct Analysis;

/// What a file is by its text, as the server decides which files to check (docs/editors.md).
enum class ConfigText {
  kNone,      ///< not an Arbiter config
  kFragment,  ///< a config without a `name`: a file meant to be included
  kConfig,    ///< a config with a `name`: a root
};

class Server {
 public:
  /// `make_registry` gives a registry of the built-in classes: each config is loaded into a
  /// fresh one, so that the plugins one config names are unknown to every other.
  Server(std::function<Registry()> make_registry, LoadOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Handles one message's JSON text: a malformed one is answered with a JSON-RPC error.
  /// Returns the responses and notifications to send, in order.
  std::vector<nlohmann::json> handle(const std::string& text);
  std::vector<nlohmann::json> handle(const nlohmann::json& message);

  /// After the `exit` notification: the process exits with exit_code().
  bool exited() const { return exited_; }
  /// 0 when `shutdown` came before `exit`, 1 otherwise (as the protocol says).
  int exit_code() const { return shutdown_ ? 0 : 1; }

 private:
  struct Open {
    std::string path;
    std::string text;
  };
  using json = nlohmann::json;
  /// The classes a registry knows, as completion and hover read them.
  struct Catalog {
    json classes;  // catalog_json()
    json schema;   // config_schema()
  };

  json dispatch(const std::string& method, const json& params, std::vector<json>& out);
  /// After `paths` changed (opened, edited, closed; on the disk when `rescan`): loads again the
  /// configs they belong to, and no other, then publishes what changed.
  void update(const std::set<std::string>& paths, bool rescan, std::vector<json>& out);
  /// Publishes the diagnostics of the files of the `touched` roots and clears those of `gone`.
  void publish(const std::set<std::string>& touched, const std::set<std::string>& gone,
               std::vector<json>& out);
  std::shared_ptr<const Analysis> analyse(const std::string& root) const;
  /// The config on the disk (or open) that includes `path`, the topmost one that has a `name`;
  /// empty when none is found in the workspace folder that holds it (else the folder above it).
  std::string includer_of(const std::string& path, std::set<std::string>& visited) const;
  bool is_open(const std::string& path) const;
  /// What an open file is, by its text (kNone when it is not open).
  ConfigText kind_of(const std::string& path) const;
  std::string text_on_disk_or_open(const std::string& path) const;
  /// A --plugin-path directory that does not exist, on each config that names plugins.
  void report_plugin_path(Analysis& analysis) const;
  const Analysis* analysis_of(const std::string& path) const;
  const Analysis* good_analysis_of(const std::string& path) const;
  const Program* program_of(const std::string& path) const;
  const std::string* text_of(const std::string& path) const;
  const Catalog& catalog_of(const Analysis* analysis) const;

  json completion(const json& params) const;
  json hover(const json& params) const;
  json definition(const json& params) const;
  json references(const json& params) const;
  json rename(const json& params) const;
  json symbols(const json& params) const;
  json code_actions(const json& params) const;
  /// codeAction/resolve: the edit of an action offered without one (adding a behaviour, the
  /// moves, removing an actuator or a queue item), checked.
  json resolve_code_action(const json& action) const;

  std::function<Registry()> make_registry_;
  LoadOptions options_;
  Overlay overlay_;
  std::map<std::string, Open> open_;                                 // by URI
  std::map<std::string, std::shared_ptr<const Analysis>> analyses_;  // by root path
  std::map<std::string, std::shared_ptr<const Analysis>> good_;      // the last that parsed
  std::map<std::string, std::shared_ptr<const Analysis>> compiled_;  // the last that compiled
  std::set<std::string> published_;                                  // files with diagnostics
  std::map<std::string, std::string> owners_;  // an open included file -> the config checked
  std::map<std::string, ConfigText> kinds_;    // what each open file is, by path
  std::vector<std::string> workspace_;         // the client's workspace folders
  bool watch_ = false;                         // the client registers file watchers when asked
  // By the classes a registry knows, with their origins: a config's plugins add classes.
  mutable std::map<std::string, Catalog> catalogs_;
  bool initialized_ = false;
  bool shutdown_ = false;
  bool exited_ = false;
};

/// Serves `in` and `out` until `exit` or the end of the input; returns the exit status.
int run(std::istream& in, std::ostream& out, std::function<Registry()> make_registry,
        LoadOptions options);

}  // namespace arbiter::lsp

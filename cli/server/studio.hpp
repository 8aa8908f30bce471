#pragma once
// The studio's HTTP API (`arbiter edit`, `arbiter run --serve --edit`; docs/studio.md): a config's
// texts as the browser edits them, not yet saved. Each operation is one of the edit engine's
// (arbiter/edit.hpp), run against those texts; the answer holds its edits, the new texts and what
// `arbiter validate` says of them. Save writes only the config's own files, each atomically, and
// only while each still holds the text the edit started from.

#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "arbiter/edit.hpp"
#include "arbiter/load.hpp"
#include "arbiter/registry.hpp"

namespace httplib {
class Server;
}

namespace arbiter::cli {

/// An HTTP status and a JSON body.
using Reply = std::pair<int, std::string>;

class Studio {
 public:
  /// Applies saved files (run --edit: the transactional reload) and says how, as a JSON object.
  using AfterSave = std::function<std::string()>;

  /// Reads `config` (and the files it includes) from the disk, with `registry` (which must
  /// outlive the studio; its plugins are loaded into it).
  Studio(std::string config, Registry& registry, LoadOptions options);
  Studio(const Studio&) = delete;
  Studio& operator=(const Studio&) = delete;

  void set_after_save(AfterSave hook) { after_save_ = std::move(hook); }
  /// Adds the API's routes to `http`, before it serves: GET /studio/state and /studio/classes,
  /// POST /studio/edit, /studio/texts, /studio/revert and /studio/save.
  void attach(httplib::Server& http);

  /// The files (text as edited and as on the disk), the graph of the texts (the dump, null when
  /// they do not compile), their diagnostics and the review: what saving would change.
  Reply state();
  /// Every class of the registry with its params (`arbiter plugins --format json`).
  Reply classes();
  /// One operation, {"op": ..., ...}, applied to the texts: 200 with the edits and the state,
  /// 422 with why it was refused (and the texts unchanged), 400 for a request that is not one.
  Reply edit(const std::string& body);
  /// Replaces texts: {"texts": {PATH: TEXT, ...}} (an edit in the text pane, an undo); 403 for a
  /// path that is not one of the config's files.
  Reply set_texts(const std::string& body);
  /// Reads the config's files from the disk again, in place of the texts edited: after a change
  /// made on the disk (a save would be a conflict), or to drop the edits.
  Reply revert();
  /// {"files": [{"path", "text", "base"}, ...]}: each written (temp file, then rename) when every
  /// path is the config or a file its current load reads (else 403) and every file still holds
  /// `base` (else 409);
  /// nothing is written otherwise.
  Reply save(const std::string& body);

 private:
  /// Loads the texts again; files the load newly reads join them.
  void reload();
  /// `loaded` (of the texts) as the current load; files it newly reads join the texts.
  void adopt(EditedConfig loaded);
  std::string state_json(const std::string& extra_key = "", const std::string& extra = "");
  /// `path` is the config or a file the current load reads (not one an include named before).
  bool read_now(const std::string& path) const;

  std::string config_;
  Registry& registry_;
  LoadOptions options_;
  std::vector<std::string> order_;            // the files, the config first
  std::map<std::string, std::string> texts_;  // as edited
  std::map<std::string, std::string> disk_;   // as last read or written
  EditedConfig current_;                      // the texts loaded
  EditedConfig saved_;                        // the disk's texts loaded: the review's base
  AfterSave after_save_;
  std::mutex mutex_;  // one request at a time: each reads and replaces the texts
};

/// What the studio opens for a config file that does not exist yet or is empty: `arbiter: 1`,
/// a `name:` made from the file's name, and `layers: []`, in the file's format.
std::string new_config_text(const std::string& path);

}  // namespace arbiter::cli

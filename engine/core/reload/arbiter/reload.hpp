#pragma once
// engine/core/reload: an edited config and a running Manager in; a new Program staged in the
// manager (swapped in between two steps, state carried over) or the edit's diagnostics out.
//
// Hot reload (docs/hot_reload.md): a running manager's config is loaded again, validated and
// compiled on the caller's thread; a valid one is staged in the manager, which swaps it in at
// the start of its next step, carrying over what matches. The structural diff between the two
// programs tells a person (or an embedder's log) what the edit changed.

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/model.hpp"
#include "arbiter/program.hpp"

namespace arbiter {

/// One structural difference between two programs.
struct Change {
  enum class Kind { kAdded, kRemoved, kChanged };
  Kind kind = Kind::kChanged;
  /// "layer", "behaviour", "inhibition", "actuator", "controller", or "config" (its name or
  /// rate_hz: config_diff()).
  std::string item;
  /// "control/kick_ball", "control: kick_ball => go_behind_ball", "gait_velocity", "goalie".
  std::string name;
  /// For a change, what changed: "class soccer.KickBall -> scripted", "params", ...
  std::string detail;
};

struct ProgramDiff {
  std::vector<Change> changes;  ///< layers, behaviours, inhibitions, actuators, controllers
  bool empty() const { return changes.empty(); }
};

/// What differs from `before` to `after`: layers, behaviours (class), declared inhibitions
/// (chaining or not), actuators (type, aggregation, layer, default) and controllers
/// (declaration), each added, removed or changed. Params are not in a Program: Reloader adds
/// the behaviours and interface layers whose params changed from the models.
ProgramDiff diff(const Program& before, const Program& after);

/// diff() and the params that changed, of behaviours, interface layers and states: what an edit
/// changed, as a hot reload reports it; and the config's name and rate_hz ("config" changes),
/// which a reload keeps but two runs may differ by. Both programs need their models
/// (Program::model); a params change needs them, and both programs' classes from one registry.
ProgramDiff config_diff(const Program& before, const Program& after);

/// One line per change, each indented by `indent`: `+ behaviour control/kick_ball (scripted)`,
/// `- inhibition control: a => b`, `~ behaviour control/b: params`.
std::string format(const ProgramDiff& diff, const std::string& indent = "  ");

struct ReloadResult {
  /// True when the new program was staged: the manager swaps it in at the start of its next
  /// step. False when it had an error (or a warning under `strict`): the running program
  /// goes on untouched.
  bool staged = false;
  Diagnostics diagnostics;  ///< errors, warnings and lints of the new config, sorted
  ProgramDiff diff;         ///< empty when not staged (or when nothing changed)
  /// Matched behaviours (`layer/name`), interface layers and controllers that do not keep
  /// their instance: their declaration or port handles changed (behaviours and interfaces are
  /// offered carry_over(); controllers restart from their configured queue).
  std::vector<std::string> restarted;
};

/// Loads a config for a manager and reloads it while the manager runs. reload() may be called
/// from a thread other than the one that steps the manager (one reloading thread at a time);
/// the manager swaps the new program in inside step(), without allocating. The registry, the
/// Reloader and the manager must outlive one another's use: the registry outlives both.
class Reloader {
 public:
  explicit Reloader(Registry& registry, LoadOptions options = {});
  ~Reloader();
  Reloader(const Reloader&) = delete;
  Reloader& operator=(const Reloader&) = delete;

  /// The first load of `path` (as load_config does), for the manager that reload() will
  /// update.
  std::optional<Program> load(const std::string& path, Diagnostics& diagnostics);

  /// Loads the config of load() again and, when it is valid, stages it in `manager` (which must
  /// run the program of load() or of an earlier reload). A program staged earlier and not yet
  /// swapped in is taken back first; what the last swap replaced is freed here.
  ReloadResult reload(Manager& manager);

  const std::string& path() const { return path_; }
  /// The config file and every file it includes (of the last config that was read far enough
  /// to know them), to watch for changes.
  const std::vector<std::string>& files() const { return files_; }
  /// Files of a config: (path, text), the config first, then its includes.
  using FileTexts = std::vector<std::pair<std::string, std::string>>;
  /// Called by reload(), on its thread, with the files of the new config just before it is
  /// staged: what a recording keeps of the reload (Recorder::stage_files). Set it before any
  /// reload() call.
  void set_on_staging(std::function<void(const FileTexts&)> hook) { on_staging_ = std::move(hook); }

 private:
  std::optional<Program> load_program(Diagnostics& diagnostics);

  Registry& registry_;
  LoadOptions options_;
  std::string path_;
  std::vector<std::string> files_;
  FileTexts texts_;  // of the last load
  std::function<void(const FileTexts&)> on_staging_;
};

}  // namespace arbiter

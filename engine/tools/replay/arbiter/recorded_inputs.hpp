#pragma once
// engine/tools/replay: a recording in; its inputs out as an interface class that feeds a run
// again, and substitute.hpp's class swaps, for `arbiter replay` and what-if runs.
//
// The inputs of a recorded run (recording.hpp) as an interface class: each interface layer that
// has it writes, step by step, the values its actuators had in the recorded run, and reports
// again what that layer reported, instead of talking to a world, a robot or DDS. It feeds
// `arbiter replay` and the scenario tests that replay a recording (`replay:`, scenario.hpp).

#include <cstdint>
#include <istream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/model.hpp"
#include "arbiter/recorded_scene.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

namespace mcap {
class Reader;
struct Record;
}  // namespace mcap
class RecordedInputsLayer;

/// What replay needs of a recording besides its steps (read those with open_trace()).
struct RecordedRun {
  RecordingInfo info;
  /// Each step's `/arbiter/inputs` message, in order.
  std::vector<std::pair<std::uint64_t, std::string>> inputs;
  /// Each hot reload: the last step before it, and the files (path, text) of the config it
  /// loaded (empty in recordings that did not keep them).
  struct Reload {
    std::uint64_t after_step = 0;
    std::vector<std::pair<std::string, std::string>> files;
  };
  std::vector<Reload> reloads;
  std::uint64_t dropped = 0;               ///< steps the recorder dropped (its gap records)
  std::optional<std::uint64_t> first_gap;  ///< the last step before the first dropped one
  std::uint64_t first_gap_dropped = 0;     ///< the steps the first gap dropped
};

/// Why a replay of a recording ends before the recording does.
enum class ReplayCut {
  kDropped,        ///< the recorder dropped steps there: their inputs are lost
  kReloaded,       ///< the config was reloaded there, and this replay does not apply reloads
  kReloadNotKept,  ///< the config was reloaded there, and the recording does not hold its files
};
/// The warning for a replay that ends after `after_step`, worded alike by every tool that replays
/// a recording: `dropped` is kDropped's count of steps, `replayer` who replays ("the replay",
/// "the test").
std::string replay_cut(ReplayCut why, std::uint64_t after_step, std::uint64_t dropped,
                       std::string_view replayer);

/// Reads the config, inputs and reloads of the recording at `path`, whole; nullopt with `error`
/// set when it is not a readable recording. A recording cut off while written gives what it
/// holds.
std::optional<RecordedRun> read_recorded_run(const std::string& path, Diagnostic& error);

/// What replay needs of a recording besides its steps, read in file order as a replay goes, never
/// whole: the config first, then each step's inputs, and the reloads and dropped steps between
/// them where they happened.
class RecordingReader {
 public:
  /// Opens the recording and reads it up to its config; check error().
  explicit RecordingReader(const std::string& path);
  ~RecordingReader();
  RecordingReader(const RecordingReader&) = delete;
  RecordingReader& operator=(const RecordingReader&) = delete;

  const std::optional<Diagnostic>& error() const { return error_; }
  const RecordingInfo& info() const { return info_; }

  struct Event {
    enum class Kind { kInputs, kReload, kGap };
    Kind kind = Kind::kInputs;
    /// kInputs: the step; kReload, kGap: the last step before it
    std::uint64_t step = 0;
    std::string text;  ///< kInputs: the step's `/arbiter/inputs` message
    /// kInputs: the step's `/arbiter/scene` message (empty when the step drew nothing), and the
    /// byte of the file where it (or its chunk) starts
    std::string scene;
    std::uint64_t scene_offset = 0;
    std::vector<std::pair<std::string, std::string>> files;  ///< kReload: as RecordedRun::Reload
    std::uint64_t dropped = 0;                               ///< kGap: how many steps
  };
  /// The next event; false at the end of the recording or on an error (error()). A recording cut
  /// off while written ends where it was cut (its steps say so: open_trace()).
  bool next(Event& event);

 private:
  void fail(std::string message);
  bool read(Event& event);
  // The records after a step's inputs that are the step's too (its scene message), up to the
  // next event's first record, which is kept in record_ for read().
  void read_step_rest(Event& event, std::uint64_t log_time);

  std::string path_;
  std::unique_ptr<std::istream> in_;
  std::unique_ptr<mcap::Reader> reader_;
  std::unique_ptr<mcap::Record> record_;
  std::optional<Diagnostic> error_;
  RecordingInfo info_;
  bool config_ = false;
  std::vector<Event> ahead_;
  bool held_ = false;          // record_ holds a record read on past a step, not yet taken
  bool ended_ = false;         // the reader has returned false
  std::uint64_t inputs_ = 0;   // inputs messages read
  std::uint64_t dropped_ = 0;  // steps the gaps read say were dropped
};

/// The recorded inputs of a run, by actuator name and step. A replay that applies hot reloads
/// adds it to its manager as an observer, so that load() stops feeding the layers of a program a
/// reload replaced (they would convert every step's inputs again, and fail on an actuator whose
/// type the reload changed).
class RecordedInputs : public Observer {
 public:
  /// All the inputs of a run: each step's `/arbiter/inputs` message (RecordedRun::inputs).
  explicit RecordedInputs(const std::vector<std::pair<std::uint64_t, std::string>>& messages);
  /// The inputs of one step at a time, each given by load() before it is stepped: a replay that
  /// streams its recording (RecordingReader).
  RecordedInputs();
  RecordedInputs(const RecordedInputs&) = delete;
  RecordedInputs& operator=(const RecordedInputs&) = delete;

  /// The interface class that writes the recorded inputs: substitute it for interface layers
  /// (substitute.hpp). It must outlive the program compiled with it, and so must this object.
  const ClassInfo& interface_class() const { return class_; }

  /// Binds every interface layer of `model` to interface_class(): the layer's class is not
  /// created, its params are not used. Then check_places().
  void replace_interfaces(Model& model, Diagnostics& diagnostics) const;

  /// Reports, at `where`, each recorded input that no layer of `model` bound to
  /// interface_class() declares; a type that does not fit is reported when the program compiles.
  void check_places(const Model& model, const SourceLocation& where,
                    Diagnostics& diagnostics) const;

  /// The step numbers recorded.
  std::uint64_t steps() const { return steps_; }

  /// In place of the step held: the inputs of `step`, its `/arbiter/inputs` message (empty when
  /// the step has none), taken at once by every interface layer bound to interface_class(),
  /// and its `/arbiter/scene` message (empty when the step drew nothing), which the first of
  /// those layers draws in the step as the recorded run's viewer showed it. False, with the
  /// error in `diagnostics`, when a value does not fit its actuator's type, or the inputs or
  /// scene message (from `recording`) is not one a recorder writes. Call it between steps: it
  /// parses and allocates, so that the step itself does neither.
  bool load(std::uint64_t step, const std::string& message, Diagnostics& diagnostics,
            const std::string& scene = std::string(), const SourceLocation& recording = {});
  /// The steps held: first_held() and the held() - 1 after it.
  std::uint64_t first_held() const { return first_; }
  std::uint64_t held() const { return reported_.size(); }

  struct Column {
    std::string name;
    /// Per held step (index step - first_held()): the value, as a config's value reads (kNull
    /// where the step recorded none, which `recorded` tells from a recorded null).
    std::vector<Node> values;
    std::vector<char> recorded;
    std::vector<char> written;
  };
  const Column* find(const std::string& name) const;

  /// What interface code reported in a step, which interface layer reported it ("" in
  /// recordings that did not say: the first interface layer reports those again), and whether
  /// in the input pass (else the output pass, as recordings that did not say are replayed).
  struct Report {
    std::string layer;
    std::string text;
    bool input_pass = false;
  };
  /// What was reported in `step` (empty when nothing).
  const std::vector<Report>& reported(std::uint64_t step) const;
  /// True for the first caller only: the layer that reports what a recording did not attribute.
  bool claim_unattributed() const;
  /// Draws the recorded picture of the step held, if it drew, when `layer` is the one that draws.
  /// Allocation-free.
  void draw(const RecordedInputsLayer* layer, const StepContext& ctx) const;
  /// The layers that load() gives each step to.
  void remember(RecordedInputsLayer* layer) const;
  void forget(RecordedInputsLayer* layer) const;

  /// Whether a manager runs the program compiled first: layers compiled from then on are for a
  /// hot reload.
  bool running() const { return running_; }
  void on_start(const Manager& manager) override;
  void on_step(const Manager&) override {}
  /// The layers of `next` are fed from here on; those of the running program are fed until it is
  /// replaced, but a value that does not fit them is no error, since they will not run it.
  void on_staged(const Program& next, std::uint64_t stage) override;
  /// Forgets the layers of the program replaced, which no step runs again.
  void on_reload(const Manager& manager) override;

 private:
  /// False when `message` is not a JSON object with an "inputs" object.
  bool add(std::uint64_t step, const std::string& message);

  std::vector<Column> columns_;
  // Where every recorded value is, for what reads it: the recording, as a whole.
  NodeLocation recording_{std::make_shared<const std::string>("recording"), 1, 1};
  std::vector<std::vector<Report>> reported_;  // per held step
  std::uint64_t first_ = 1;
  std::uint64_t steps_ = 0;
  mutable std::vector<RecordedInputsLayer*> layers_;
  RecordedScene scene_;     // what the recorded run's viewer showed after the step held
  bool scene_now_ = false;  // the step held drew
  // The layer that draws the picture: the first of layers_, so that it is drawn once.
  mutable const RecordedInputsLayer* drawer_ = nullptr;
  bool running_ = false;
  std::vector<const Interface*> staged_;  // the interfaces of the program staged, until swapped in
  ClassInfo class_;
  mutable bool unattributed_claimed_ = false;
};

}  // namespace arbiter

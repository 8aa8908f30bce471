#include "arbiter/recorded_inputs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>

#include "arbiter/behaviour.hpp"
#include "arbiter/document.hpp"
#include "arbiter/init_context.hpp"
#include "core/record/mcap.hpp"

namespace arbiter {

namespace {

/// A recorded value as the document node its JSON text reads as, without the text: the value a
/// JSON config would give (strings quoted, numbers and booleans plain scalars in their JSON
/// spelling).
Node to_node(const nlohmann::ordered_json& value, const NodeLocation& at) {
  switch (value.type()) {
    case nlohmann::ordered_json::value_t::array: {
      Node node(Node::Kind::kSequence, at);
      for (const auto& item : value) node.push_item(to_node(item, at));
      return node;
    }
    case nlohmann::ordered_json::value_t::object: {
      Node node(Node::Kind::kMapping, at);
      for (const auto& [key, item] : value.items()) node.add_entry(key, at, to_node(item, at));
      return node;
    }
    case nlohmann::ordered_json::value_t::string: {
      Node node(Node::Kind::kScalar, at);
      node.set_scalar(value.get<std::string>(), true);
      return node;
    }
    case nlohmann::ordered_json::value_t::null:
    case nlohmann::ordered_json::value_t::discarded:
      return Node(Node::Kind::kNull, at);
    default: {
      Node node(Node::Kind::kScalar, at);
      node.set_scalar(value.dump(), false);
      return node;
    }
  }
}

/// `node` (from to_node()) as JSON again, for a message.
std::string json_text(const Node& node) {
  switch (node.kind()) {
    case Node::Kind::kNull:
      return "null";
    case Node::Kind::kScalar:
      return node.quoted() ? nlohmann::json(node.text()).dump() : node.text();
    case Node::Kind::kSequence: {
      std::string text = "[";
      for (const auto& item : node.items()) {
        text += (text.size() > 1 ? "," : "") + json_text(item);
      }
      return text + "]";
    }
    case Node::Kind::kMapping: {
      std::string text = "{";
      for (const auto& entry : node.entries()) {
        text += (text.size() > 1 ? "," : "") + nlohmann::json(entry.key).dump() + ":" +
                json_text(entry.value);
      }
      return text + "}";
    }
  }
  return "null";
}

}  // namespace

/// Writes its layer's actuators from the recording: what the recorded run's interface wrote.
/// Holds the steps RecordedInputs holds (all of them, or the one a streamed replay is at), their
/// values converted to the actuators' types, so that the step loop parses and allocates nothing.
class RecordedInputsLayer : public Interface {
 public:
  explicit RecordedInputsLayer(const RecordedInputs& inputs) : inputs_(inputs) {}
  ~RecordedInputsLayer() override { inputs_.forget(this); }

  void init(InitContext& ctx) override {
    // Resolved here, so that the output pass compares no names.
    unattributed_ = inputs_.claim_unattributed();
    name_ = ctx.name();
    for (const auto& actuator : ctx.layer_actuators()) {
      const auto* column = inputs_.find(actuator.name);
      if (column == nullptr) {
        ctx.error(actuator.location,
                  fmt::format("the recording has no input '{}': the recorded run's interface "
                              "layers did not declare it",
                              actuator.name));
        continue;
      }
      Feed feed;
      feed.name = actuator.name;
      feed.type = actuator.type;
      feed.location = actuator.location;
      feed.output = ctx.output_to_actuator(actuator.name, actuator.location);
      feeds_.push_back(std::move(feed));
    }
    // A layer compiled for a hot reload takes its first step at the next load(): the step held
    // now is the last of the program it replaces, in that program's types.
    std::string error;
    SourceLocation where;
    if (!inputs_.running() && !take(error, where)) ctx.error(where, error);
    inputs_.remember(this);
  }

  /// Takes the steps RecordedInputs holds now; false, with the error and where, when a value
  /// does not fit its actuator's type.
  bool take(std::string& error, SourceLocation& where) {
    const auto held = inputs_.held();
    for (auto& pass : reports_) {
      pass.assign(held, {});
    }
    for (std::uint64_t i = 0; i < held; ++i) {
      for (const auto& report : inputs_.reported(inputs_.first_held() + i)) {
        if (report.layer == name_ || (report.layer.empty() && unattributed_)) {
          reports_[report.input_pass ? kInputPass : kOutputPass][i].push_back(report.text.c_str());
        }
      }
    }
    for (auto& feed : feeds_) {
      const auto* column = inputs_.find(feed.name);
      feed.values.clear();
      feed.written.clear();
      for (std::size_t i = 0; i < held; ++i) {
        feed.values.emplace_back(*feed.type);
        feed.written.push_back(column != nullptr && column->written[i]);
        if (column == nullptr || column->recorded[i] == 0) continue;
        std::string expected;
        if (!feed.type->from_node(column->values[i], feed.values.back().data(), expected)) {
          where = feed.location;
          error = fmt::format(
              "recorded input '{}' at step {} is {}, not {} (a {}): the recording and the config "
              "replayed disagree on its type (an edited config must keep the recorded inputs' "
              "types)",
              feed.name, inputs_.first_held() + i, json_text(column->values[i]), expected,
              feed.type->name);
          return false;
        }
      }
    }
    return true;
  }

  /// Holds no step: what take() failed to convert is not written.
  void drop() {
    for (auto& pass : reports_) pass.clear();
    for (auto& feed : feeds_) {
      feed.values.clear();
      feed.written.clear();
    }
  }

  // Reported again by the layer that reported it, in the pass it reported in, so that the
  // step's reports come in the recorded order.
  void output(const StepContext& ctx) override {
    const auto index = ctx.step() - inputs_.first_held();
    if (ctx.step() < inputs_.first_held() || index >= reports_[kOutputPass].size()) return;
    for (const char* text : reports_[kOutputPass][index]) ctx.report(text);
  }

  void input(WriteContext& ctx) override {
    if (ctx.step() < inputs_.first_held()) return;
    // The world's picture at the start of the step, as the recorded world drew it when its
    // layer read it.
    if (ctx.step() == inputs_.first_held()) inputs_.draw(this, ctx);
    const auto index = ctx.step() - inputs_.first_held();
    if (index < reports_[kInputPass].size()) {
      for (const char* text : reports_[kInputPass][index]) ctx.report(text);
    }
    for (auto& feed : feeds_) {
      if (index < feed.values.size() && feed.written[index]) {
        ctx.write(feed.output, feed.values[index]);
      }
    }
  }

 private:
  struct Feed {
    std::string name;
    const ValueType* type = nullptr;
    SourceLocation location;
    AnyOutput output;
    std::vector<ValueBox> values;
    std::vector<char> written;
  };
  const RecordedInputs& inputs_;
  std::string name_;
  bool unattributed_ = false;
  std::vector<Feed> feeds_;
  enum Pass { kInputPass, kOutputPass };
  std::vector<std::vector<const char*>> reports_[2];  // this layer's, per pass, per held step
};

RecordedInputs::RecordedInputs(const std::vector<std::pair<std::uint64_t, std::string>>& messages)
    : RecordedInputs() {
  for (const auto& [step, text] : messages) steps_ = std::max(steps_, step);
  reported_.resize(steps_);
  for (const auto& [step, text] : messages) add(step, text);
}

RecordedInputs::RecordedInputs() {
  class_.name = "arbiter.RecordedInputs";
  class_.kind = ClassKind::kInterface;
  class_.origin = "replay";
  class_.make_interface = [this] { return std::make_unique<RecordedInputsLayer>(*this); };
}

bool RecordedInputs::add(std::uint64_t step, const std::string& text) {
  const auto json = nlohmann::ordered_json::parse(text, nullptr, false);
  if (!json.is_object() || !json.contains("inputs") || !json["inputs"].is_object()) return false;
  if (step < first_ || step - first_ >= reported_.size()) return true;  // not a step held
  const auto index = step - first_;
  if (json.contains("reported") && json["reported"].is_array()) {
    for (const auto& item : json["reported"]) {
      // Older recordings list the texts only.
      if (item.is_string()) reported_[index].push_back({"", item.get<std::string>()});
      if (item.is_object() && item.value("text", nlohmann::ordered_json()).is_string()) {
        const auto by = item.value("by", nlohmann::ordered_json());
        const auto pass = item.value("pass", nlohmann::ordered_json());
        reported_[index].push_back({by.is_string() ? by.get<std::string>() : std::string(),
                                    item["text"].get<std::string>(),
                                    pass.is_string() && pass.get<std::string>() == "input"});
      }
    }
  }
  for (const auto& [name, entry] : json["inputs"].items()) {
    auto* column = const_cast<Column*>(find(name));
    if (column == nullptr) {
      column = &columns_.emplace_back();
      column->name = name;
      column->values.resize(reported_.size());
      column->recorded.resize(reported_.size());
      column->written.resize(reported_.size());
    }
    column->values[index] = to_node(entry.value("value", nlohmann::ordered_json()), recording_);
    column->recorded[index] = 1;
    column->written[index] = entry.value("written", false) ? 1 : 0;
  }
  return true;
}

bool RecordedInputs::load(std::uint64_t step, const std::string& message, Diagnostics& diagnostics,
                          const std::string& scene, const SourceLocation& recording) {
  scene_now_ = !scene.empty();
  std::string bad;
  if (scene_now_ && !scene_.apply(scene, bad)) {
    diagnostics.error(recording, "bad-recording",
                      fmt::format("the /arbiter/scene message of step {}: {}", step, bad));
    return false;
  }
  first_ = step;
  steps_ = step;
  reported_.assign(1, {});
  for (auto& column : columns_) {
    column.values.assign(1, Node());
    column.recorded.assign(1, 0);
    column.written.assign(1, 0);
  }
  // A message that is not one a recorder writes would leave the step's inputs unset, and the
  // replay would differ from the recording with the run blamed for it.
  if (!message.empty() && !add(step, message)) {
    diagnostics.error(recording, "bad-recording",
                      fmt::format("the /arbiter/inputs message of step {}: not a JSON object "
                                  "with an \"inputs\" object",
                                  step));
    return false;
  }
  std::string error;
  SourceLocation where;
  for (auto* layer : layers_) {
    if (layer->take(error, where)) continue;
    // A layer of the program a staged reload replaces, whose actuator the reload changed: it
    // does not run this step (an interface kept across the reload keeps its actuators' types).
    if (!staged_.empty() && std::find(staged_.begin(), staged_.end(), layer) == staged_.end()) {
      layer->drop();
      continue;
    }
    diagnostics.error(where, "replay-input", error);
    return false;
  }
  return true;
}

void RecordedInputs::on_start(const Manager&) {
  running_ = true;
}

void RecordedInputs::on_staged(const Program& next, std::uint64_t) {
  staged_.clear();
  for (const auto& layer : next.layers) {
    if (layer.interface) staged_.push_back(layer.interface.get());
  }
}

void RecordedInputs::on_reload(const Manager& manager) {
  staged_.clear();
  const auto& running = manager.program().layers;
  layers_.erase(std::remove_if(layers_.begin(), layers_.end(),
                               [&](const RecordedInputsLayer* layer) {
                                 return std::none_of(running.begin(), running.end(),
                                                     [&](const CompiledLayer& compiled) {
                                                       return compiled.interface.get() == layer;
                                                     });
                               }),
                layers_.end());
  // The replaced program's layer that drew hands the picture on to the running program's.
  if (std::find(layers_.begin(), layers_.end(), drawer_) == layers_.end()) {
    drawer_ = layers_.empty() ? nullptr : layers_.front();
  }
}

void RecordedInputs::draw(const RecordedInputsLayer* layer, const StepContext& ctx) const {
  if (layer == drawer_ && scene_now_) scene_.draw(ctx);
}

void RecordedInputs::remember(RecordedInputsLayer* layer) const {
  layers_.push_back(layer);
  if (drawer_ == nullptr) drawer_ = layer;
}

void RecordedInputs::forget(RecordedInputsLayer* layer) const {
  layers_.erase(std::remove(layers_.begin(), layers_.end(), layer), layers_.end());
  if (drawer_ == layer) drawer_ = layers_.empty() ? nullptr : layers_.front();
}

const std::vector<RecordedInputs::Report>& RecordedInputs::reported(std::uint64_t step) const {
  static const std::vector<Report> kNone;
  return step >= first_ && step - first_ < reported_.size() ? reported_[step - first_] : kNone;
}

bool RecordedInputs::claim_unattributed() const {
  const bool first = !unattributed_claimed_;
  unattributed_claimed_ = true;
  return first;
}

const RecordedInputs::Column* RecordedInputs::find(const std::string& name) const {
  for (const auto& column : columns_) {
    if (column.name == name) return &column;
  }
  return nullptr;
}

void RecordedInputs::replace_interfaces(Model& model, Diagnostics& diagnostics) const {
  for (auto& layer : model.layers) {
    if (!layer.is_interface()) continue;
    layer.interface = &class_;
    layer.params = {};
    layer.ports.clear();
  }
  check_places(model, model.location, diagnostics);
}

void RecordedInputs::check_places(const Model& model, const SourceLocation& where,
                                  Diagnostics& diagnostics) const {
  std::vector<std::string> declared;
  for (const auto& layer : model.layers) {
    if (layer.interface != &class_) continue;
    for (const auto& actuator : layer.actuators) declared.push_back(actuator.name.text);
  }
  for (const auto& column : columns_) {
    if (std::find(declared.begin(), declared.end(), column.name) != declared.end()) continue;
    diagnostics
        .error(where, "replay-input",
               fmt::format("recorded input '{}' has no place in this config: no interface layer "
                           "declares an actuator '{}'",
                           column.name, column.name))
        .unknown_name(column.name, declared, "the config has no interface layer",
                      "interface actuators");
  }
}

RecordingReader::RecordingReader(const std::string& path)
    : path_(path),
      in_(std::make_unique<std::ifstream>(path, std::ios::binary)),
      record_(std::make_unique<mcap::Record>()) {
  if (!*in_) {
    fail("cannot read the recording");
    return;
  }
  reader_ = std::make_unique<mcap::Reader>(*in_);
  // The recorder writes the config before the first step: read up to it, keeping what comes
  // before it, but not past a step's inputs, so that a file without it is not read whole.
  Event event;
  while (!config_ && read(event)) {
    const bool step = event.kind == Event::Kind::kInputs;
    ahead_.push_back(std::move(event));
    if (step) break;
  }
  if (error_) return;
  if (!config_ || info_.files.empty()) {
    fail(reader_->truncated()
             ? mcap::cut_before_header(reader_->good_until())
             : "the recording has no 'arbiter.config' metadata with the config's files; record "
               "one with 'arbiter run CONFIG --record RUN.mcap'");
  }
}

RecordingReader::~RecordingReader() = default;

void RecordingReader::fail(std::string message) {
  error_ = Diagnostic{{path_, 0, 0}, Severity::kError, "bad-recording", std::move(message), {}};
}

bool RecordingReader::next(Event& event) {
  if (error_) return false;
  if (!ahead_.empty()) {
    event = std::move(ahead_.front());
    ahead_.erase(ahead_.begin());
    return true;
  }
  return read(event);
}

bool RecordingReader::read(Event& event) {
  event = Event();
  while (held_ || (!ended_ && reader_->next(*record_))) {
    held_ = false;
    if (record_->kind == mcap::Record::Kind::kMetadata) {
      if (record_->name == "arbiter.config") {
        config_ = true;
        for (auto& [key, value] : record_->metadata) {
          if (key.rfind("file:", 0) == 0) {
            info_.files.emplace_back(key.substr(5), std::move(value));
          } else if (key == "version") {
            info_.version = value;
          } else if (key == "plugins" && !value.empty()) {
            std::size_t start = 0;
            while (start <= value.size()) {
              const auto end = std::min(value.find('\n', start), value.size());
              info_.plugins.push_back(value.substr(start, end - start));
              start = end + 1;
            }
          }
        }
        continue;
      }
      if (record_->name == "arbiter.reload") {
        event.kind = Event::Kind::kReload;
        for (auto& [key, value] : record_->metadata) {
          if (key == "after_step") event.step = std::strtoull(value.c_str(), nullptr, 10);
          if (key.rfind("file:", 0) == 0) event.files.emplace_back(key.substr(5), std::move(value));
        }
        return true;
      }
      if (record_->name == "arbiter.gap") {
        event.kind = Event::Kind::kGap;
        for (const auto& [key, value] : record_->metadata) {
          if (key == "dropped") event.dropped = std::strtoull(value.c_str(), nullptr, 10);
          if (key == "after_step") event.step = std::strtoull(value.c_str(), nullptr, 10);
        }
        dropped_ += event.dropped;
        return true;
      }
    } else if (record_->topic == "/arbiter/inputs") {
      // Checked here, before RecordedInputs copies its values out of a parsed tree.
      if (const auto deep = find_too_deep_json(record_->data)) {
        fail(fmt::format(
            "at byte {}: an inputs message nests deeper than {} levels (at byte {} of the message)",
            record_->offset, ReadLimits().max_depth, *deep));
        return false;
      }
      event.kind = Event::Kind::kInputs;
      const auto key = record_->data.find("\"step\": ");
      const char* number = key == std::string::npos ? nullptr : record_->data.c_str() + key + 8;
      if (number == nullptr || *number < '0' || *number > '9') {
        fail(
            fmt::format("at byte {}: an inputs message without its \"step\" number, not one a "
                        "recorder writes",
                        record_->offset));
        return false;
      }
      event.step = std::strtoull(number, nullptr, 10);
      // Each step's inputs follow those of the step before it: a step beyond those the recording
      // holds (or says it dropped) is not a recorded run's, and a reader that keeps the inputs
      // per step would size that for nothing.
      if (event.step > inputs_ + dropped_ + 1) {
        fail(fmt::format(
            "at byte {}: an inputs message for step {}, after the inputs of {} steps (and {} "
            "dropped); each step's inputs follow those of the step before it",
            record_->offset, event.step, inputs_, dropped_));
        return false;
      }
      ++inputs_;
      event.text = std::move(record_->data);
      read_step_rest(event, record_->log_time);
      return true;
    }
  }
  ended_ = true;
  if (!reader_->error().empty()) fail(reader_->error());
  return false;
}

void RecordingReader::read_step_rest(Event& event, std::uint64_t log_time) {
  // The recorder writes a step's record, its inputs, then its scene and log messages, at the
  // step's log time. A scene after another is a stopping run's safe step, which no replay steps.
  while (reader_->next(*record_)) {
    if (record_->kind == mcap::Record::Kind::kMessage && record_->topic == "/arbiter/scene") {
      if (event.scene.empty() && record_->log_time == log_time) {
        event.scene = std::move(record_->data);
        event.scene_offset = record_->offset;
      }
      continue;
    }
    if (record_->kind == mcap::Record::Kind::kMetadata || record_->topic == "/arbiter/inputs") {
      held_ = true;
      return;
    }
  }
  ended_ = true;  // read() reports the reader's error, if any
}

std::string replay_cut(ReplayCut why, std::uint64_t after_step, std::uint64_t dropped,
                       std::string_view replayer) {
  switch (why) {
    case ReplayCut::kDropped:
      return fmt::format("the recording dropped {} steps after step {}; {} runs up to there",
                         dropped, after_step, replayer);
    case ReplayCut::kReloaded:
      return fmt::format("the config was reloaded after step {}; {} runs up to there", after_step,
                         replayer);
    case ReplayCut::kReloadNotKept:
      break;
  }
  return fmt::format(
      "the config was reloaded after step {} and the recording does not hold its files; {} "
      "runs up to there",
      after_step, replayer);
}

std::optional<RecordedRun> read_recorded_run(const std::string& path, Diagnostic& error) {
  RecordingReader reader(path);
  RecordedRun run;
  RecordingReader::Event event;
  while (reader.next(event)) {
    if (event.kind == RecordingReader::Event::Kind::kInputs) {
      run.inputs.emplace_back(event.step, std::move(event.text));
    } else if (event.kind == RecordingReader::Event::Kind::kReload) {
      run.reloads.push_back({event.step, std::move(event.files)});
    } else if (event.kind == RecordingReader::Event::Kind::kGap) {
      run.dropped += event.dropped;
      if (!run.first_gap) {
        run.first_gap = event.step;
        run.first_gap_dropped = event.dropped;
      }
    }
  }
  if (reader.error()) {
    error = *reader.error();
    return std::nullopt;
  }
  run.info = reader.info();
  return run;
}

}  // namespace arbiter

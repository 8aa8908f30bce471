#include "arbiter/recorded_inputs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "arbiter/behaviour.hpp"
#include "arbiter/document.hpp"
#include "arbiter/init_context.hpp"
#include "mcap.hpp"

namespace arbiter {

namespace {

/// Writes its layer's actuators from the recording: what the recorded run's interface wrote.
class Replayed : public Interface {
 public:
  explicit Replayed(const RecordedInputs& inputs) : inputs_(inputs) {}

  void init(InitContext& ctx) override {
    // Resolved here, so that the output pass compares no names.
    const bool unattributed = inputs_.claim_unattributed();
    for (auto& pass : reports_) pass.resize(inputs_.steps());
    for (std::uint64_t step = 1; step <= inputs_.steps(); ++step) {
      for (const auto& report : inputs_.reported(step)) {
        if (report.layer == ctx.name() || (report.layer.empty() && unattributed)) {
          reports_[report.input_pass ? kInputPass : kOutputPass][step - 1].push_back(
              report.text.c_str());
        }
      }
    }
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
      feed.output = ctx.output_to_actuator(actuator.name, actuator.location);
      for (std::size_t i = 0; i < column->values.size(); ++i) {
        feed.values.emplace_back(*actuator.type);
        feed.written.push_back(column->written[i]);
        if (column->values[i].empty()) continue;
        Diagnostics parsed;
        const auto node =
            parse_document(column->values[i], "recording", DocumentFormat::kJson, parsed);
        std::string expected;
        if (!node || !actuator.type->from_node(*node, feed.values.back().data(), expected)) {
          ctx.error(
              actuator.location,
              fmt::format("recorded input '{}' at step {} is {}, not {} (a {}): the edited "
                          "config must keep the recorded inputs' types",
                          actuator.name, i + 1, column->values[i], expected, actuator.type->name));
          break;
        }
      }
      feeds_.push_back(std::move(feed));
    }
  }

  // Reported again by the layer that reported it, in the pass it reported in, so that the
  // step's reports come in the recorded order.
  void output(const StepContext& ctx) override {
    const auto index = ctx.step() - 1;
    if (index >= reports_[kOutputPass].size()) return;
    for (const char* text : reports_[kOutputPass][index]) ctx.report(text);
  }

  void input(WriteContext& ctx) override {
    const auto index = ctx.step() - 1;
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
    AnyOutput output;
    std::vector<ValueBox> values;
    std::vector<char> written;
  };
  const RecordedInputs& inputs_;
  std::vector<Feed> feeds_;
  enum Pass { kInputPass, kOutputPass };
  std::vector<std::vector<const char*>> reports_[2];  // this layer's, per pass, per step - 1
};

}  // namespace

RecordedInputs::RecordedInputs(const std::vector<std::pair<std::uint64_t, std::string>>& messages) {
  for (const auto& [step, text] : messages) steps_ = std::max(steps_, step);
  for (const auto& [step, text] : messages) {
    const auto json = nlohmann::ordered_json::parse(text, nullptr, false);
    if (step == 0 || !json.is_object() || !json.contains("inputs")) continue;
    if (json.contains("reported") && json["reported"].is_array()) {
      reported_.resize(steps_);
      for (const auto& item : json["reported"]) {
        // Older recordings list the texts only.
        if (item.is_string()) reported_[step - 1].push_back({"", item.get<std::string>()});
        if (item.is_object() && item.value("text", nlohmann::ordered_json()).is_string()) {
          const auto by = item.value("by", nlohmann::ordered_json());
          const auto pass = item.value("pass", nlohmann::ordered_json());
          reported_[step - 1].push_back({by.is_string() ? by.get<std::string>() : std::string(),
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
        column->values.resize(steps_);
        column->written.resize(steps_);
      }
      column->values[step - 1] = entry.value("value", nlohmann::ordered_json()).dump();
      column->written[step - 1] = entry.value("written", false) ? 1 : 0;
    }
  }
  class_.name = "arbiter.RecordedInputs";
  class_.kind = ClassKind::kInterface;
  class_.origin = "replay";
  class_.make_interface = [this] { return std::make_unique<Replayed>(*this); };
}

const std::vector<RecordedInputs::Report>& RecordedInputs::reported(std::uint64_t step) const {
  static const std::vector<Report> kNone;
  return step >= 1 && step <= reported_.size() ? reported_[step - 1] : kNone;
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

std::optional<RecordedRun> read_recorded_run(const std::string& path, Diagnostic& error) {
  const auto fail = [&](std::string message) {
    error = Diagnostic{{path, 0, 0}, Severity::kError, "bad-recording", std::move(message), {}};
    return std::nullopt;
  };
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail("cannot read the recording");
  mcap::Reader reader(
      std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
  RecordedRun run;
  bool config = false;
  mcap::Record record;
  while (reader.next(record)) {
    if (record.kind == mcap::Record::Kind::kMetadata) {
      if (record.name == "arbiter.config") {
        config = true;
        for (auto& [key, value] : record.metadata) {
          if (key.rfind("file:", 0) == 0) {
            run.info.files.emplace_back(key.substr(5), std::move(value));
          } else if (key == "version") {
            run.info.version = value;
          } else if (key == "plugins" && !value.empty()) {
            std::size_t start = 0;
            while (start <= value.size()) {
              const auto end = std::min(value.find('\n', start), value.size());
              run.info.plugins.push_back(value.substr(start, end - start));
              start = end + 1;
            }
          }
        }
      } else if (record.name == "arbiter.reload") {
        RecordedRun::Reload reload;
        for (auto& [key, value] : record.metadata) {
          if (key == "after_step") reload.after_step = std::strtoull(value.c_str(), nullptr, 10);
          if (key.rfind("file:", 0) == 0)
            reload.files.emplace_back(key.substr(5), std::move(value));
        }
        run.reloads.push_back(std::move(reload));
      } else if (record.name == "arbiter.gap") {
        for (const auto& [key, value] : record.metadata) {
          if (key == "dropped") run.dropped += std::strtoull(value.c_str(), nullptr, 10);
          if (key == "after_step" && !run.first_gap) {
            run.first_gap = std::strtoull(value.c_str(), nullptr, 10);
          }
        }
      }
    } else if (record.topic == "/arbiter/inputs") {
      // Checked here, before RecordedInputs copies its values out of a parsed tree.
      if (const auto deep = find_too_deep_json(record.data)) {
        return fail(fmt::format(
            "at byte {}: an inputs message nests deeper than {} levels (at byte {} of the "
            "message)",
            record.offset, ReadLimits().max_depth, *deep));
      }
      const auto key = record.data.find("\"step\": ");
      const auto step =
          key == std::string::npos ? 0 : std::strtoull(record.data.c_str() + key + 8, nullptr, 10);
      // The inputs are kept per step up to the last step: a step beyond those the recording
      // holds (or says it dropped) is not a recorded run's, and would size that for nothing.
      const std::uint64_t held = run.inputs.size() + run.dropped;
      if (step > held + 1) {
        return fail(fmt::format(
            "at byte {}: an inputs message for step {}, after the inputs of {} steps (and {} "
            "dropped); each step's inputs follow those of the step before it",
            record.offset, step, run.inputs.size(), run.dropped));
      }
      run.inputs.emplace_back(step, std::move(record.data));
    }
    record = mcap::Record();
  }
  if (!reader.error().empty()) return fail(reader.error());
  if (!config || run.info.files.empty()) {
    return fail(
        "the recording has no 'arbiter.config' metadata with the config's files; record "
        "one with 'arbiter run CONFIG --record RUN.mcap'");
  }
  return run;
}

}  // namespace arbiter

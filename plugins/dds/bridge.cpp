#include "bridge.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "arbiter/init_context.hpp"
#include "domain.hpp"
#include "messages.hpp"

namespace arbiter::dds {

/// QoS of one topic's reader or writer.
struct TopicQos {
  bool reliable = true;
  bool keep_all = false;
  std::int32_t depth = 1;  // for keep_last
  bool transient_local = false;
};

struct Bridge::Subscription {
  std::string name;   // the actuator
  std::string topic;  // the DDS topic name
  ValueKind kind = ValueKind::kDouble;
  Message message = Message::kFloat64;
  AnyOutput output;
  ValueBox staged;  // the newest sample taken, as an engine value
  dds_entity_t reader = 0;
  dds_listener_t* listener = nullptr;
  std::vector<SampleStorage> samples;  // what dds_take fills, reused every step
  std::vector<void*> buffers;
  std::vector<dds_sample_info_t> infos;
  // Set by Cyclone DDS's threads (listeners), read by the input pass.
  std::atomic<bool> pending{false};
  std::atomic<std::int32_t> publishers{0};
  std::int32_t reported_publishers = 0;
  std::string found_event;
  std::string lost_event;
};

struct Bridge::Publication {
  std::string name;  // the sensor
  std::string topic;
  ValueKind kind = ValueKind::kDouble;
  Message message = Message::kFloat64;
  std::uint32_t actuator = kUnbound;
  dds_entity_t writer = 0;
  dds_listener_t* listener = nullptr;
  SampleStorage sample{};
  std::atomic<std::int32_t> subscribers{0};
  bool failing = false;
  std::string failed_event;
};

namespace {

constexpr std::size_t kMaxBatch = 16;

void on_data_available(dds_entity_t /*reader*/, void* arg) {
  static_cast<Bridge::Subscription*>(arg)->pending.store(true, std::memory_order_release);
}

void on_subscription_matched(dds_entity_t /*reader*/,
                             const dds_subscription_matched_status_t status, void* arg) {
  static_cast<Bridge::Subscription*>(arg)->publishers.store(
      static_cast<std::int32_t>(status.current_count), std::memory_order_release);
}

void on_publication_matched(dds_entity_t /*writer*/, const dds_publication_matched_status_t status,
                            void* arg) {
  static_cast<Bridge::Publication*>(arg)->subscribers.store(
      static_cast<std::int32_t>(status.current_count), std::memory_order_release);
}

/// A ROS 2 topic name: tokens of letters, digits and '_' separated by single '/', none starting
/// with a digit; a leading '/' makes it absolute. Returns what is wrong, or an empty string.
std::string check_topic_name(const std::string& name) {
  if (name.empty() || name == "/") return "a topic name cannot be empty";
  std::size_t token_start = name[0] == '/' ? 1 : 0;
  for (std::size_t i = token_start; i <= name.size(); ++i) {
    if (i == name.size() || name[i] == '/') {
      if (i == token_start) {
        return i == name.size() ? "a topic name cannot end with '/'"
                                : "a topic name cannot contain '//'";
      }
      if (name[token_start] >= '0' && name[token_start] <= '9') {
        return fmt::format("'{}' starts with a digit", name.substr(token_start, i - token_start));
      }
      token_start = i + 1;
      continue;
    }
    const char c = name[i];
    const bool allowed =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!allowed) return fmt::format("'{}' is not allowed in a topic name", c);
  }
  return {};
}

/// What the config says about one topic.
struct Plan {
  std::string name;
  std::string topic;  // as the config writes it (ROS 2 style), before prefix and namespace
  SourceLocation location;
  SourceLocation topic_location;
  ValueKind kind = ValueKind::kDouble;
  Message message = Message::kFloat64;
  TopicQos qos;
  std::uint32_t actuator = kUnbound;
  bool subscribe = false;
};

/// Reads the bridge's params and reports their problems, counting the errors.
class ParamReader {
 public:
  explicit ParamReader(InitContext& ctx) : ctx_(ctx) {}

  void error(const SourceLocation& at, std::string message) {
    ++errors_;
    ctx_.error(at, std::move(message));
  }
  int errors() const { return errors_; }

  TopicQos bridge_qos() {
    TopicQos qos;
    qos.reliable = ctx_.param<std::string>("reliability") == "reliable";
    qos.keep_all = ctx_.param<std::string>("history") == "keep_all";
    qos.depth = static_cast<std::int32_t>(ctx_.param<std::int64_t>("depth"));
    qos.transient_local = ctx_.param<std::string>("durability") == "transient_local";
    return qos;
  }

  /// Applies one entry of `topics:` (a topic name, or a mapping of options) to `plan`.
  void apply(const Node& value, Plan& plan) {
    if (value.is_scalar() && !value.reads_as_null()) {
      set_topic(value, plan);
      return;
    }
    if (!value.is_mapping()) {
      error(value.location(),
            fmt::format("topics: '{}' must map to a topic name or to a mapping with "
                        "topic, message, reliability, history, depth, durability; found {}",
                        plan.name, value.describe()));
      return;
    }
    static const std::vector<std::string> kKeys = {"topic",   "message", "reliability",
                                                   "history", "depth",   "durability"};
    for (const auto& entry : value.entries()) {
      if (std::find(kKeys.begin(), kKeys.end(), entry.key) == kKeys.end()) {
        error(entry.key_location, fmt::format("unknown key '{}' for topic '{}'; {}", entry.key,
                                              plan.name, suggest(entry.key, kKeys, "allowed")));
        continue;
      }
      const Node& option = entry.value;
      if (entry.key == "topic") {
        set_topic(option, plan);
      } else if (entry.key == "message") {
        set_message(option, plan);
      } else if (entry.key == "reliability") {
        if (auto choice = choose(option, entry.key, {"reliable", "best_effort"})) {
          plan.qos.reliable = *choice == "reliable";
        }
      } else if (entry.key == "history") {
        if (auto choice = choose(option, entry.key, {"keep_last", "keep_all"})) {
          plan.qos.keep_all = *choice == "keep_all";
        }
      } else if (entry.key == "durability") {
        if (auto choice = choose(option, entry.key, {"volatile", "transient_local"})) {
          plan.qos.transient_local = *choice == "transient_local";
        }
      } else if (entry.key == "depth") {
        const auto depth = option.as_int();
        if (!depth || *depth < 1 || *depth > 10000) {
          error(option.location(), fmt::format("depth must be an integer in [1, 10000], "
                                               "found {}",
                                               option.describe()));
        } else {
          plan.qos.depth = static_cast<std::int32_t>(*depth);
        }
      }
    }
  }

  void check_topic(const std::string& topic, const SourceLocation& at, const char* what) {
    const std::string problem = check_topic_name(topic);
    if (!problem.empty()) {
      error(at, fmt::format("{} '{}' is not a valid ROS 2 topic name: {}", what, topic, problem));
    }
  }

 private:
  void set_topic(const Node& node, Plan& plan) {
    if (!node.is_scalar() || node.reads_as_null()) {
      error(node.location(),
            fmt::format("the topic of '{}' must be a name, found {}", plan.name, node.describe()));
      return;
    }
    plan.topic = node.text();
    plan.topic_location = node.location();
    check_topic(plan.topic, node.location(), "topic");
  }

  void set_message(const Node& node, Plan& plan) {
    const auto message = message_named(node.text());
    if (node.is_scalar() && message && carries(*message, plan.kind)) {
      plan.message = *message;
      return;
    }
    const auto allowed = messages_for(plan.kind);
    std::string list;
    for (const auto& name : allowed) list += (list.empty() ? "" : ", ") + name;
    error(node.location(), fmt::format("'{}' cannot travel as {}; its message can be: {}",
                                       plan.name, node.describe(), list));
  }

  std::optional<std::string> choose(const Node& node, const std::string& key,
                                    const std::vector<std::string>& allowed) {
    if (node.is_scalar() &&
        std::find(allowed.begin(), allowed.end(), node.text()) != allowed.end()) {
      return node.text();
    }
    error(node.location(), fmt::format("{} must be one of {}, found {}", key,
                                       fmt::join(allowed, ", "), node.describe()));
    return std::nullopt;
  }

  InitContext& ctx_;
  int errors_ = 0;
};

dds_qos_t* make_qos(const TopicQos& topic) {
  dds_qos_t* qos = dds_create_qos();
  // A writer never waits for room in its history: step() must not block. A full keep_all
  // history makes dds_write() fail at once instead (counted, and reported as an event).
  dds_qset_reliability(qos, topic.reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                       0);
  dds_qset_history(qos, topic.keep_all ? DDS_HISTORY_KEEP_ALL : DDS_HISTORY_KEEP_LAST,
                   topic.keep_all ? 1 : topic.depth);
  dds_qset_durability(
      qos, topic.transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  return qos;
}

/// The config's file, read, or Cyclone XML written inline (starting with '<').
std::optional<std::string> read_cyclone_config(const std::string& value, const SourceLocation& at,
                                               std::string& path, std::string& error) {
  if (!value.empty() && value.front() == '<') return value;
  namespace fs = std::filesystem;
  fs::path file(value);
  if (file.is_relative()) file = fs::path(at.file).parent_path() / file;
  path = file.lexically_normal().string();
  std::ifstream in(path, std::ios::binary);
  if (!in || fs::is_directory(path)) {
    error = fmt::format("cannot read the Cyclone DDS configuration '{}'", path);
    return std::nullopt;
  }
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string full_topic(const std::string& prefix, const std::string& ns, const std::string& name) {
  if (!name.empty() && name.front() == '/') return prefix + name.substr(1);
  return ns.empty() ? prefix + name : prefix + ns + "/" + name;
}

}  // namespace

Bridge::Bridge() = default;

Bridge::~Bridge() {
  // Deleting the participant deletes its readers and writers and waits for running listeners.
  if (participant_ > 0) dds_delete(participant_);
  for (auto& subscription : subscriptions_) {
    if (subscription->listener != nullptr) dds_delete_listener(subscription->listener);
    for (auto& sample : subscription->samples) {
      dds_sample_free(&sample, &descriptor(subscription->message), DDS_FREE_CONTENTS);
    }
  }
  for (auto& publication : publications_) {
    if (publication->listener != nullptr) dds_delete_listener(publication->listener);
  }
}

namespace {

/// The actuator a sensor reads, bound through an input of the sensor's C++ type; the output
/// pass reads it as that type again (read_sensor).
std::uint32_t sensor_actuator(InitContext& ctx, const std::string& sensor, ValueKind kind,
                              const SourceLocation& where) {
  switch (kind) {
    case ValueKind::kBool:
      return ctx.sensor_input<bool>(sensor, where).actuator;
    case ValueKind::kInt:
      return ctx.sensor_input<std::int64_t>(sensor, where).actuator;
    case ValueKind::kDouble:
      return ctx.sensor_input<double>(sensor, where).actuator;
    case ValueKind::kVec2:
      return ctx.sensor_input<Vec2>(sensor, where).actuator;
    case ValueKind::kVec3:
      return ctx.sensor_input<Vec3>(sensor, where).actuator;
    case ValueKind::kString:
      return ctx.sensor_input<std::string>(sensor, where).actuator;
  }
  return kUnbound;
}

/// A plan for each actuator (subscribed) and sensor (published) of the layer, with the options
/// `topics:` gives them.
std::vector<Plan> plan_topics(InitContext& ctx, ParamReader& params,
                              const std::vector<LayerItem>& actuators,
                              const std::vector<LayerItem>& sensors) {
  const TopicQos qos = params.bridge_qos();
  std::vector<Plan> plans;
  const auto add = [&](const LayerItem& item, bool subscribe) {
    const auto kind = kind_of(item.type->name);
    if (!kind) {
      params.error(item.location, fmt::format("{} '{}' has type '{}', which the DDS bridge does "
                                              "not carry; it carries {}",
                                              subscribe ? "actuator" : "sensor", item.name,
                                              item.type->name, carried_types()));
      return;
    }
    Plan plan;
    plan.name = item.name;
    plan.topic = item.name;
    plan.location = item.location;
    plan.topic_location = item.location;
    plan.kind = *kind;
    plan.message = default_message(*kind);
    plan.qos = qos;
    plan.subscribe = subscribe;
    if (!subscribe) plan.actuator = sensor_actuator(ctx, item.name, *kind, item.location);
    plans.push_back(std::move(plan));
  };
  for (const auto& item : actuators) add(item, true);
  for (const auto& item : sensors) add(item, false);

  const Node topics = ctx.param<Node>("topics");
  if (!topics.reads_as_null() && !topics.is_mapping()) {
    params.error(topics.location(),
                 fmt::format("'topics' must map actuators and sensors of this layer to topic "
                             "names, found {}",
                             topics.describe()));
    return plans;
  }
  std::vector<std::string> known;
  for (const auto& item : actuators) known.push_back(item.name);
  for (const auto& item : sensors) known.push_back(item.name);
  for (const auto& entry : topics.entries()) {
    const auto plan = std::find_if(plans.begin(), plans.end(), [&](const Plan& candidate) {
      return candidate.name == entry.key;
    });
    if (plan != plans.end()) {
      params.apply(entry.value, *plan);
    } else if (std::find(known.begin(), known.end(), entry.key) == known.end()) {
      params.error(entry.key_location,
                   fmt::format("topics: '{}' is neither an actuator nor a sensor of layer '{}'; {}",
                               entry.key, ctx.name(),
                               known.empty() ? std::string("the layer has none")
                                             : suggest(entry.key, known)));
    }
  }
  return plans;
}

std::unique_ptr<Bridge::Subscription> subscribe(InitContext& ctx, dds_entity_t participant,
                                                dds_entity_t topic, const std::string& topic_name,
                                                const Plan& plan) {
  auto subscription = std::make_unique<Bridge::Subscription>();
  Bridge::Subscription& in = *subscription;
  in.name = plan.name;
  in.topic = topic_name;
  in.kind = plan.kind;
  in.message = plan.message;
  in.output = ctx.output_to_actuator(plan.name, plan.location);
  if (in.output.type != nullptr) in.staged = ValueBox(*in.output.type);
  const std::size_t batch =
      plan.qos.keep_all
          ? kMaxBatch
          : std::min<std::size_t>(kMaxBatch, static_cast<std::size_t>(plan.qos.depth));
  in.samples.resize(batch, SampleStorage{});
  for (auto& sample : in.samples) in.buffers.push_back(&sample);
  in.infos.resize(batch);
  in.found_event = fmt::format("{}: publisher found on {}", in.name, topic_name);
  in.lost_event =
      fmt::format("{}: publisher lost on {}; the value is held, unwritten", in.name, topic_name);
  in.listener = dds_create_listener(&in);
  dds_lset_data_available(in.listener, on_data_available);
  dds_lset_subscription_matched(in.listener, on_subscription_matched);
  dds_qos_t* qos = make_qos(plan.qos);
  in.reader = dds_create_reader(participant, topic, qos, in.listener);
  dds_delete_qos(qos);
  if (in.reader < 0) {
    ctx.error(plan.topic_location, fmt::format("cannot subscribe to DDS topic '{}': {}", topic_name,
                                               retcode_name(in.reader)));
  }
  return subscription;
}

std::unique_ptr<Bridge::Publication> publish(InitContext& ctx, dds_entity_t participant,
                                             dds_entity_t topic, const std::string& topic_name,
                                             const Plan& plan) {
  auto publication = std::make_unique<Bridge::Publication>();
  Bridge::Publication& out = *publication;
  out.name = plan.name;
  out.topic = topic_name;
  out.kind = plan.kind;
  out.message = plan.message;
  out.actuator = plan.actuator;
  out.failed_event =
      fmt::format("{}: publishing on {} failed; the history is full", out.name, topic_name);
  out.listener = dds_create_listener(&out);
  dds_lset_publication_matched(out.listener, on_publication_matched);
  dds_qos_t* qos = make_qos(plan.qos);
  out.writer = dds_create_writer(participant, topic, qos, out.listener);
  dds_delete_qos(qos);
  if (out.writer < 0) {
    ctx.error(plan.topic_location, fmt::format("cannot publish DDS topic '{}': {}", topic_name,
                                               retcode_name(out.writer)));
  }
  return publication;
}

}  // namespace

void Bridge::init(InitContext& ctx) {
  ParamReader params(ctx);
  publish_unwritten_ = ctx.param<std::string>("publish") == "every_step";
  const std::string prefix = ctx.param<std::string>("topic_prefix");
  std::string ns = ctx.param<std::string>("namespace");
  if (!ns.empty()) {
    params.check_topic(ns, ctx.param_location("namespace"), "namespace");
    ns.erase(0, ns.find_first_not_of('/'));
  }

  const std::vector<LayerItem> actuators = ctx.layer_actuators();
  const std::vector<LayerItem> sensors = ctx.layer_sensors();
  if (actuators.empty() && sensors.empty()) {
    ctx.warning(ctx.location(),
                fmt::format("layer '{}' has no actuators and no sensors: the DDS bridge "
                            "subscribes to a topic for each actuator and publishes each sensor",
                            ctx.name()));
  }
  const std::vector<Plan> plans = plan_topics(ctx, params, actuators, sensors);
  std::map<std::string, const Plan*> published;
  for (const auto& plan : plans) {
    if (plan.subscribe) continue;
    const std::string topic = full_topic(prefix, ns, plan.topic);
    const auto [first, fresh] = published.emplace(topic, &plan);
    if (!fresh) {
      params.error(plan.topic_location,
                   fmt::format("sensors '{}' and '{}' are both published on topic '{}'; a topic "
                               "carries one value",
                               first->second->name, plan.name, topic));
    }
  }

  std::string config_path;
  std::string config;
  if (const auto value = ctx.param<std::string>("cyclone_config"); !value.empty()) {
    std::string problem;
    const auto text =
        read_cyclone_config(value, ctx.param_location("cyclone_config"), config_path, problem);
    if (text) {
      config = *text;
    } else {
      params.error(ctx.param_location("cyclone_config"), problem);
    }
  }
  // Nothing joins the network while the config has an error.
  if (params.errors() > 0) return;

  const auto domain_id = static_cast<std::uint32_t>(ctx.param<std::int64_t>("domain_id"));
  std::string problem;
  domain_ = Domain::open(domain_id, config,
                         config_path.empty() ? (config.empty() ? "" : "inline XML")
                                             : fmt::format("the configuration '{}'", config_path),
                         problem);
  if (!domain_) {
    ctx.error(ctx.param_location(config.empty() ? "domain_id" : "cyclone_config"),
              fmt::format("cannot open DDS domain {}: {}", domain_id, problem));
    return;
  }
  participant_ = dds_create_participant(domain_id, nullptr, nullptr);
  if (participant_ < 0) {
    ctx.error(ctx.param_location("domain_id"),
              fmt::format("cannot join DDS domain {}: {}", domain_id, retcode_name(participant_)));
    participant_ = 0;
    return;
  }
  for (const auto& plan : plans) {
    const std::string topic_name = full_topic(prefix, ns, plan.topic);
    const dds_topic_descriptor_t& type = descriptor(plan.message);
    const dds_entity_t topic =
        dds_create_topic(participant_, &type, topic_name.c_str(), nullptr, nullptr);
    if (topic < 0) {
      ctx.error(plan.topic_location, fmt::format("cannot create DDS topic '{}' of type {}: {}",
                                                 topic_name, type.m_typename, retcode_name(topic)));
    } else if (plan.subscribe) {
      subscriptions_.push_back(subscribe(ctx, participant_, topic, topic_name, plan));
    } else {
      publications_.push_back(publish(ctx, participant_, topic, topic_name, plan));
    }
  }
}

void Bridge::input(ExecuteContext& ctx) {
  for (auto& owned : subscriptions_) {
    Subscription& in = *owned;
    const std::int32_t publishers = in.publishers.load(std::memory_order_acquire);
    if ((publishers > 0) != (in.reported_publishers > 0)) {
      ctx.report(publishers > 0 ? in.found_event.c_str() : in.lost_event.c_str());
    }
    in.reported_publishers = publishers;
    if (!in.pending.exchange(false, std::memory_order_acq_rel)) continue;

    // Samples come oldest first; only the newest valid one becomes the actuator's value.
    const auto batch = static_cast<std::uint32_t>(in.buffers.size());
    bool fresh = false;
    for (;;) {
      const dds_return_t taken =
          dds_take(in.reader, in.buffers.data(), in.infos.data(), batch, batch);
      if (taken <= 0) break;
      for (dds_return_t i = taken; i-- > 0;) {
        if (!in.infos[i].valid_data) continue;
        from_sample(in.buffers[i], in.kind, in.staged.data());
        fresh = true;
        break;
      }
      for (dds_return_t i = 0; i < taken; ++i) stats_.samples_taken += in.infos[i].valid_data;
      if (static_cast<std::uint32_t>(taken) < batch) break;
    }
    if (fresh) {
      ctx.write(in.output, in.staged);
      ++stats_.values_written;
    }
  }
}

namespace {

/// The value and written flag of the actuator a sensor reads, as the bridge's type knows it.
template <typename T>
const void* read_sensor(const StepContext& ctx, std::uint32_t actuator, bool& written) {
  const Input<T> input{actuator};
  written = ctx.written(input);
  return &ctx.read(input);
}

}  // namespace

void Bridge::output(const StepContext& ctx) {
  for (auto& owned : publications_) {
    Publication& out = *owned;
    bool written = false;
    const void* value = nullptr;
    switch (out.kind) {
      case ValueKind::kBool:
        value = read_sensor<bool>(ctx, out.actuator, written);
        break;
      case ValueKind::kInt:
        value = read_sensor<std::int64_t>(ctx, out.actuator, written);
        break;
      case ValueKind::kDouble:
        value = read_sensor<double>(ctx, out.actuator, written);
        break;
      case ValueKind::kVec2:
        value = read_sensor<Vec2>(ctx, out.actuator, written);
        break;
      case ValueKind::kVec3:
        value = read_sensor<Vec3>(ctx, out.actuator, written);
        break;
      case ValueKind::kString:
        value = read_sensor<std::string>(ctx, out.actuator, written);
        break;
    }
    if (!written && !publish_unwritten_) continue;
    to_sample(out.kind, value, &out.sample);
    if (dds_write(out.writer, &out.sample) == DDS_RETCODE_OK) {
      ++stats_.published;
      out.failing = false;
    } else {
      ++stats_.publish_failures;
      if (!out.failing) ctx.report(out.failed_event.c_str());
      out.failing = true;
    }
  }
}

std::string Bridge::topic_of(const std::string& name) const {
  for (const auto& in : subscriptions_) {
    if (in->name == name) return in->topic;
  }
  for (const auto& out : publications_) {
    if (out->name == name) return out->topic;
  }
  return {};
}

namespace {

template <typename Done>
bool poll_until(std::chrono::milliseconds timeout, Done done) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

}  // namespace

bool Bridge::wait_for_peers(std::chrono::milliseconds timeout) const {
  return poll_until(timeout, [&] {
    for (const auto& in : subscriptions_) {
      if (in->publishers.load(std::memory_order_acquire) == 0) return false;
    }
    for (const auto& out : publications_) {
      if (out->subscribers.load(std::memory_order_acquire) == 0) return false;
    }
    return true;
  });
}

bool Bridge::wait_for_data(std::chrono::milliseconds timeout) const {
  return poll_until(timeout, [&] {
    for (const auto& in : subscriptions_) {
      if (!in->pending.load(std::memory_order_acquire)) return false;
    }
    return true;
  });
}

void register_bridge(Registry& registry) {
  auto& info =
      registry.add_interface<Bridge>("dds.Bridge")
          .describe(
              "Connects the behaviour system to DDS topics (Eclipse Cyclone DDS), named and typed "
              "as ROS 2 names and types them. Subscribes to a topic for each actuator of its "
              "layer: a value received between two steps is written in the next input pass, and "
              "an actuator whose topic delivered nothing keeps its value, unwritten. Publishes "
              "each sensor of its layer in the output pass, without waiting. Carries bool, int, "
              "double, vec2, vec3 and string values. Reports 'NAME: publisher found' and "
              "'NAME: publisher lost' events. See docs/dds.md.");
  info.param("domain_id", ParamKind::kInt)
      .fallback(std::int64_t{0})
      .range(0.0, 232.0)
      .describe("the DDS domain (ROS_DOMAIN_ID for ROS 2 nodes)");
  info.param("cyclone_config", ParamKind::kString)
      .fallback(std::string())
      .describe(
          "a Cyclone DDS XML configuration file, relative to this config file (or XML text "
          "starting with '<'); empty: Cyclone's defaults, or the file CYCLONEDDS_URI names");
  info.param("reliability", ParamKind::kString)
      .fallback(std::string("reliable"))
      .one_of({"reliable", "best_effort"})
      .describe("reliability QoS of every reader and writer (per topic: 'topics')");
  info.param("history", ParamKind::kString)
      .fallback(std::string("keep_last"))
      .one_of({"keep_last", "keep_all"})
      .describe("history QoS of every reader and writer (per topic: 'topics')");
  info.param("depth", ParamKind::kInt)
      .fallback(std::int64_t{1})
      .range(1.0, 10000.0)
      .describe("the history depth for keep_last: how many samples a reader keeps between steps");
  info.param("durability", ParamKind::kString)
      .fallback(std::string("volatile"))
      .one_of({"volatile", "transient_local"})
      .describe(
          "durability QoS: transient_local lets a subscriber that joins late get the last "
          "value");
  info.param("topic_prefix", ParamKind::kString)
      .fallback(std::string("rt/"))
      .describe("prepended to every topic name: 'rt/' is ROS 2's prefix for topics");
  info.param("namespace", ParamKind::kString)
      .fallback(std::string())
      .describe("a ROS 2 namespace for topic names that do not start with '/'");
  info.param("topics", ParamKind::kAny)
      .fallback(Node())
      .describe(
          "per actuator or sensor of the layer: its topic name (default: its own name), or "
          "{topic, message, reliability, history, depth, durability}");
  info.param("publish", ParamKind::kString)
      .fallback(std::string("written"))
      .one_of({"written", "every_step"})
      .describe(
          "written: publish a sensor only in steps in which its actuator was written; "
          "every_step: publish every sensor every step");
}

}  // namespace arbiter::dds

#include "bridge.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "arbiter/fields.hpp"
#include "arbiter/init_context.hpp"
#include "domain.hpp"
#include "messages.hpp"

namespace arbiter::dds {

/// QoS of one topic's reader or writer; the defaults are ROS 2's default profile.
struct TopicQos {
  /// Unset: the DDS implementation's default for each side (Cyclone DDS: reliable writers,
  /// best-effort readers), as ROS 2's system_default profile leaves it.
  std::optional<bool> reliable = true;
  bool keep_all = false;
  std::int32_t depth = 10;  // for keep_last
  bool transient_local = false;
};

/// What a subscription and a publication share: the value and topic they carry, their listener,
/// and a peer's QoS that cannot match theirs.
struct Endpoint {
  std::string name;   // the actuator (subscribed) or sensor (published)
  std::string topic;  // the DDS topic name
  ValueKind kind = ValueKind::kDouble;
  Message message = Message::kFloat64;
  dds_listener_t* listener = nullptr;
  // Set by a listener when a peer's QoS cannot match this reader's or writer's; reported once.
  std::atomic<std::int32_t> incompatible_policy{0};
  bool incompatible_reported = false;
  std::vector<std::string> incompatible_events;  // by QoS policy id
};

struct Bridge::Subscription : Endpoint {
  AnyOutput output;
  ValueBox staged;  // the newest sample taken, as an engine value
  dds_entity_t reader = 0;
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

struct Bridge::Publication : Endpoint {
  std::uint32_t actuator = kUnbound;
  dds_entity_t writer = 0;
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

void on_requested_incompatible_qos(dds_entity_t /*reader*/,
                                   const dds_requested_incompatible_qos_status_t status,
                                   void* arg) {
  static_cast<Bridge::Subscription*>(arg)->incompatible_policy.store(
      static_cast<std::int32_t>(status.last_policy_id), std::memory_order_release);
}

void on_offered_incompatible_qos(dds_entity_t /*writer*/,
                                 const dds_offered_incompatible_qos_status_t status, void* arg) {
  static_cast<Bridge::Publication*>(arg)->incompatible_policy.store(
      static_cast<std::int32_t>(status.last_policy_id), std::memory_order_release);
}

/// ROS 2's QoS profiles by name (rmw/qos_profiles.h).
std::optional<TopicQos> qos_profile(const std::string& name) {
  TopicQos qos;
  if (name == "default") return qos;
  if (name == "sensor_data") {
    qos.reliable = false;
    qos.depth = 5;
    return qos;
  }
  if (name == "system_default") {
    qos.reliable.reset();
    qos.depth = 1;
    return qos;
  }
  return std::nullopt;
}

const std::vector<std::string> kQosProfiles = {"default", "sensor_data", "system_default"};

/// Whether the config wrote the param bound to `member`: a default is located at the instance.
template <typename M>
bool param_written(InitContext& ctx, M BridgeParams::*member) {
  const SourceLocation at = ctx.param_location(member);
  const SourceLocation& self = ctx.location();
  return at.file != self.file || at.line != self.line || at.column != self.column;
}

/// The warning a reader (`subscriber`) or writer reports when a peer's QoS policy `policy`
/// cannot match its own, saying what to change; an entry for every policy id.
std::vector<std::string> incompatible_qos_events(const std::string& name, const std::string& topic,
                                                 const TopicQos& qos, bool subscriber) {
  std::vector<std::string> events(DDS_DATA_REPRESENTATION_QOS_POLICY_ID + 1);
  const char* const peer = subscriber ? "a publisher" : "a subscriber";
  const char* const self = subscriber ? "this subscription" : "this publication";
  const char* const outcome =
      subscriber ? "nothing it publishes arrives" : "it receives nothing from this bridge";
  for (std::size_t id = 0; id < events.size(); ++id) {
    std::string detail;
    if (id == DDS_RELIABILITY_QOS_POLICY_ID) {
      detail = subscriber ? fmt::format(
                                "{} offers best_effort reliability, {} requests reliable; {}. "
                                "Set 'reliability: best_effort' (or 'qos: sensor_data') for "
                                "'{}' under topics:, or make the publisher reliable",
                                peer, self, outcome, name)
                          : fmt::format(
                                "{} requests reliable reliability, {} offers best_effort; {}. "
                                "Set 'reliability: reliable' (or 'qos: default') for '{}' "
                                "under topics:, or make the subscriber best-effort",
                                peer, self, outcome, name);
    } else if (id == DDS_DURABILITY_QOS_POLICY_ID) {
      detail = subscriber ? fmt::format(
                                "{} offers volatile durability, {} requests {}; {}. Set "
                                "'durability: volatile' for '{}' under topics:, or make the "
                                "publisher transient_local",
                                peer, self, qos.transient_local ? "transient_local" : "more",
                                outcome, name)
                          : fmt::format(
                                "{} requests a durability {} does not offer ({}); {}. Set "
                                "'durability: transient_local' for '{}' under topics:, or make "
                                "the subscriber volatile",
                                peer, self, qos.transient_local ? "transient_local" : "volatile",
                                outcome, name);
    } else {
      detail = fmt::format(
          "{}'s QoS policy {} cannot match {}'s; {}. Make the two sides agree "
          "on it",
          peer, id, self, outcome);
    }
    events[id] = fmt::format("{}: warning: incompatible QoS on {}: {}", name, topic, detail);
  }
  return events;
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

/// What the config binds one actuator or sensor to: its topic, message and QoS.
struct TopicBinding {
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

/// The `qos` profile, then the policies the config writes beside it.
TopicQos bridge_qos(InitContext& ctx, const BridgeParams& params) {
  TopicQos qos = qos_profile(params.qos).value_or(TopicQos{});
  if (param_written(ctx, &BridgeParams::reliability)) {
    qos.reliable = params.reliability == "reliable";
  }
  if (param_written(ctx, &BridgeParams::history)) qos.keep_all = params.history == "keep_all";
  if (param_written(ctx, &BridgeParams::depth)) qos.depth = static_cast<std::int32_t>(params.depth);
  if (param_written(ctx, &BridgeParams::durability)) {
    qos.transient_local = params.durability == "transient_local";
  }
  return qos;
}

void check_topic(InitContext& ctx, const std::string& topic, const SourceLocation& at,
                 const char* what) {
  const std::string problem = check_topic_name(topic);
  if (!problem.empty()) {
    ctx.error(at, fmt::format("{} '{}' is not a valid ROS 2 topic name: {}", what, topic, problem));
  }
}

void set_topic(InitContext& ctx, const Node& node, TopicBinding& binding) {
  if (!node.is_scalar() || node.reads_as_null()) {
    ctx.error(node.location(), fmt::format("the topic of '{}' must be a name, found {}",
                                           binding.name, node.describe()));
    return;
  }
  binding.topic = node.text();
  binding.topic_location = node.location();
  check_topic(ctx, binding.topic, node.location(), "topic");
}

void set_message(InitContext& ctx, const Node& node, TopicBinding& binding) {
  const auto message = message_named(node.text());
  if (node.is_scalar() && message && carries(*message, binding.kind)) {
    binding.message = *message;
    return;
  }
  const auto allowed = messages_for(binding.kind);
  std::string list;
  for (const auto& name : allowed) list += (list.empty() ? "" : ", ") + name;
  ctx.error(node.location(), fmt::format("'{}' cannot travel as {}; its message can be: {}",
                                         binding.name, node.describe(), list));
}

std::optional<std::string> choose(InitContext& ctx, const Node& node, const std::string& key,
                                  const std::vector<std::string>& allowed) {
  if (node.is_scalar() && std::find(allowed.begin(), allowed.end(), node.text()) != allowed.end()) {
    return node.text();
  }
  ctx.error(node.location(), fmt::format("{} must be one of {}, found {}", key,
                                         fmt::join(allowed, ", "), node.describe()));
  return std::nullopt;
}

/// Applies one entry of `topics:` (a topic name, or a mapping of options) to `binding`. The
/// mapping is read as the model reads its own (Fields): a key that is none of the options is an
/// `unknown-key` error with a suggestion, anything but a mapping a `wrong-type` one.
void read_topic_options(InitContext& ctx, const Node& value, TopicBinding& binding) {
  if (value.is_scalar() && !value.reads_as_null()) {
    set_topic(ctx, value, binding);
    return;
  }
  static const std::vector<std::string_view> kKeys = {
      "topic", "message", "qos", "reliability", "history", "depth", "durability"};
  const Fields fields(value, fmt::format("topic '{}'", binding.name), kKeys, ctx.diagnostics(),
                      "a topic name or a mapping with topic, message, qos, reliability, history, "
                      "depth, durability");
  if (!fields.ok()) return;
  // A profile replaces the bridge's QoS for this topic, wherever the mapping writes it; the
  // policies written beside it then change it.
  if (const Node* profile = fields.optional("qos")) {
    if (auto choice = choose(ctx, *profile, "qos", kQosProfiles)) {
      binding.qos = *qos_profile(*choice);
    }
  }
  for (const auto& entry : value.entries()) {
    const Node& option = entry.value;
    if (entry.key == "topic") {
      set_topic(ctx, option, binding);
    } else if (entry.key == "message") {
      set_message(ctx, option, binding);
    } else if (entry.key == "reliability") {
      if (auto choice = choose(ctx, option, entry.key, {"reliable", "best_effort"})) {
        binding.qos.reliable = *choice == "reliable";
      }
    } else if (entry.key == "history") {
      if (auto choice = choose(ctx, option, entry.key, {"keep_last", "keep_all"})) {
        binding.qos.keep_all = *choice == "keep_all";
      }
    } else if (entry.key == "durability") {
      if (auto choice = choose(ctx, option, entry.key, {"volatile", "transient_local"})) {
        binding.qos.transient_local = *choice == "transient_local";
      }
    } else if (entry.key == "depth") {
      const auto depth = option.as_int();
      if (!depth || *depth < 1 || *depth > 10000) {
        ctx.error(option.location(), fmt::format("depth must be an integer in [1, 10000], found {}",
                                                 option.describe()));
      } else {
        binding.qos.depth = static_cast<std::int32_t>(*depth);
      }
    }
  }
}

dds_qos_t* make_qos(const TopicQos& topic, bool writer) {
  dds_qos_t* qos = dds_create_qos();
  // A writer never waits for room in its history: step() must not block. A full keep_all
  // history makes dds_write() fail at once instead (counted, and reported as an event).
  const bool reliable = topic.reliable.value_or(writer);
  dds_qset_reliability(qos, reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT, 0);
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

/// `domain_id`, or else ROS_DOMAIN_ID as a ROS 2 node reads it, or else 0.
std::optional<std::int64_t> domain_id_of(InitContext& ctx, const BridgeParams& params) {
  if (param_written(ctx, &BridgeParams::domain_id)) return params.domain_id;
  const char* variable = std::getenv("ROS_DOMAIN_ID");
  if (variable == nullptr || *variable == '\0') return 0;
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(variable, &end, 10);
  if (errno != 0 || *end != '\0' || value < 0 || value > 232) {
    ctx.error(ctx.location(),
              fmt::format("the environment variable ROS_DOMAIN_ID is '{}', which is not a DDS "
                          "domain id (an integer in [0, 232]); set it to one, or set "
                          "'domain_id' in the bridge's params",
                          variable));
    return std::nullopt;
  }
  return value;
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

/// A binding for each actuator (subscribed) and sensor (published) of the layer, with the options
/// `topics:` gives them.
std::vector<TopicBinding> bind_topics(InitContext& ctx, const BridgeParams& params,
                                      const std::vector<LayerItem>& actuators,
                                      const std::vector<LayerItem>& sensors) {
  const TopicQos qos = bridge_qos(ctx, params);
  std::vector<TopicBinding> bindings;
  const auto add = [&](const LayerItem& item, bool subscribe) {
    const auto kind = kind_of(item.type->name);
    if (!kind) {
      ctx.error(item.location, fmt::format("{} '{}' has type '{}', which the DDS bridge does "
                                           "not carry; it carries {}",
                                           subscribe ? "actuator" : "sensor", item.name,
                                           item.type->name, carried_types()));
      return;
    }
    TopicBinding binding;
    binding.name = item.name;
    binding.topic = item.name;
    binding.location = item.location;
    binding.topic_location = item.location;
    binding.kind = *kind;
    binding.message = default_message(*kind);
    binding.qos = qos;
    binding.subscribe = subscribe;
    if (!subscribe) binding.actuator = sensor_actuator(ctx, item.name, *kind, item.location);
    bindings.push_back(std::move(binding));
  };
  for (const auto& item : actuators) add(item, true);
  for (const auto& item : sensors) add(item, false);

  const Node& topics = params.topics;
  if (!topics.reads_as_null() && !topics.is_mapping()) {
    ctx.error(topics.location(),
              fmt::format("'topics' must map actuators and sensors of this layer to topic "
                          "names, found {}",
                          topics.describe()));
    return bindings;
  }
  std::vector<std::string> known;
  for (const auto& item : actuators) known.push_back(item.name);
  for (const auto& item : sensors) known.push_back(item.name);
  for (const auto& entry : topics.entries()) {
    const auto binding =
        std::find_if(bindings.begin(), bindings.end(),
                     [&](const TopicBinding& candidate) { return candidate.name == entry.key; });
    if (binding != bindings.end()) {
      read_topic_options(ctx, entry.value, *binding);
    } else if (std::find(known.begin(), known.end(), entry.key) == known.end()) {
      ctx.error(entry.key_location,
                fmt::format(
                    "topics: '{}' is neither an actuator nor a sensor of layer '{}'; {}", entry.key,
                    ctx.name(),
                    known.empty() ? std::string("the layer has none") : suggest(entry.key, known)));
    }
  }
  return bindings;
}

/// Names `endpoint` after the binding it carries on `topic_name`, with the QoS warnings it may
/// report.
void name_endpoint(Endpoint& endpoint, const std::string& topic_name, const TopicBinding& binding,
                   bool subscriber) {
  endpoint.name = binding.name;
  endpoint.topic = topic_name;
  endpoint.kind = binding.kind;
  endpoint.message = binding.message;
  endpoint.incompatible_events =
      incompatible_qos_events(binding.name, topic_name, binding.qos, subscriber);
}

/// Creates the reader (subscriber) or writer of `endpoint`, whose listener is set up, with the
/// binding's QoS; reports at the binding's topic when DDS refuses.
dds_entity_t open_endpoint(InitContext& ctx, dds_entity_t participant, dds_entity_t topic,
                           const TopicBinding& binding, const Endpoint& endpoint, bool subscriber) {
  dds_qos_t* qos = make_qos(binding.qos, !subscriber);
  const dds_entity_t entity = subscriber
                                  ? dds_create_reader(participant, topic, qos, endpoint.listener)
                                  : dds_create_writer(participant, topic, qos, endpoint.listener);
  dds_delete_qos(qos);
  if (entity < 0) {
    ctx.error(binding.topic_location,
              fmt::format("cannot {} DDS topic '{}': {}", subscriber ? "subscribe to" : "publish",
                          endpoint.topic, retcode_name(entity)));
  }
  return entity;
}

std::unique_ptr<Bridge::Subscription> subscribe(InitContext& ctx, dds_entity_t participant,
                                                dds_entity_t topic, const std::string& topic_name,
                                                const TopicBinding& binding) {
  auto subscription = std::make_unique<Bridge::Subscription>();
  Bridge::Subscription& in = *subscription;
  name_endpoint(in, topic_name, binding, true);
  in.output = ctx.output_to_actuator(binding.name, binding.location);
  if (in.output.type != nullptr) in.staged = ValueBox(*in.output.type);
  const std::size_t batch =
      binding.qos.keep_all
          ? kMaxBatch
          : std::min<std::size_t>(kMaxBatch, static_cast<std::size_t>(binding.qos.depth));
  in.samples.resize(batch, SampleStorage{});
  for (auto& sample : in.samples) in.buffers.push_back(&sample);
  in.infos.resize(batch);
  in.found_event = fmt::format("{}: publisher found on {}", in.name, topic_name);
  in.lost_event =
      fmt::format("{}: publisher lost on {}; the value is held, unwritten", in.name, topic_name);
  in.listener = dds_create_listener(&in);
  dds_lset_data_available(in.listener, on_data_available);
  dds_lset_subscription_matched(in.listener, on_subscription_matched);
  dds_lset_requested_incompatible_qos(in.listener, on_requested_incompatible_qos);
  in.reader = open_endpoint(ctx, participant, topic, binding, in, true);
  return subscription;
}

std::unique_ptr<Bridge::Publication> publish(InitContext& ctx, dds_entity_t participant,
                                             dds_entity_t topic, const std::string& topic_name,
                                             const TopicBinding& binding) {
  auto publication = std::make_unique<Bridge::Publication>();
  Bridge::Publication& out = *publication;
  name_endpoint(out, topic_name, binding, false);
  out.actuator = binding.actuator;
  out.failed_event =
      fmt::format("{}: publishing on {} failed; the history is full", out.name, topic_name);
  out.listener = dds_create_listener(&out);
  dds_lset_publication_matched(out.listener, on_publication_matched);
  dds_lset_offered_incompatible_qos(out.listener, on_offered_incompatible_qos);
  out.writer = open_endpoint(ctx, participant, topic, binding, out, false);
  return publication;
}

}  // namespace

void Bridge::init(InitContext& ctx) {
  // Nothing joins the network while the config has an error: counted from here.
  const std::size_t errors_before = ctx.diagnostics().error_count();
  publish_unwritten_ = publish_when == "every_step";
  const std::string& prefix = topic_prefix;
  std::string ns = BridgeParams::ns;
  if (!ns.empty()) {
    check_topic(ctx, ns, ctx.param_location(&BridgeParams::ns), "namespace");
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
  const std::vector<TopicBinding> bindings = bind_topics(ctx, *this, actuators, sensors);
  std::map<std::string, const TopicBinding*> published;
  for (const auto& binding : bindings) {
    if (binding.subscribe) continue;
    const std::string topic = full_topic(prefix, ns, binding.topic);
    const auto [first, fresh] = published.emplace(topic, &binding);
    if (!fresh) {
      ctx.error(binding.topic_location,
                fmt::format("sensors '{}' and '{}' are both published on topic '{}'; a topic "
                            "carries one value",
                            first->second->name, binding.name, topic));
    }
  }

  std::string config_path;
  std::string config;
  if (!cyclone_config.empty()) {
    std::string problem;
    const SourceLocation at = ctx.param_location(&BridgeParams::cyclone_config);
    const auto text = read_cyclone_config(cyclone_config, at, config_path, problem);
    if (text) {
      config = *text;
    } else {
      ctx.error(at, problem);
    }
  }
  const auto domain = domain_id_of(ctx, *this);
  if (ctx.diagnostics().error_count() > errors_before || !domain) return;

  const auto domain_id = static_cast<std::uint32_t>(*domain);
  std::string problem;
  domain_ = Domain::open(domain_id, config,
                         config_path.empty() ? (config.empty() ? "" : "inline XML")
                                             : fmt::format("the configuration '{}'", config_path),
                         problem);
  if (!domain_) {
    ctx.error(config.empty() ? ctx.param_location(&BridgeParams::domain_id)
                             : ctx.param_location(&BridgeParams::cyclone_config),
              fmt::format("cannot open DDS domain {}: {}", domain_id, problem));
    return;
  }
  participant_ = dds_create_participant(domain_id, nullptr, nullptr);
  if (participant_ < 0) {
    ctx.error(ctx.param_location(&BridgeParams::domain_id),
              fmt::format("cannot join DDS domain {}: {}", domain_id, retcode_name(participant_)));
    participant_ = 0;
    return;
  }
  for (const auto& binding : bindings) {
    const std::string topic_name = full_topic(prefix, ns, binding.topic);
    const dds_topic_descriptor_t& type = descriptor(binding.message);
    const dds_entity_t topic =
        dds_create_topic(participant_, &type, topic_name.c_str(), nullptr, nullptr);
    if (topic < 0) {
      ctx.error(binding.topic_location,
                fmt::format("cannot create DDS topic '{}' of type {}: {}", topic_name,
                            type.m_typename, retcode_name(topic)));
    } else if (binding.subscribe) {
      subscriptions_.push_back(subscribe(ctx, participant_, topic, topic_name, binding));
    } else {
      publications_.push_back(publish(ctx, participant_, topic, topic_name, binding));
    }
  }
}

namespace {

/// Reports, once, that a peer's QoS cannot match this reader's or writer's.
void report_incompatible(const StepContext& ctx, Endpoint& endpoint) {
  if (endpoint.incompatible_reported) return;
  const std::int32_t policy = endpoint.incompatible_policy.load(std::memory_order_acquire);
  if (policy <= 0) return;
  const auto id = static_cast<std::size_t>(policy);
  ctx.report(
      endpoint.incompatible_events[std::min(id, endpoint.incompatible_events.size() - 1)].c_str());
  endpoint.incompatible_reported = true;
}

}  // namespace

void Bridge::input(WriteContext& ctx) {
  for (auto& owned : subscriptions_) {
    Subscription& in = *owned;
    const std::int32_t publishers = in.publishers.load(std::memory_order_acquire);
    if ((publishers > 0) != (in.reported_publishers > 0)) {
      ctx.report(publishers > 0 ? in.found_event.c_str() : in.lost_event.c_str());
    }
    in.reported_publishers = publishers;
    report_incompatible(ctx, in);
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
    report_incompatible(ctx, out);
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

namespace {

/// The JSON Schema of `topics:`, for `arbiter schema`: the shapes init() checks. Whether a message
/// can carry an actuator's type depends on the layer, which only `arbiter validate` knows.
std::string topics_schema() {
  std::string messages;
  for (const Message message : {Message::kBool, Message::kInt64, Message::kFloat64,
                                Message::kString, Message::kVector3, Message::kPoint}) {
    messages += fmt::format("{}\"{}\"", messages.empty() ? "" : ", ", ros_name(message));
  }
  std::string profiles;
  for (const auto& profile : kQosProfiles) {
    profiles += fmt::format("{}\"{}\"", profiles.empty() ? "" : ", ", profile);
  }
  std::string schema = R"({
  "title": "Topics",
  "type": ["object", "null"],
  "propertyNames": {"pattern": "^[a-z_][a-z0-9_]*$"},
  "additionalProperties": {
    "title": "Topic of an actuator or sensor",
    "anyOf": [
      {"title": "Topic name", @NAME@},
      {
        "title": "Topic options",
        "type": "object",
        "additionalProperties": false,
        "properties": {
          "topic": {"title": "Topic name", @NAME@},
          "message": {"title": "ROS 2 message", "enum": [@MESSAGES@]},
          "qos": {"title": "ROS 2 QoS profile", "enum": [@PROFILES@]},
          "reliability": {"title": "Reliability", "enum": ["reliable", "best_effort"]},
          "history": {"title": "History", "enum": ["keep_last", "keep_all"]},
          "depth": {"title": "Depth", "type": "integer", "minimum": 1, "maximum": 10000},
          "durability": {"title": "Durability", "enum": ["volatile", "transient_local"]}
        }
      }
    ]
  }
})";
  // A ROS 2 name (check_topic_name): tokens not starting with a digit, an optional leading '/'.
  const std::string name =
      R"("type": "string", "pattern": "^/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")";
  for (auto at = schema.find("@NAME@"); at != std::string::npos; at = schema.find("@NAME@")) {
    schema.replace(at, 6, name);
  }
  schema.replace(schema.find("@MESSAGES@"), 10, messages);
  schema.replace(schema.find("@PROFILES@"), 10, profiles);
  return schema;
}

}  // namespace

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
  info.param("domain_id", &Bridge::domain_id)
      .defaults_to(0)
      .range(0.0, 232.0)
      .describe(
          "the DDS domain; when not set, the environment variable ROS_DOMAIN_ID, as for a ROS 2 "
          "node, or else 0");
  info.param("cyclone_config", &Bridge::cyclone_config)
      .defaults_to(std::string())
      .describe(
          "a Cyclone DDS XML configuration file, relative to this config file (or XML text "
          "starting with '<'); empty: Cyclone's defaults, or the file CYCLONEDDS_URI names");
  info.param("qos", &Bridge::qos)
      .defaults_to(std::string("default"))
      .one_of(kQosProfiles)
      .describe(
          "the ROS 2 QoS profile of every reader and writer: default (reliable, keep last 10, "
          "volatile), sensor_data (best effort, keep last 5, volatile) or system_default (the "
          "DDS implementation's); the params below change it, 'topics' per topic");
  info.param("reliability", &Bridge::reliability)
      .defaults_to(std::string("reliable"))
      .one_of({"reliable", "best_effort"})
      .describe("reliability QoS of every reader and writer, instead of the profile's");
  info.param("history", &Bridge::history)
      .defaults_to(std::string("keep_last"))
      .one_of({"keep_last", "keep_all"})
      .describe("history QoS of every reader and writer, instead of the profile's");
  info.param("depth", &Bridge::depth)
      .defaults_to(10)
      .range(1.0, 10000.0)
      .describe(
          "the history depth for keep_last, instead of the profile's: how many samples a reader "
          "keeps between steps");
  info.param("durability", &Bridge::durability)
      .defaults_to(std::string("volatile"))
      .one_of({"volatile", "transient_local"})
      .describe(
          "durability QoS, instead of the profile's: transient_local lets a subscriber that "
          "joins late get the last value");
  info.param("topic_prefix", &Bridge::topic_prefix)
      .defaults_to(std::string("rt/"))
      .describe("prepended to every topic name: 'rt/' is ROS 2's prefix for topics");
  info.param("namespace", &Bridge::ns)
      .defaults_to(std::string())
      .describe("a ROS 2 namespace for topic names that do not start with '/'");
  info.param("topics", &Bridge::topics)
      .defaults_to(Node())
      .schema(topics_schema())
      .describe(
          "per actuator or sensor of the layer: its topic name (default: its own name), or "
          "{topic, message, qos, reliability, history, depth, durability}");
  info.param("publish", &Bridge::publish_when)
      .defaults_to(std::string("written"))
      .one_of({"written", "every_step"})
      .describe(
          "written: publish a sensor only in steps in which its actuator was written; "
          "every_step: publish every sensor every step");
}

}  // namespace arbiter::dds

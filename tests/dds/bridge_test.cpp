// dds.Bridge in one process: two managers on one DDS domain, stepped by the test, so that what
// each step sees can be checked exactly (docs/semantics.md, "Interface layers"; docs/dds.md).

#include <catch2/catch.hpp>

#include <functional>
#include <map>
#include <memory>
#include <string>

#include <stdlib.h>

#include "dds_support.hpp"
#include "test_support.hpp"

using namespace arbiter;
using namespace arbiter::dds_test;
using namespace std::chrono_literals;

namespace {

// One value of every type the bridge carries.
const Values kPorts = {{"flag", "bool"},  {"count", "int"},   {"level", "double"},
                       {"point", "vec2"}, {"vector", "vec3"}, {"text", "string"}};

const std::vector<std::string> kValues = [] {
  std::vector<std::string> names;
  for (const auto& port : kPorts) names.push_back(port.first);
  return names;
}();

/// `{name: type, ...}` and `[name, ...]` of (name, type) pairs.
std::pair<std::string, std::string> yaml_ports(const Values& ports) {
  std::string map;
  std::string list;
  for (const auto& [name, type] : ports) {
    map += (map.empty() ? "{" : ", ") + name + ": " + type;
    list += (list.empty() ? "[" : ", ") + name;
  }
  return {map + "}", list + "]"};
}

/// A sender at 100 Hz: `stamp` (probe.Stamp) writes `ports` (names and types), which the bridge
/// layer to_dds publishes; `params` are its params after the domain and loopback configuration,
/// as lines indented by six.
std::string sender_yaml(const Values& ports, const std::string& params = "",
                        const std::string& stamp = "probe.Stamp") {
  const auto [actuators, sensors] = yaml_ports(ports);
  return fill(
      R"(
arbiter: 1
name: sender
rate_hz: 100
layers:
  - name: source
    actuators: {actuators}
    behaviours: {stamp: {behaviour}}
  - name: to_dds
    interface: dds.Bridge
    params:
      domain_id: {domain}
      cyclone_config: {xml}
{params}    sensors: {sensors}
)",
      {{"actuators", actuators}, {"behaviour", stamp}, {"params", params}, {"sensors", sensors}});
}

/// A receiver at 100 Hz of `ports` from the bridge layer from_dds, as sender_yaml() sends them;
/// `more` are layers after it.
std::string receiver_yaml(const Values& ports, const std::string& params = "",
                          const std::string& more = "") {
  const auto actuators = yaml_ports(ports).first;
  return fill(R"(
arbiter: 1
name: receiver
rate_hz: 100
layers:
  - name: from_dds
    interface: dds.Bridge
    params:
      domain_id: {domain}
      cyclone_config: {xml}
{params}    actuators: {actuators}
{more})",
              {{"actuators", actuators}, {"params", params}, {"more", more}});
}

// Publishes what probe.Stamp writes, in steps {every} apart, as bridge option {publish} says.
std::string every_type_sender() {
  return sender_yaml(kPorts, "      publish: {publish}\n",
                     "{type: probe.Stamp, params: {every: {every}}}");
}

// Receives them; a layer after the bridge reads one.
std::string every_type_receiver() {
  return receiver_yaml(kPorts, "", R"(  - name: user
    sensors: [count]
    actuators: {unused: double}
)");
}

struct Pair : Setup {
  std::string sender_path;
  std::unique_ptr<Manager> sender;
  std::unique_ptr<Manager> receiver;

  explicit Pair(int every = 1, const std::string& publish = "written") {
    sender_path = write("sender.yaml", every_type_sender(),
                        {{"every", std::to_string(every)}, {"publish", publish}});
    start_sender();
    receiver = std::make_unique<Manager>(load("receiver.yaml", every_type_receiver()));
    REQUIRE(bridge_of(*sender, "to_dds").wait_for_peers(10s));
    REQUIRE(bridge_of(*receiver, "from_dds").wait_for_peers(10s));
  }

  void start_sender() { sender = std::make_unique<Manager>(load_file(sender_path, registry)); }

  dds::Bridge& from_dds() const { return bridge_of(*receiver, "from_dds"); }

  /// Steps the sender `steps` times, then the receiver once, after every topic delivered.
  void send_and_receive(int steps = 1) {
    for (int i = 0; i < steps; ++i) sender->step();
    REQUIRE(from_dds().wait_for_data(10s));
    receiver->step();
  }
};

/// In this step the receiver read no new value: each holds the last, probe.Stamp's of step
/// `step`, unwritten.
void check_stale(const Manager& receiver, int step) {
  for (const auto& name : kValues) {
    INFO(name);
    CHECK_FALSE(written(receiver, name));
  }
  CHECK(value_of(receiver, "count") == step);
  CHECK(value_of(receiver, "text") == "step " + std::to_string(step));
}

bool events_contain(const Manager& manager, const std::string& text) {
  for (std::size_t e = 0; e < manager.event_count(); ++e) {
    if (std::string(manager.event(e).text).find(text) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("values of every type arrive with their types and are written in the next step",
          "[dds]") {
  Pair pair;
  for (const auto& name : kValues) {
    CHECK_FALSE(written(*pair.receiver, name));
  }
  pair.send_and_receive();
  CHECK(value_of(*pair.receiver, "flag") == true);
  CHECK(value_of(*pair.receiver, "count") == 1);
  CHECK(value_of(*pair.receiver, "level") == 0.5);
  CHECK(value_of(*pair.receiver, "point") == nlohmann::json::parse("[1.0, -1.0]"));
  CHECK(value_of(*pair.receiver, "vector") == nlohmann::json::parse("[1.0, 2.0, -0.5]"));
  CHECK(value_of(*pair.receiver, "text") == "step 1");
  for (const auto& name : kValues) {
    INFO(name);
    CHECK(written(*pair.receiver, name));
  }
  CHECK(pair.from_dds().stats().values_written == kValues.size());
}

TEST_CASE("a step without a delivery reads the last value, unwritten", "[dds]") {
  Pair pair;
  pair.send_and_receive();
  pair.receiver->step();
  check_stale(*pair.receiver, 1);
}

TEST_CASE("of several values sent between two steps, the newest is the one read", "[dds]") {
  Pair pair;
  pair.send_and_receive(4);
  CHECK(value_of(*pair.receiver, "count") == 4);
  CHECK(value_of(*pair.receiver, "vector") == nlohmann::json::parse("[4.0, 8.0, -0.5]"));
  CHECK(written(*pair.receiver, "count"));
}

TEST_CASE("a sensor is published only in steps in which its actuator was written", "[dds]") {
  SECTION("by default") {
    Pair pair(/*every=*/2);
    pair.sender->step();  // step 1: probe.Stamp inactive, nothing written
    pair.send_and_receive();
    CHECK(value_of(*pair.receiver, "count") == 2);
    CHECK(pair.from_dds().stats().samples_taken == kValues.size());
    CHECK(bridge_of(*pair.sender, "to_dds").stats().published == kValues.size());
  }
  SECTION("with publish: every_step, every step") {
    Pair pair(/*every=*/2, "every_step");
    pair.sender->step();
    pair.send_and_receive();
    CHECK(value_of(*pair.receiver, "count") == 2);
    CHECK(bridge_of(*pair.sender, "to_dds").stats().published == 2 * kValues.size());
  }
}

TEST_CASE("a publisher that disappears leaves its values stale, not lost, until it is back",
          "[dds]") {
  Pair pair;
  pair.send_and_receive(3);
  REQUIRE(value_of(*pair.receiver, "count") == 3);

  pair.sender.reset();
  bool lost = false;
  REQUIRE(step_until(
      *pair.receiver,
      [&] {
        lost = lost || events_contain(*pair.receiver, "count: publisher lost");
        return lost;
      },
      10s));
  for (int i = 0; i < 3; ++i) {
    pair.receiver->step();
    check_stale(*pair.receiver, 3);
  }

  pair.start_sender();
  REQUIRE(bridge_of(*pair.sender, "to_dds").wait_for_peers(10s));
  pair.send_and_receive();
  CHECK(written(*pair.receiver, "count"));
  CHECK(value_of(*pair.receiver, "count") == 1);  // the new sender's first step
}

TEST_CASE("per-topic options: a late subscriber gets the last value, a vector travels as Vector3",
          "[dds]") {
  Setup setup;
  // The same options on both sides: a topic's type and QoS must agree to match.
  const Values ports = {{"count", "int"}, {"point", "vec2"}};
  constexpr const char* kTopics = R"(      topics:
        count: {topic: /probe/count, durability: transient_local}
        point: {topic: /probe/point, message: geometry_msgs/msg/Vector3, reliability: best_effort}
)";
  Manager sender(setup.load("sender.yaml", sender_yaml(ports, kTopics)));
  sender.step();
  sender.step();
  CHECK(bridge_of(sender, "to_dds").topic_of("point") == "rt/probe/point");

  Manager receiver(setup.load("receiver.yaml", receiver_yaml(ports, kTopics)));
  auto& from_dds = bridge_of(receiver, "from_dds");
  // The count was published before the receiver existed; transient_local keeps it for it.
  REQUIRE(step_until(
      receiver, [&] { return written(receiver, "count"); }, 10s));
  CHECK(value_of(receiver, "count") == 2);
  CHECK_FALSE(written(receiver, "point"));  // volatile: the earlier points are gone

  REQUIRE(from_dds.wait_for_peers(10s));
  sender.step();
  REQUIRE(from_dds.wait_for_data(10s));
  receiver.step();
  CHECK(value_of(receiver, "count") == 3);
  CHECK(value_of(receiver, "point") == nlohmann::json::parse("[3.0, -3.0]"));
}

namespace {

/// Steps `sender` once and, once every topic delivered, `receiver` once; then the receiver reads
/// the values probe.Stamp wrote in its first step, with their types.
void check_first_values_arrive(Manager& sender, const std::string& to_dds, Manager& receiver,
                               const std::string& from_dds) {
  REQUIRE(bridge_of(sender, to_dds).wait_for_peers(10s));
  REQUIRE(bridge_of(receiver, from_dds).wait_for_peers(10s));
  sender.step();
  REQUIRE(bridge_of(receiver, from_dds).wait_for_data(10s));
  receiver.step();
  CHECK(value_of(receiver, "flag") == true);
  CHECK(value_of(receiver, "count") == 1);
  CHECK(value_of(receiver, "level") == 0.5);
  CHECK(value_of(receiver, "point") == nlohmann::json::parse("[1.0, -1.0]"));
  CHECK(value_of(receiver, "vector") == nlohmann::json::parse("[1.0, 2.0, -0.5]"));
  CHECK(value_of(receiver, "text") == "step 1");
  for (const auto& name : kValues) {
    INFO(name);
    CHECK(written(receiver, name));
  }
}

}  // namespace

TEST_CASE("a program compiled from text in memory bridges its layers both ways", "[dds]") {
  Setup setup;
  const auto text = [&](const std::string& config) {
    return fill(fill(config, {{"every", "1"}, {"publish", "written"}}), setup.values());
  };
  // Named after files that do not exist: nothing may read the config again.
  Manager sender(
      test::compile_text(text(every_type_sender()), setup.registry, "no/such/sender.yaml"));
  Manager receiver(
      test::compile_text(text(every_type_receiver()), setup.registry, "no/such/receiver.yaml"));
  check_first_values_arrive(sender, "to_dds", receiver, "from_dds");
}

TEST_CASE("a bridge layer in an included file bridges what that layer names", "[dds]") {
  Setup setup;
  // The bridges' layers come after other layers' actuators, from included files of included
  // files, so that their actuators and sensors are not the program's first.
  setup.write("source.yaml", R"(
arbiter: 1
layers:
  - name: source
    actuators: {flag: bool, count: int, level: double, point: vec2, vector: vec3, text: string}
    behaviours: {stamp: probe.Stamp}
)");
  setup.write("to_dds.yaml", R"(
arbiter: 1
include: [source.yaml]
layers:
  - name: to_dds
    interface: dds.Bridge
    params: {domain_id: {domain}, cyclone_config: {xml}}
    sensors: [text, vector, point, level, count, flag]
)");
  setup.write("spacer.yaml", R"(
arbiter: 1
layers:
  - name: spacer
    actuators: {pad_text: string, pad_vector: vec3}
)");
  setup.write("from_dds.yaml", R"(
arbiter: 1
include: [spacer.yaml]
layers:
  - name: from_dds
    interface: dds.Bridge
    params: {domain_id: {domain}, cyclone_config: {xml}}
    actuators: {text: string, flag: bool, count: int, level: double, point: vec2, vector: vec3}
)");
  Manager sender(setup.load("sender.yaml", R"(
arbiter: 1
name: sender
rate_hz: 100
include: [to_dds.yaml]
layers:
  - name: after
    actuators: {late: double}
)"));
  Manager receiver(setup.load("receiver.yaml", R"(
arbiter: 1
name: receiver
rate_hz: 100
include: [from_dds.yaml]
layers:
  - name: user
    sensors: [count, pad_vector]
    actuators: {unused: double}
)"));
  CHECK(bridge_of(sender, "to_dds").publication_count() == kValues.size());
  CHECK(bridge_of(receiver, "from_dds").subscription_count() == kValues.size());
  CHECK(bridge_of(receiver, "from_dds").topic_of("vector") == "rt/vector");
  check_first_values_arrive(sender, "to_dds", receiver, "from_dds");
}

namespace {

/// A value type of a plugin's own, which the bridge does not carry.
struct Colour {
  std::int64_t code = 0;
};

}  // namespace

template <>
struct arbiter::ValueTraits<Colour> {
  static bool from_node(const Node& node, Colour& to, std::string& expected) {
    expected = "an integer";
    const auto code = node.as_int();
    if (code) to.code = *code;
    return code.has_value();
  }
  static void append_json(const Colour& value, std::string& out) {
    out += std::to_string(value.code);
  }
};

TEST_CASE("a sensor the bridge cannot carry is reported where its layer names it", "[dds]") {
  Setup setup;
  setup.write("link.yaml", R"(
arbiter: 1
layers:
  - name: link
    interface: dds.Bridge
    params: {domain_id: {domain}, cyclone_config: {xml}}
    sensors: [beacon]
)");
  setup.registry.add_value_type<Colour>("test.Colour");
  const std::string root = setup.dir.write("root.yaml", R"(
arbiter: 1
name: root
include: [link.yaml]
layers:
  - name: lights
    actuators: {beacon: test.Colour}
)");
  Diagnostics diagnostics;
  CHECK_FALSE(load(root, setup.registry, diagnostics));
  REQUIRE(diagnostics.error_count() == 1);
  const Diagnostic& error = diagnostics.items().front();
  CHECK(error.location.file == setup.dir.file("link.yaml"));
  CHECK(error.location.line == 7);
  CHECK(error.location.column == 15);
  CHECK_THAT(error.message, Catch::Contains("sensor 'beacon' has type 'test.Colour'"));
}

namespace {

/// Steps both managers at their rate until `done()`, or 10 s pass; counts each event text seen.
std::map<std::string, int> step_both_until(Manager& a, Manager& b,
                                           const std::function<bool()>& done) {
  std::map<std::string, int> seen;
  const auto record = [&](const Manager& manager) {
    for (std::size_t e = 0; e < manager.event_count(); ++e) ++seen[manager.event(e).text];
  };
  step_until(
      a,
      [&] {
        record(a);
        b.step();
        record(b);
        return done();
      },
      10s);
  return seen;
}

int count_containing(const std::map<std::string, int>& seen, const std::string& part) {
  int count = 0;
  for (const auto& [text, times] : seen) {
    if (text.find(part) != std::string::npos) count += times;
  }
  return count;
}

}  // namespace

TEST_CASE("a peer whose QoS cannot match is reported once per topic on both sides, with the fix",
          "[dds][qos]") {
  Setup setup;
  // ROS 2's sensor-data profile is best effort: against the default (reliable) reader, nothing
  // would ever arrive. The count's reliability is set back to reliable, so the count arrives.
  const Values ports = {{"count", "int"}, {"level", "double"}};
  Manager sender(setup.load("sender.yaml", sender_yaml(ports, R"(      qos: sensor_data
      topics: {count: {reliability: reliable}}
)")));
  Manager receiver(setup.load("receiver.yaml", receiver_yaml(ports)));
  const auto seen = step_both_until(sender, receiver, [&] {
    return written(receiver, "count") &&
           bridge_of(receiver, "from_dds").stats().values_written >= 5;
  });
  CHECK(written(receiver, "count"));
  // Both sides say it, once, with the topic, the policy, each side's value and the fix.
  CHECK(seen.count(
            "level: warning: incompatible QoS on rt/level: a publisher offers best_effort "
            "reliability, this subscription requests reliable; nothing it publishes arrives. Set "
            "'reliability: best_effort' (or 'qos: sensor_data') for 'level' under topics:, or "
            "make the publisher reliable") == 1);
  CHECK(seen.count(
            "level: warning: incompatible QoS on rt/level: a subscriber requests reliable "
            "reliability, this publication offers best_effort; it receives nothing from this "
            "bridge. Set 'reliability: reliable' (or 'qos: default') for 'level' under topics:, "
            "or make the subscriber best-effort") == 1);
  CHECK(count_containing(seen, "incompatible QoS") == 2);
  CHECK(count_containing(seen, "rt/count") == 1);  // only "publisher found"
  CHECK_FALSE(written(receiver, "level"));
}

TEST_CASE("a profile per topic: sensor data matches sensor data, a late joiner gets the kept value",
          "[dds][qos]") {
  Setup setup;
  const Values ports = {{"count", "int"}, {"level", "double"}};
  constexpr const char* kTopics = R"(      topics:
        count: {qos: default, durability: transient_local}
        level: {qos: sensor_data}
)";
  Manager sender(setup.load("sender.yaml", sender_yaml(ports, kTopics)));
  sender.step();
  // The receiver asks for what was published before it joined; the sender keeps it.
  Manager receiver(setup.load("receiver.yaml", receiver_yaml(ports, kTopics)));
  const auto seen = step_both_until(
      sender, receiver, [&] { return written(receiver, "level") && written(receiver, "count"); });
  CHECK(written(receiver, "level"));
  CHECK(count_containing(seen, "incompatible QoS") == 0);
}

TEST_CASE("without domain_id the bridge joins the domain ROS_DOMAIN_ID names, as ROS 2 nodes do",
          "[dds]") {
  Setup setup;
  Manager sender(setup.load("sender.yaml", sender_yaml({{"count", "int"}})));
  const std::string receiver_path = setup.write("receiver.yaml", R"(
arbiter: 1
name: receiver
rate_hz: 100
layers:
  - name: from_dds
    interface: dds.Bridge
    params: {cyclone_config: {xml}}
    actuators: {count: int}
)");
  SECTION("a domain id") {
    ::setenv("ROS_DOMAIN_ID", std::to_string(setup.domain.id()).c_str(), 1);
    Manager receiver(load_file(receiver_path, setup.registry));
    ::unsetenv("ROS_DOMAIN_ID");
    step_both_until(sender, receiver, [&] { return written(receiver, "count"); });
    CHECK(written(receiver, "count"));
  }
  SECTION("anything else is an error at the layer, naming the variable") {
    ::setenv("ROS_DOMAIN_ID", "seven", 1);
    Diagnostics diagnostics;
    CHECK_FALSE(load(receiver_path, setup.registry, diagnostics));
    ::unsetenv("ROS_DOMAIN_ID");
    REQUIRE(diagnostics.error_count() == 1);
    CHECK(diagnostics.items().front().location.line == 6);
    CHECK(diagnostics.items().front().message ==
          "the environment variable ROS_DOMAIN_ID is 'seven', which is not a DDS domain id (an "
          "integer in [0, 232]); set it to one, or set 'domain_id' in the bridge's params");
  }
}

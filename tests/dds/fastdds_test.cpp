// The bridge against a second DDS implementation: eProsima Fast DDS, the default middleware of ROS
// 2, as a stand-in ROS 2 node (fastdds_peer.cpp: ROS 2 type names, plain CDR, ROS 2's default
// QoS, rt/ topic names; loopback only). Each message of docs/dds.md's table crosses both ways,
// and the peer plays the split demo's strategy against its motion process.

#include <catch2/catch.hpp>

#include <signal.h>
#include <stdlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include "dds_support.hpp"

using namespace arbiter::dds_test;
using namespace std::chrono_literals;
using nlohmann::json;

namespace {

// probe.Stamp writes the value of one type; the bridge publishes it on /arbiter/out and
// subscribes to what comes back on /arbiter/in as `back`.
constexpr const char* kEcho = R"(
arbiter: 1
name: echo
rate_hz: 50
plugins: [dds, dds_probe]
layers:
  - name: source
    actuators: {{port}: {type}}
    behaviours: {stamp: probe.Stamp}
  - name: link
    interface: dds.Bridge
    params:
      domain_id: {domain}
      cyclone_config: {xml}
      topics:
        {port}: {topic: /arbiter/out, message: {message}}
        back: {topic: /arbiter/in, message: {message}}
    actuators: {back: {type}}
    sensors: [{port}]
    lint: {ignore: [unread-actuator]}  # the test reads it in the trace
)";

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The stamp's number `n` of the step a value was written in, checked against how probe.Stamp
/// derives the value from it; -1 when the value is not one it writes.
double stamp_of(const json& value, const std::string& type) {
  if (type == "bool") return value.is_boolean() ? 0 : -1;
  if (type == "int") return value.is_number_integer() ? value.get<double>() : -1;
  if (type == "double") return value.is_number() ? 2.0 * value.get<double>() : -1;
  if (type == "string") {
    std::smatch match;
    const std::string text = value.is_string() ? value.get<std::string>() : "";
    return std::regex_match(text, match, std::regex("step ([0-9]+)")) ? std::stod(match[1]) : -1;
  }
  if (type == "vec2") {
    return value.size() == 2 && value[1] == -value[0].get<double>() ? value[0].get<double>() : -1;
  }
  if (type == "vec3") {
    return value.size() == 3 && value[1] == 2.0 * value[0].get<double>() && value[2] == -0.5
               ? value[0].get<double>()
               : -1;
  }
  return -1;
}

/// Runs the echo config for `type` carried as `message` against the Fast DDS peer, and checks
/// what each side received.
void check_round_trip(const std::string& message, const std::string& type, const std::string& port,
                      const std::string& received) {
  Setup setup;
  const std::string config =
      setup.write("echo.yaml", kEcho, {{"port", port}, {"type", type}, {"message", message}});
  Child peer({ARBITER_FASTDDS_PEER, "echo", message, std::to_string(setup.domain.id()), "40"},
             setup.dir.file("peer.out"));
  Child arbiter(arbiter_run(config, 2000, setup.dir.file("echo.jsonl"), /*quiet=*/false),
                setup.dir.file("arbiter.out"));
  // The echoes count once both directions are matched: the peer has received a stamp (the
  // bridge's writer found its reader) and the bridge's reader has found the peer's writer, as
  // the bridge reports; from then on the peer's echoes, 50 ms apart, arrive.
  const bool found = peer.wait_for_output("received: ", 30s) &&
                     arbiter.wait_for_output("link: back: publisher found", 30s);
  if (found) std::this_thread::sleep_for(1s);
  peer.signal(SIGINT);
  check_exit(peer, 30s);
  arbiter.signal(SIGINT);
  check_exit(arbiter, 20s);
  INFO(peer.output());
  INFO(arbiter.output());
  REQUIRE(found);
  // Arbiter → Fast DDS: the peer decoded the stamp's value.
  CHECK(std::regex_search(peer.output(), std::regex("received: " + received + "\n")));
  // Fast DDS → Arbiter: what came back is a value the stamp wrote in an earlier step.
  int written = 0;
  for (const auto& step : read_trace(setup.dir.file("echo.jsonl"))) {
    const json& back = step.at("actuators").at("back");
    if (!back.at("written").get<bool>()) continue;
    ++written;
    INFO(step.dump());
    const double n = stamp_of(back.at("value"), type);
    CHECK(n >= 0);
    CHECK(n < step.at("step").get<double>());
  }
  // A second of echoes, 50 ms apart: in steps of their own unless the machine stalls the 50 Hz
  // process.
  CHECK(written >= 3);
}

}  // namespace

TEST_CASE("a value of each type crosses to Fast DDS and back as its ROS 2 message",
          "[dds][fastdds]") {
  // {message, type, port, what the peer prints on receiving the stamp's value}
  const auto trip = GENERATE(values<std::array<const char*, 4>>({
      {"std_msgs/msg/Bool", "bool", "flag", "data=(true|false)"},
      {"std_msgs/msg/Int64", "int", "count", "data=[1-9][0-9]*"},
      {"std_msgs/msg/Float64", "double", "level", "data=[0-9]+(\\.5)?"},
      {"std_msgs/msg/String", "string", "text", "data=\"step [1-9][0-9]*\""},
      {"geometry_msgs/msg/Point", "vec2", "point", "x=([1-9][0-9]*) y=-\\1 z=0"},
      {"geometry_msgs/msg/Vector3", "vec3", "vector", "x=[1-9][0-9]* y=[0-9]+ z=-0.5"},
  }));
  INFO(trip[0]);
  check_round_trip(trip[0], trip[1], trip[2], trip[3]);
}

TEST_CASE("a Fast DDS node playing the strategy walks the split demo's robot to the ball and kicks",
          "[dds][fastdds][process]") {
  // The shipped motion config, with the ball placed near the robot so that the walk is short.
  DomainLease domain;
  TempDir dir;
  std::string motion = read_text_file(ARBITER_SOURCE_DIR "/configs/soccer/split/motion.yaml");
  const std::string ball = "ball_start: [0.5, 1.0]";
  REQUIRE(motion.find(ball) != std::string::npos);
  motion.replace(motion.find(ball), ball.size(), "ball_start: [-2.2, -0.8]");
  dir.write("motion.yaml", motion);
  std::filesystem::copy_file(ARBITER_SOURCE_DIR "/configs/soccer/split/cyclonedds-loopback.xml",
                             dir.file("cyclonedds-loopback.xml"));
  ::setenv("ROS_DOMAIN_ID", std::to_string(domain.id()).c_str(), 1);
  Child motion_process(arbiter_run(dir.file("motion.yaml"), 1200, dir.file("motion.jsonl"),
                                   /*quiet=*/false),
                       dir.file("motion.out"));
  ::unsetenv("ROS_DOMAIN_ID");
  Child strategy({ARBITER_FASTDDS_PEER, "strategy", std::to_string(domain.id()), "10"},
                 dir.file("strategy.out"));
  check_exit(strategy, 30s);
  check_exit(motion_process, 30s);
  const std::string motion_output = motion_process.output();
  INFO(motion_output);
  INFO(strategy.output());
  // Fast DDS received what the motion process publishes ...
  const std::string strategy_output = strategy.output();
  std::smatch counts;
  REQUIRE(std::regex_search(strategy_output, counts,
                            std::regex("received ball_visible ([0-9]+), ball_position ([0-9]+), "
                                       "robot_pose ([0-9]+)")));
  CHECK(std::stoi(counts[1]) > 10);
  CHECK(std::stoi(counts[2]) > 10);
  CHECK(std::stoi(counts[3]) > 10);
  // ... and the world reacted to its commands: the robot walked, and kicked the ball.
  CHECK(motion_output.find("strategy_link: walk_command: publisher found") != std::string::npos);
  CHECK(motion_output.find("world: ball kicked") != std::string::npos);
  const auto trace = read_trace(dir.file("motion.jsonl"));
  REQUIRE(!trace.empty());
  // The farthest the robot got from its start: after a goal the world kicks off again and puts
  // the robot back, so the last pose may be near the first.
  const json start = trace.front().at("actuators").at("robot_pose").at("value");
  double farthest = 0.0;
  for (const json& record : trace) {
    const json& pose = record.at("actuators").at("robot_pose").at("value");
    farthest = std::max(farthest, std::hypot(pose[0].get<double>() - start[0].get<double>(),
                                             pose[1].get<double>() - start[1].get<double>()));
  }
  CHECK(farthest > 0.3);
}

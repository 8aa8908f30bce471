// The soccer demo split over two processes (configs/soccer/split/): a 10 Hz strategy process and a
// 100 Hz motion process, started with the README's `arbiter run` commands (both at once, and the
// motion for 15 s rather than 30), reach the single-process demo's outcome.

#include <catch2/catch.hpp>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include <stdlib.h>

#include "dds_support.hpp"

using namespace arbiter::dds_test;
using namespace std::chrono_literals;

namespace {

const std::string kSplitDir = ARBITER_SOURCE_DIR "/configs/soccer/split/";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The text of layer `name` in a config: from its `- name:` line to the next layer's.
std::string layer_text(const std::string& config, const std::string& name) {
  const auto begin = config.find("  - name: " + name + "\n");
  REQUIRE(begin != std::string::npos);
  const auto end = config.find("\n  - name: ", begin + 1);
  return config.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
}

}  // namespace

TEST_CASE("the strategy process runs the single-process demo's control layer unchanged", "[dds]") {
  const std::string single = read_text(ARBITER_SOURCE_DIR "/configs/soccer/walk_and_kick.yaml");
  const std::string strategy = read_text(kSplitDir + "strategy.yaml");
  CHECK(layer_text(strategy, "control") == layer_text(single, "control"));
}

TEST_CASE("the split soccer demo kicks the ball and scores a goal", "[dds][process]") {
  // The shipped configs, on a domain no other test uses: they take it from ROS_DOMAIN_ID, as a
  // ROS 2 node does.
  DomainLease domain;
  TempDir dir;
  for (const std::string name : {"motion.yaml", "strategy.yaml"}) {
    const std::string text = read_text(kSplitDir + name);
    REQUIRE(text.find("domain_id") == std::string::npos);
    dir.write(name, text);
  }
  ::setenv("ROS_DOMAIN_ID", std::to_string(domain.id()).c_str(), 1);
  std::filesystem::copy_file(kSplitDir + "cyclonedds-loopback.xml",
                             dir.file("cyclonedds-loopback.xml"));

  // The single-process demo scores after 13.1 s; the split one about as soon.
  Child motion(arbiter_run(dir.file("motion.yaml"), 1500, "", /*quiet=*/false),
               dir.file("motion.out"));
  Child strategy(arbiter_run(dir.file("strategy.yaml"), 150, "", /*quiet=*/false),
                 dir.file("strategy.out"));
  check_exit(motion, 60s);
  check_exit(strategy, 20s);
  const std::string motion_output = motion.output();
  INFO(motion_output);
  INFO(strategy.output());
  CHECK(std::regex_search(motion_output, std::regex("world: ball kicked[\\s\\S]*world: goal!")));
  // The single-process demo's outcome: one kick, one goal.
  CHECK(motion_output.find("world: ball kicked (1 time)") != std::string::npos);
  CHECK(motion_output.find("world: goal! (1 time)") != std::string::npos);
  CHECK(motion_output.find("strategy_link: walk_command: publisher found") != std::string::npos);
  CHECK(strategy.output().find("motion_link: ball_position: publisher found") != std::string::npos);
}

TEST_CASE("the motion process stands at once when the strategy process stops or pauses",
          "[dds][process][safe]") {
  DomainLease domain;
  TempDir dir;
  const std::string id = "domain_id: " + std::to_string(domain.id());
  for (const std::string name : {"motion.yaml", "strategy.yaml"}) {
    dir.write(name,
              std::regex_replace(read_text(kSplitDir + name), std::regex("domain_id: 7"), id));
  }
  std::filesystem::copy_file(kSplitDir + "cyclonedds-loopback.xml",
                             dir.file("cyclonedds-loopback.xml"));
  const auto zero = nlohmann::json::array({0.0, 0.0, 0.0});
  // The walk commands the motion process received (written) in `trace`, from the strategy's
  // first on: the last is the safe gait, the one before it made the robot walk, and the safe one
  // arrived in the next motion step or so, not after the 0.3 s hold timeout (30 steps). Returns
  // the step it arrived in.
  const auto check_stood_at_once = [&](const std::string& trace) {
    std::vector<std::pair<std::uint64_t, nlohmann::json>> commands;
    for (const auto& record : read_trace(trace)) {
      const auto& command = record["actuators"]["walk_command"];
      if (command["written"] == true) commands.emplace_back(record["step"], command["value"]);
    }
    REQUIRE(commands.size() >= 2);
    CHECK(commands.back().second == zero);
    CHECK(commands[commands.size() - 2].second != zero);
    CHECK(commands.back().first - commands[commands.size() - 2].first <= 15);
    return commands.back().first;
  };

  SECTION("at the end of its steps") {
    // 1.5 s of strategy: the robot is walking to the ball when it stops.
    Child motion(arbiter_run(dir.file("motion.yaml"), 400, dir.file("motion.jsonl")),
                 dir.file("motion.out"));
    Child strategy(arbiter_run(dir.file("strategy.yaml"), 15, dir.file("strategy.jsonl")),
                   dir.file("strategy.out"));
    REQUIRE(strategy.wait(20s) == 0);
    REQUIRE(motion.wait(20s) == 0);
    const auto strategy_trace = read_trace(dir.file("strategy.jsonl"));
    REQUIRE(strategy_trace.back()["safe"] == true);
    INFO(motion.output());
    const auto safe_step = check_stood_at_once(dir.file("motion.jsonl"));
    const auto motion_trace = read_trace(dir.file("motion.jsonl"));
    const auto& at = motion_trace[safe_step - 1];
    CHECK(at["actuators"]["gait_velocity"]["value"] == zero);
  }

  SECTION("when paused from the live page") {
    Child motion(arbiter_run(dir.file("motion.yaml"), 400, dir.file("motion.jsonl")),
                 dir.file("motion.out"));
    auto argv = arbiter_run(dir.file("strategy.yaml"), 100000, "", /*quiet=*/false);
    for (const std::string arg : {"--serve", "127.0.0.1:0", "--serve-token", "pause-test"}) {
      argv.push_back(arg);
    }
    Child strategy(argv, dir.file("strategy.out"));
    // The URL, then a second of walking, then the page's Pause.
    std::smatch port;  // points into `printed`, which must outlive it
    std::string printed;
    for (int i = 0; i < 100; ++i) {
      printed = strategy.output();
      if (std::regex_search(printed, port, std::regex("127\\.0\\.0\\.1:(\\d+)/"))) break;
      std::this_thread::sleep_for(100ms);
    }
    REQUIRE(port.size() == 2);
    std::this_thread::sleep_for(1500ms);
    // The page's Pause, as curl sends it (found on PATH by the shell).
    Child pause({"/bin/sh", "-c",
                 "curl -sf -d '' -H 'X-Arbiter-Token: pause-test' http://127.0.0.1:" +
                     port[1].str() + "/control/pause"},
                dir.file("curl.out"));
    REQUIRE(pause.wait(10s) == 0);
    REQUIRE(motion.wait(20s) == 0);
    REQUIRE(strategy.stop(SIGTERM, 10s) == 0);
    INFO(strategy.output());
    check_stood_at_once(dir.file("motion.jsonl"));
    CHECK(strategy.output().find("safe values output: gait_velocity = [0.0, 0.0, 0.0]") !=
          std::string::npos);
  }
}

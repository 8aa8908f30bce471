// The soccer demo split over two processes (configs/soccer/split/): a 10 Hz strategy process and a
// 100 Hz motion process, started with the README's `arbiter run` commands (both at once, and the
// motion for 15 s rather than 30), reach the single-process demo's outcome.

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

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
  const auto motion_status = motion.wait(60s);
  const auto strategy_status = strategy.wait(20s);
  const std::string motion_output = motion.output();
  INFO(motion_output);
  INFO(strategy.output());
  REQUIRE(motion_status);
  REQUIRE(strategy_status);
  CHECK(*motion_status == 0);
  CHECK(*strategy_status == 0);
  CHECK(std::regex_search(motion_output, std::regex("world: ball kicked[\\s\\S]*world: goal!")));
  // The single-process demo's outcome: one kick, one goal.
  CHECK(motion_output.find("world: ball kicked (1 time)") != std::string::npos);
  CHECK(motion_output.find("world: goal! (1 time)") != std::string::npos);
  CHECK(motion_output.find("strategy_link: walk_command: publisher found") != std::string::npos);
  CHECK(strategy.output().find("motion_link: ball_position: publisher found") != std::string::npos);
}

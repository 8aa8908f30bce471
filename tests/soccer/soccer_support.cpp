#include "soccer_support.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "soccer.hpp"
#include "test_support.hpp"

namespace arbiter::soccer::test {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

const std::string kDemoConfig = ARBITER_SOURCE_DIR "/configs/soccer/walk_and_kick.yaml";
const std::string kGoalieConfig = ARBITER_SOURCE_DIR "/configs/soccer/goalie.yaml";

Registry soccer_registry() {
  Registry registry = arbiter::test::make_test_registry();
  registry.set_origin("soccer");
  arbiter::soccer::register_classes(registry);
  return registry;
}

std::string demo_config_with(const Pose& robot, const Point& ball, int seed) {
  std::string text = read_file(kDemoConfig);
  const auto replace = [&](const std::string& key, const std::string& value) {
    const std::regex pattern(key + ": [^\\n#]*");
    REQUIRE(std::regex_search(text, pattern));
    text = std::regex_replace(text, pattern, key + ": " + value,
                              std::regex_constants::format_first_only);
  };
  replace("seed", std::to_string(seed));
  replace("robot_start", "[" + std::to_string(robot.x) + ", " + std::to_string(robot.y) + ", " +
                             std::to_string(robot.theta) + "]");
  replace("ball_start", "[" + std::to_string(ball.x) + ", " + std::to_string(ball.y) + "]");
  return text;
}

WorldLink& world_link(const Manager& manager) {
  for (const auto& layer : manager.program().layers) {
    if (layer.is_interface()) return dynamic_cast<WorldLink&>(*layer.interface);
  }
  throw std::runtime_error("the program has no interface layer");
}

std::string edited(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

void StoryLog::on_step(const Manager& manager) {
  const std::string step = std::to_string(manager.steps());
  std::vector<std::pair<std::uint32_t, std::string>> happened;  // by sequence
  const Controller* goalie = manager.program().find_controller("goalie");
  if (goalie != nullptr) {
    for (std::size_t e = 0; e < goalie->event_count(); ++e) {
      const auto& event = goalie->events()[e];
      if (event.kind != Controller::Event::Kind::kActivate) continue;
      happened.emplace_back(event.sequence,
                            step + " activate " + goalie->states()[event.state].name);
      const Pose robot = world_link(manager).world()->robot();
      poses.push_back(robot);
    }
  }
  for (std::size_t e = 0; e < manager.event_count(); ++e) {
    const auto& event = manager.event(e);
    happened.emplace_back(event.sequence,
                          step + " " + manager.event_source(event) + ": " + event.text);
  }
  std::sort(happened.begin(), happened.end());
  for (auto& [sequence, line] : happened) lines.push_back(std::move(line));
  if (goalie != nullptr && goalie->status() != ControllerStatus::kRunning && !ended) {
    ended = true;
    lines.push_back(step + " " + arbiter::to_string(goalie->status()));
  }
}

std::vector<std::string> lines_with(const StoryLog& log, const std::string& what) {
  std::vector<std::string> found;
  for (const auto& line : log.lines) {
    if (line.find(what) != std::string::npos) found.push_back(line);
  }
  return found;
}

}  // namespace arbiter::soccer::test

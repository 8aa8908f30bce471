#pragma once
// Shared by the soccer plugin's tests: its registry, the demo configs and what a run of them
// tells.

#include <cstdint>
#include <string>
#include <vector>

#include "arbiter/manager.hpp"
#include "arbiter/registry.hpp"
#include "world.hpp"
#include "world_link.hpp"

namespace arbiter::soccer::test {

std::string read_file(const std::string& path);

extern const std::string kDemoConfig;
extern const std::string kGoalieConfig;

Registry soccer_registry();

/// The demo config with the world's params replaced, as a user would edit it.
std::string demo_config_with(const Pose& robot, const Point& ball, int seed);

WorldLink& world_link(const Manager& manager);

/// `text` with the first occurrence of `from` replaced by `to`, which must be there.
std::string edited(std::string text, const std::string& from, const std::string& to);

/// What happened in each step, in the order it happened: "11 activate walk_to_pose" for a goalie
/// state that became current, "201 world: shot on goal" for an event reported by behaviour or
/// interface code.
class StoryLog : public Observer {
 public:
  void on_step(const Manager& manager) override;

  std::vector<std::string> lines;
  std::vector<Pose> poses;  ///< the robot's pose at each activation, in order
  bool ended = false;
};

/// The lines of `log` that mention `what`.
std::vector<std::string> lines_with(const StoryLog& log, const std::string& what);

}  // namespace arbiter::soccer::test

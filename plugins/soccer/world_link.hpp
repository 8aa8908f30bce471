#pragma once
// soccer.WorldLink: the interface class that owns the simulated world. The input pass publishes
// what the robot senses; the output pass applies the commands and advances the world by one dt.

#include <memory>

#include "arbiter/behaviour.hpp"
#include "arbiter/registry.hpp"
#include "world.hpp"

namespace arbiter::soccer {

void register_world_link(Registry& registry);

class WorldLink final : public Interface {
 public:
  void init(InitContext& ctx) override;
  void input(WriteContext& ctx) override;
  void output(const StepContext& ctx) override;

  /// The world, for tests and tools; null before init().
  const World* world() const { return world_.get(); }
  World* world() { return world_.get(); }

 private:
  friend void register_world_link(Registry& registry);
  std::unique_ptr<World> world_;
  std::int64_t seed_ = 0;
  double dt_ = 0.0;
  Vec3 robot_start_;
  Vec2 ball_start_;
  double noise_ = 0.0;
  std::int64_t button_step_ = -1;
  std::int64_t shot_step_ = -1;
  Vec2 shot_target_;
  double shot_speed_ = 0.0;
  double kick_off_delay_ = 0.0;
  Output<bool> ball_visible_;
  Output<Vec2> ball_position_;
  Output<Vec2> ball_velocity_;
  Output<Vec3> robot_pose_;
  Output<bool> button_;
  Output<bool> ball_kicked_;
  Output<bool> goal_scored_;
  Input<Vec3> gait_velocity_;
  Input<double> head_angle_;
  Input<bool> kick_;
  Input<std::int64_t> dive_;
};

}  // namespace arbiter::soccer

#include "hold.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "arbiter/init_context.hpp"

namespace arbiter::dds {
namespace {

template <typename T>
void register_hold(Registry& registry, const std::string& type);

template <typename T>
class Hold final : public Behaviour {
 public:
  void init(BehaviourInitContext& ctx) override {
    const double steps = std::ceil(timeout_ * ctx.rate_hz() - 1e-9);
    timeout_steps_ = std::max<std::int64_t>(1, static_cast<std::int64_t>(steps));
  }

  void update(const StepContext& ctx) override {
    if (ctx.written(from_)) {
      age_ = 0;
    } else if (age_ < kNever) {
      ++age_;
    }
  }

  double activation(const StepContext& /*ctx*/) override {
    return age_ < timeout_steps_ ? level_ : 0.0;
  }

  void execute(ExecuteContext& ctx) override { ctx.write(to_, ctx.read(from_)); }

 private:
  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();
  friend void register_hold<T>(Registry& registry, const std::string& type);

  Input<T> from_;
  Output<T> to_;
  double level_ = 1.0;
  double timeout_ = 0.0;  ///< seconds
  std::int64_t timeout_steps_ = 1;
  std::int64_t age_ = kNever;  // steps since `from` was last written
};

template <typename T>
void register_hold(Registry& registry, const std::string& type) {
  auto& info =
      registry.add_behaviour<Hold<T>>(fmt::format("dds.Hold{}", type))
          .describe(
              "Writes the last value its 'from' sensor received to its 'to' actuator every step, "
              "from a step in which 'from' was written until 'timeout' seconds pass without "
              "another write; requests activation 0 after that. Bridges a command sent at a "
              "lower rate (through dds.Bridge) to a layer that needs it every step.");
  info.param("timeout", &Hold<T>::timeout_)
      .defaults_to(0.25)
      .range(0.0, 3600.0)
      .describe(
          "seconds (steps at the config's rate_hz, at least one) that a value is held after "
          "it was last written");
  info.param("activation", &Hold<T>::level_)
      .defaults_to(1.0)
      .range(0.0, 1.0)
      .describe("the activation level requested while holding");
  info.port("from", &Hold<T>::from_)
      .describe("the received value, e.g. an actuator of a dds.Bridge layer");
  info.port("to", &Hold<T>::to_).describe("the actuator written every step while holding");
}

}  // namespace

void register_holds(Registry& registry) {
  register_hold<bool>(registry, "Bool");
  register_hold<std::int64_t>(registry, "Int");
  register_hold<double>(registry, "Double");
  register_hold<Vec2>(registry, "Vec2");
  register_hold<Vec3>(registry, "Vec3");
  register_hold<std::string>(registry, "String");
}

}  // namespace arbiter::dds

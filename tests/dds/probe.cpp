#include "probe.hpp"

#include <time.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "arbiter/init_context.hpp"

namespace arbiter::dds_test {
namespace {

/// In a step N that is a multiple of `every`, writes flag = N odd, count = N, level = N / 2,
/// point = (N, -N), vector = (N, 2N, -0.5), text = "step N" and time = the monotonic clock.
class Stamp final : public Behaviour {
 public:
  void init(BehaviourInitContext&) override { scratch_.reserve(kStringCapacity); }

  double activation(const StepContext& ctx) override {
    return static_cast<std::int64_t>(ctx.step()) % every_ == 0 ? 1.0 : 0.0;
  }

  void execute(ExecuteContext& ctx) override {
    const auto n = static_cast<std::int64_t>(ctx.step());
    const auto x = static_cast<double>(n);
    ctx.write(flag_, n % 2 == 1);
    ctx.write(count_, n);
    ctx.write(level_, x / 2.0);
    ctx.write(point_, Vec2{x, -x});
    ctx.write(vector_, Vec3{x, 2.0 * x, -0.5});
    char text[32];
    std::snprintf(text, sizeof text, "step %lld", static_cast<long long>(n));
    scratch_.assign(text);  // within the reserved capacity: no allocation
    ctx.write(text_, scratch_);
    ctx.write(time_, monotonic_seconds());
  }

 private:
  friend void dds_test::register_probe(Registry& registry);

  std::int64_t every_ = 1;
  Output<bool> flag_;
  Output<std::int64_t> count_;
  Output<double> level_;
  Output<Vec2> point_;
  Output<Vec3> vector_;
  Output<std::string> text_;
  Output<double> time_;
  std::string scratch_;
};

}  // namespace

double monotonic_seconds() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

void register_probe(Registry& registry) {
  auto& info = registry.add_behaviour<Stamp>("probe.Stamp")
                   .describe("Writes values of every type, derived from the step number.");
  info.param("every", &Stamp::every_)
      .defaults_to(1)
      .at_least(1)
      .describe("active (and writing) only in steps that are a multiple of this");
  info.port("flag", &Stamp::flag_).make_optional().describe("step is odd");
  info.port("count", &Stamp::count_).make_optional().describe("the step");
  info.port("level", &Stamp::level_).make_optional().describe("step / 2");
  info.port("point", &Stamp::point_).make_optional().describe("(step, -step)");
  info.port("vector", &Stamp::vector_).make_optional().describe("(step, 2 step, -0.5)");
  info.port("text", &Stamp::text_).make_optional().describe("'step N'");
  info.port("time", &Stamp::time_).make_optional().describe("the monotonic clock (s)");
}

}  // namespace arbiter::dds_test

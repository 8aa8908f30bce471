// A plugin that works: test_good.Constant requests its `level` and writes its `value` to `out`;
// test_good.Faulty is the same until its `throw_at` step, where execute() throws (a buggy
// behaviour as `arbiter run` meets it).

#include <cstdint>
#include <stdexcept>

#include "arbiter/init_context.hpp"
#include "arbiter/plugin.hpp"

namespace {

class Constant final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext&) override { return level_; }
  void execute(arbiter::ExecuteContext& ctx) override { ctx.write(out_, value_); }

 private:
  friend void register_classes(arbiter::Registry& registry);
  double level_ = 0.0;
  double value_ = 0.0;
  arbiter::Output<double> out_;
};

class Faulty final : public arbiter::Behaviour {
 public:
  double activation(const arbiter::StepContext&) override { return 1.0; }
  void execute(arbiter::ExecuteContext&) override {
    if (++executions_ == throw_at_) throw std::runtime_error("sensor cable unplugged");
  }

 private:
  friend void register_classes(arbiter::Registry& registry);
  std::int64_t throw_at_ = 0;
  std::int64_t executions_ = 0;
};

void register_classes(arbiter::Registry& registry) {
  auto& constant = registry.add_behaviour<Constant>("test_good.Constant");
  constant.param("level", &Constant::level_).defaults_to(1.0).range(0.0, 1.0);
  constant.param("value", &Constant::value_).defaults_to(0.0);
  constant.port("out", &Constant::out_);
  registry.add_behaviour<Faulty>("test_good.Faulty")
      .param("throw_at", &Faulty::throw_at_)
      .defaults_to(1)
      .range(1, 1000000);
}

}  // namespace

ARBITER_PLUGIN(registry) {
  register_classes(registry);
}

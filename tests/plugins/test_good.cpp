// A plugin that works: test_good.Constant requests its `level` and writes its `value` to `out`.

#include "arbiter/init_context.hpp"
#include "arbiter/plugin.hpp"

namespace {

class Constant final : public arbiter::Behaviour {
 public:
  void init(arbiter::InitContext& ctx) override {
    level_ = ctx.param<double>("level");
    value_ = ctx.param<double>("value");
    out_ = ctx.output<double>("out");
  }
  double activation(const arbiter::StepContext&) override { return level_; }
  void execute(arbiter::ExecuteContext& ctx) override { ctx.write(out_, value_); }

 private:
  double level_ = 0.0;
  double value_ = 0.0;
  arbiter::Output<double> out_;
};

}  // namespace

ARBITER_PLUGIN(registry) {
  auto& constant = registry.add_behaviour<Constant>("test_good.Constant");
  constant.param("level", arbiter::ParamKind::kDouble).fallback(1.0).range(0.0, 1.0);
  constant.param("value", arbiter::ParamKind::kDouble).fallback(0.0);
  constant.output<double>("out");
}

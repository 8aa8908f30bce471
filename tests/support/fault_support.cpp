#include "fault_support.hpp"

#include <limits>

namespace arbiter::test {

double number_of(const std::string& text) {
  if (text == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (text == "inf") return std::numeric_limits<double>::infinity();
  if (text == "-inf") return -std::numeric_limits<double>::infinity();
  return std::stod(text);
}

Registry make_fault_registry() {
  Registry r = make_test_registry();
  r.set_origin("robustness_test");
  constexpr std::int64_t kForever = std::numeric_limits<std::int64_t>::max();
  auto& faulty = r.add_behaviour<Faulty>("robust.Faulty");
  faulty.param<std::string>("callback")
      .defaults_to(std::string("activation"))
      .one_of({"init", "update", "activation", "execute", "inhibited"});
  faulty.param<std::int64_t>("from").defaults_to(1);
  faulty.param<std::int64_t>("until").defaults_to(kForever);
  faulty.param<double>("level").defaults_to(1.0);
  faulty.param<double>("value").defaults_to(0.0);
  faulty.output<double>("out").make_optional();
  auto& odd = r.add_behaviour<Odd>("robust.Odd");
  odd.param<std::string>("level").defaults_to(std::string("1"));
  odd.param<std::string>("value").defaults_to(std::string("0"));
  odd.param<std::int64_t>("from").defaults_to(1);
  odd.output<double>("out").make_optional();
  odd.output<Vec2>("out2").make_optional();
  odd.output<Vec3>("out3").make_optional();
  auto& feed = r.add_interface<FaultyFeed>("robust.FaultyFeed");
  feed.param<std::string>("callback").defaults_to(std::string("input"));
  feed.param<std::int64_t>("from").defaults_to(1);
  feed.param<std::int64_t>("until").defaults_to(kForever);
  feed.output<double>("out").make_optional();
  auto& state = add_state_class<FaultyState>(r, "robust.FaultyState");
  state.param<std::string>("callback")
      .defaults_to(std::string("execute"))
      .one_of({"init", "activate", "execute", "deactivate"});
  return r;
}

const Registry& fault_registry() {
  static const Registry instance = make_fault_registry();
  return instance;
}

/// A logger whose lines ("error: ..." / "warning: ...") the test can read.
Manager make(const std::string& yaml, Log& log) {
  return Manager(compile_text(yaml, fault_registry()), log.logger);
}

double actuator(const Manager& manager, const std::string& name) {
  return manager.actuator<double>(*manager.program().find_actuator(name));
}

bool written(const Manager& manager, const std::string& name) {
  return manager.actuator_written(*manager.program().find_actuator(name));
}

}  // namespace arbiter::test

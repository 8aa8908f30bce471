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
  faulty.param("callback", &Faulty::callback)
      .defaults_to(std::string("activation"))
      .one_of({"init", "update", "activation", "execute", "inhibited"});
  faulty.param("from", &Faulty::from_param).defaults_to(1);
  faulty.param("until", &Faulty::until_param).defaults_to(kForever);
  faulty.param("level", &Faulty::level).defaults_to(1.0);
  faulty.param("value", &Faulty::value).defaults_to(0.0);
  faulty.port("out", &Faulty::out).make_optional();
  auto& odd = r.add_behaviour<Odd>("robust.Odd");
  odd.param("level", &Odd::level_text).defaults_to(std::string("1"));
  odd.param("value", &Odd::value_text).defaults_to(std::string("0"));
  odd.param("from", &Odd::from_param).defaults_to(1);
  odd.port("out", &Odd::out).make_optional();
  odd.port("out2", &Odd::out2).make_optional();
  odd.port("out3", &Odd::out3).make_optional();
  auto& feed = r.add_interface<FaultyFeed>("robust.FaultyFeed");
  feed.param("callback", &FaultyFeed::callback).defaults_to(std::string("input"));
  feed.param("from", &FaultyFeed::from_param).defaults_to(1);
  feed.param("until", &FaultyFeed::until_param).defaults_to(kForever);
  feed.port("out", &FaultyFeed::out).make_optional();
  auto& state = add_state_class<FaultyState>(r, "robust.FaultyState");
  state.param("callback", &FaultyState::callback_param)
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

#include "arbiter/run_state.hpp"

#include <algorithm>
#include <string>
#include <typeinfo>

namespace arbiter {

namespace {

// How many doubles of a value a non-finite check looks at: double, vec2 and vec3 values.
std::uint8_t finite_components(const ValueType& type) {
  if (type.cpp_type == nullptr) return 0;
  if (*type.cpp_type == typeid(double)) return 1;
  if (*type.cpp_type == typeid(Vec2)) return 2;
  if (*type.cpp_type == typeid(Vec3)) return 3;
  return 0;
}

std::size_t round_up(std::size_t n, std::size_t to) {
  return (n + to - 1) / to * to;
}

}  // namespace

TrackedLayout::TrackedLayout(std::size_t behaviours, std::size_t actuators,
                             std::size_t value_bytes) {
  bytes[kRequested] = behaviours * sizeof(double);
  bytes[kActivation] = behaviours * sizeof(double);
  bytes[kActive] = behaviours * sizeof(char);
  bytes[kWritten] = actuators * sizeof(bool);
  bytes[kValues] = value_bytes;
  std::size_t end = 0;
  for (std::size_t part = 0; part < kParts; ++part) {
    // The values keep the alignment the program's offsets assume.
    at[part] = round_up(end, part == kValues ? kAlignment : alignof(double));
    end = at[part] + bytes[part];
  }
  total = end;
  allocated = round_up(total, kLine);
}

ValueBuffer::ValueBuffer(std::size_t bytes)
    : bytes_(std::make_unique<std::byte[]>(std::max<std::size_t>(bytes, 1))) {}

ValueBuffer::~ValueBuffer() {
  for (const auto& [type, offset] : constructed_) type->destroy(at(offset));
}

void ValueBuffer::construct(const ValueType& type, std::uint32_t offset) {
  // Reserved first: once constructed, the value is recorded without a throw in between.
  if (constructed_.size() == constructed_.capacity()) {
    constructed_.reserve(2 * constructed_.size() + 8);
  }
  type.construct(at(offset));
  constructed_.emplace_back(&type, offset);
}

RunState::RunState(const Program& program)
    : tracked_layout(program.behaviours.size(), program.actuators.size(), program.value_bytes),
      tracked(tracked_layout.allocated) {
  const std::size_t behaviours = program.behaviours.size();
  const std::size_t actuators = program.actuators.size();
  const std::size_t slots = program.slots.size();
  const std::size_t callers = behaviours + program.layers.size();
  const auto part = [&](TrackedLayout::Part p) { return tracked.at(tracked_layout.at[p]); };
  // Zeroed: the levels start at 0.0, the flags false, padding as the snapshots copy it.
  requested = reinterpret_cast<double*>(part(TrackedLayout::kRequested));
  activation = reinterpret_cast<double*>(part(TrackedLayout::kActivation));
  active = reinterpret_cast<char*>(part(TrackedLayout::kActive));
  actuator_written = reinterpret_cast<bool*>(part(TrackedLayout::kWritten));
  values = part(TrackedLayout::kValues);
  slot_written = std::make_unique<bool[]>(std::max<std::size_t>(slots, 1));
  factors.assign(2 * behaviours, 1.0);
  instances.reserve(behaviours);
  for (const auto& behaviour : program.behaviours) instances.push_back(behaviour.instance.get());
  nan_reported.assign(behaviours, 0);
  exception_reported.assign(callers, 0);
  faulted_step.assign(callers, 0);
  disabled.assign(callers, 0);
  suspended.reserve(behaviours);
  finite_components.resize(slots);
  for (std::size_t s = 0; s < slots; ++s) {
    finite_components[s] = arbiter::finite_components(*program.slot_types[s]);
  }
  non_finite_reported.assign(slots, 0);
  mean_values.assign(program.max_writers, nullptr);
  mean_weights.assign(program.max_writers, 0.0);
  const auto values_at = static_cast<std::uint32_t>(tracked_layout.at[TrackedLayout::kValues]);
  for (const auto& actuator : program.actuators) {
    tracked.construct(*actuator.type, values_at + actuator.offset);
    if (actuator.default_value) {
      std::string expected;  // validated at load
      actuator.type->from_node(*actuator.default_value, values + actuator.offset, expected);
    }
  }
  for (std::size_t s = 0; s < slots; ++s) {
    tracked.construct(*program.slot_types[s], values_at + program.slot_offsets[s]);
  }
  safe_values.resize(actuators);
  for (std::size_t a = 0; a < actuators; ++a) {
    const auto& actuator = program.actuators[a];
    if (!actuator.safe_value) continue;
    safe_values[a] = ValueBox(*actuator.type);
    std::string expected;
    actuator.type->from_node(*actuator.safe_value, safe_values[a].data(), expected);
  }
}

}  // namespace arbiter

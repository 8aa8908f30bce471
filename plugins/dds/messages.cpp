#include "messages.hpp"

#include <cstdint>
#include <cstring>
#include <string>

#include "arbiter/value.hpp"
#include "ros_types.h"

namespace arbiter::dds {
namespace {

static_assert(sizeof(geometry_msgs_msg_dds__Vector3_) <= sizeof(SampleStorage));
static_assert(sizeof(geometry_msgs_msg_dds__Point_) <= sizeof(SampleStorage));
static_assert(sizeof(std_msgs_msg_dds__String_) <= sizeof(SampleStorage));
static_assert(alignof(geometry_msgs_msg_dds__Vector3_) <= alignof(SampleStorage));

struct MessageInfo {
  Message message;
  const char* ros_name;
  const dds_topic_descriptor_t* descriptor;
};

const MessageInfo kMessages[] = {
    {Message::kBool, "std_msgs/msg/Bool", &std_msgs_msg_dds__Bool__desc},
    {Message::kInt64, "std_msgs/msg/Int64", &std_msgs_msg_dds__Int64__desc},
    {Message::kFloat64, "std_msgs/msg/Float64", &std_msgs_msg_dds__Float64__desc},
    {Message::kString, "std_msgs/msg/String", &std_msgs_msg_dds__String__desc},
    {Message::kVector3, "geometry_msgs/msg/Vector3", &geometry_msgs_msg_dds__Vector3__desc},
    {Message::kPoint, "geometry_msgs/msg/Point", &geometry_msgs_msg_dds__Point__desc},
};

const MessageInfo& info(Message message) {
  return kMessages[static_cast<std::size_t>(message)];
}

// Vector3_ and Point_ have the same members; both are written through one of them.
using Xyz = geometry_msgs_msg_dds__Vector3_;
static_assert(sizeof(Xyz) == sizeof(geometry_msgs_msg_dds__Point_));

}  // namespace

std::optional<ValueKind> kind_of(std::string_view value_type) {
  if (value_type == "bool") return ValueKind::kBool;
  if (value_type == "int") return ValueKind::kInt;
  if (value_type == "double") return ValueKind::kDouble;
  if (value_type == "vec2") return ValueKind::kVec2;
  if (value_type == "vec3") return ValueKind::kVec3;
  if (value_type == "string") return ValueKind::kString;
  return std::nullopt;
}

const char* carried_types() {
  return "bool, int, double, vec2, vec3, string";
}

Message default_message(ValueKind kind) {
  switch (kind) {
    case ValueKind::kBool:
      return Message::kBool;
    case ValueKind::kInt:
      return Message::kInt64;
    case ValueKind::kDouble:
      return Message::kFloat64;
    case ValueKind::kVec2:
      return Message::kPoint;
    case ValueKind::kVec3:
      return Message::kVector3;
    case ValueKind::kString:
      return Message::kString;
  }
  return Message::kFloat64;
}

bool carries(Message message, ValueKind kind) {
  if (kind == ValueKind::kVec2 || kind == ValueKind::kVec3) {
    return message == Message::kVector3 || message == Message::kPoint;
  }
  return message == default_message(kind);
}

std::vector<std::string> messages_for(ValueKind kind) {
  std::vector<std::string> names;
  for (const auto& candidate : kMessages) {
    if (carries(candidate.message, kind)) names.emplace_back(candidate.ros_name);
  }
  return names;
}

const char* ros_name(Message message) {
  return info(message).ros_name;
}

std::optional<Message> message_named(std::string_view ros_name) {
  for (const auto& candidate : kMessages) {
    if (ros_name == candidate.ros_name) return candidate.message;
  }
  return std::nullopt;
}

const dds_topic_descriptor_t& descriptor(Message message) {
  return *info(message).descriptor;
}

void to_sample(ValueKind kind, const void* value, void* sample) {
  switch (kind) {
    case ValueKind::kBool:
      static_cast<std_msgs_msg_dds__Bool_*>(sample)->data = *static_cast<const bool*>(value);
      return;
    case ValueKind::kInt:
      static_cast<std_msgs_msg_dds__Int64_*>(sample)->data =
          *static_cast<const std::int64_t*>(value);
      return;
    case ValueKind::kDouble:
      static_cast<std_msgs_msg_dds__Float64_*>(sample)->data = *static_cast<const double*>(value);
      return;
    case ValueKind::kVec2: {
      const auto& v = *static_cast<const Vec2*>(value);
      *static_cast<Xyz*>(sample) = {v.x, v.y, 0.0};
      return;
    }
    case ValueKind::kVec3: {
      const auto& v = *static_cast<const Vec3*>(value);
      *static_cast<Xyz*>(sample) = {v.x, v.y, v.z};
      return;
    }
    case ValueKind::kString:
      // dds_write() only reads the sample, so it may point into the engine's string.
      static_cast<std_msgs_msg_dds__String_*>(sample)->data =
          const_cast<char*>(static_cast<const std::string*>(value)->c_str());
      return;
  }
}

void from_sample(const void* sample, ValueKind kind, void* value) {
  switch (kind) {
    case ValueKind::kBool:
      *static_cast<bool*>(value) = static_cast<const std_msgs_msg_dds__Bool_*>(sample)->data;
      return;
    case ValueKind::kInt:
      *static_cast<std::int64_t*>(value) =
          static_cast<const std_msgs_msg_dds__Int64_*>(sample)->data;
      return;
    case ValueKind::kDouble:
      *static_cast<double*>(value) = static_cast<const std_msgs_msg_dds__Float64_*>(sample)->data;
      return;
    case ValueKind::kVec2: {
      const auto& xyz = *static_cast<const Xyz*>(sample);
      *static_cast<Vec2*>(value) = {xyz.x, xyz.y};
      return;
    }
    case ValueKind::kVec3: {
      const auto& xyz = *static_cast<const Xyz*>(sample);
      *static_cast<Vec3*>(value) = {xyz.x, xyz.y, xyz.z};
      return;
    }
    case ValueKind::kString: {
      const char* text = static_cast<const std_msgs_msg_dds__String_*>(sample)->data;
      static_cast<std::string*>(value)->assign(text != nullptr ? text : "");
      return;
    }
  }
}

}  // namespace arbiter::dds

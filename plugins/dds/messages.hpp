#pragma once
// How the engine's value types travel over DDS: each as the DDS form of a ROS 2 message
// (std_msgs, geometry_msgs), generated from ros_types.idl by Cyclone DDS's idlc. See docs/dds.md
// for the table.

#include <dds/dds.h>

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace arbiter::dds {

/// The engine value types the bridge carries.
enum class ValueKind { kBool, kInt, kDouble, kVec2, kVec3, kString };

/// The messages values travel as.
enum class Message { kBool, kInt64, kFloat64, kString, kVector3, kPoint };

/// The kind of an engine value type, by its name ("vec3"); nullopt for one the bridge cannot carry.
std::optional<ValueKind> kind_of(std::string_view value_type);
/// The names of the value types the bridge carries, for messages.
const char* carried_types();

/// The message a value of `kind` travels as unless the config names another.
Message default_message(ValueKind kind);
/// Whether values of `kind` can travel as `message` (vectors as Vector3 or Point).
bool carries(Message message, ValueKind kind);
/// The messages `kind` can travel as, by ROS 2 name, for messages.
std::vector<std::string> messages_for(ValueKind kind);

/// The ROS 2 name, "geometry_msgs/msg/Point", and the message of such a name.
const char* ros_name(Message message);
std::optional<Message> message_named(std::string_view ros_name);

/// The idlc-generated descriptor; its type name is the DDS one, "geometry_msgs::msg::dds_::Point_".
const dds_topic_descriptor_t& descriptor(Message message);

/// Storage for one sample of any message: every generated struct fits.
struct alignas(8) SampleStorage {
  unsigned char bytes[32];
};

/// Copies an engine value of `kind` (a bool, std::int64_t, double, Vec2, Vec3 or std::string)
/// into a sample of its message. A String_ sample points into the string: it is only valid while
/// the value is unchanged. A Vec2 sent as a 3-D message has z = 0.
void to_sample(ValueKind kind, const void* value, void* sample);
/// Copies a received sample into an engine value of `kind` (a Vec2 ignores z). Does not allocate
/// for strings within the value's reserved capacity.
void from_sample(const void* sample, ValueKind kind, void* value);

}  // namespace arbiter::dds

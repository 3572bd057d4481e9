// The topics visvol uses: names, types and QoS, in one table.
//
// ROS 2 maps topic /visvol/path to DDS topic rt/visvol/path; with a namespace
// ("console_a") every name gains it as ROS would: rt/console_a/visvol/path, so
// several consoles share a network (and concurrent tests a domain) without
// seeing each other.
//
//   topic (after rt/<ns>/)       type                                      QoS
//   visvol/path                  nav_msgs::msg::dds_::Path_                latest
//   visvol/path_update           visvol_msgs::msg::dds_::PathUpdate_       latest
//   visvol/thumbnail/compressed  sensor_msgs::msg::dds_::CompressedImage_  latest
//   visvol/terrain               visvol_msgs::msg::dds_::TerrainInfo_      latest
//   visvol/terrain_catalogue     visvol_msgs::msg::dds_::TerrainCatalogue_ latest
//   visvol/device_status         visvol_msgs::msg::dds_::DeviceStatus_     latest
//   visvol/health                visvol_msgs::msg::dds_::LoopHealth_       telemetry
//   visvol/command               visvol_msgs::msg::dds_::Command_          command
//   visvol/command_ack           visvol_msgs::msg::dds_::CommandAck_       ack
//
//   latest     reliable, transient-local, keep-last 1 (a late joiner gets the newest)
//   telemetry  best effort, volatile, keep-last 1
//   command    reliable, volatile, keep-all; the console's reader queues at most 256
//   ack        reliable, transient-local; the writer keeps the last 1024 (a late
//              joiner gets them), readers keep all
//
// Readers request no more than writers offer: a volatile or best-effort reader
// (RViz's default) matches the path writer; a reliable reader does not match
// the best-effort health writer (ROS: use the sensor-data QoS profile).
//
// Thread-safety: pure functions and constant tables. Cost: topic_name()
// allocates its string; the QoS makers allocate a dds_qos_t.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "base/status.hpp"

namespace visvol::dds {

enum class Topic : int {
  path,
  path_update,
  thumbnail,
  terrain,
  device_status,
  health,
  command,
  command_ack,
  terrain_catalogue,
};
inline constexpr int kTopicCount = 9;

// The world frame of every header unless the console configures another.
inline constexpr const char* kDefaultFrameId = "visvol_world";

// The command reader's bound on commands waiting to be validated; past it the
// reliable protocol holds further commands back at their senders.
inline constexpr std::int32_t kCommandReaderMaxQueued = 256;
// Acknowledgements the writer keeps for retransmission (a flood's worth).
inline constexpr std::int32_t kAckHistoryDepth = 1024;

// "visvol/path" and friends: the name below rt/<namespace>/.
const char* relative_name(Topic topic);
// "nav_msgs::msg::dds_::Path_" and friends.
const char* type_name(Topic topic);
// One line of the table above (for --help and logs).
std::string describe(Topic topic);
// The generated type descriptor of the topic.
const dds_topic_descriptor_t& descriptor(Topic topic);

// A ROS-style namespace: empty, or segments of [A-Za-z_][A-Za-z0-9_]* joined
// by '/', at most 100 characters. A leading '/' is allowed and dropped.
Status validate_namespace(std::string_view ns);
// The DDS topic name: "rt/" + namespace + "/" + relative name. The namespace
// must be valid (validate_namespace).
std::string topic_name(std::string_view ns, Topic topic);

struct QosDeleter {
  void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

// The QoS of the table for the writers and readers of a topic.
QosPtr writer_qos(Topic topic);
QosPtr reader_qos(Topic topic);

// Seconds to a Cyclone duration, clamped to [0, 1 day].
dds_duration_t to_duration(double seconds);

}  // namespace visvol::dds

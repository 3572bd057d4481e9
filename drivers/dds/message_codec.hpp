// Conversion of the plain samples (msg/samples.hpp) into the DDS messages visvol
// publishes, into storage reserved once, and back for subscribers.
//
// Each *Message class owns a generated message and every buffer its pointers
// refer to, sized for the capacities of msg/samples.hpp: fill() copies a sample in
// with no allocation and returns the message to pass to Writer::write. The
// message stays valid until the next fill() (ThumbnailMessage also points at
// the sample's PNG bytes: keep the sample until the write returns).
//
// fill() checks structure (counts within capacity, terminated text), not
// values: a planner's NaN is published as it is, so that it shows.
//
// Thread-safety: one thread per object. Cost: O(vertices) copies. Not for the
// real-time thread (it is cheap, but its output feeds dds_write).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "base/status.hpp"
#include "msg/samples.hpp"
#include "ros2.h"
#include "visvol_msgs.h"

namespace visvol::dds {

// Unix-epoch nanoseconds to ROS time and back. Seconds outside int32 are
// clamped (ROS time ends in 2038).
builtin_interfaces_msg_dds__Time_ to_ros_time(std::int64_t stamp_ns);
std::int64_t from_ros_time(const builtin_interfaces_msg_dds__Time_& time);

// The path as nav_msgs/Path (for RViz and ROS 2 nodes) and as visvol's
// PathUpdate (the same vertices plus visibility, clearance and the measure).
// Both carry the same header: the sample's stamp and the frame id.
class PathMessages {
 public:
  explicit PathMessages(std::string frame_id);
  PathMessages(const PathMessages&) = delete;
  PathMessages& operator=(const PathMessages&) = delete;

  // invalid_argument when vertex_count exceeds kMaxPathVertices.
  Status fill(const msg::PathSample& sample);
  const nav_msgs_msg_dds__Path_& path() const { return path_; }
  const visvol_msgs_msg_dds__PathUpdate_& update() const { return update_; }

 private:
  std::string frame_id_;
  char pack_id_[msg::kPackIdCapacity] = {};
  nav_msgs_msg_dds__Path_ path_{};
  visvol_msgs_msg_dds__PathUpdate_ update_{};
  geometry_msgs_msg_dds__PoseStamped_ poses_[msg::kMaxPathVertices];
  geometry_msgs_msg_dds__Point_ positions_[msg::kMaxPathVertices];
  double visibility_[msg::kMaxPathVertices];
  double clearance_m_[msg::kMaxPathVertices];
};

// Counters the DDS layer adds to each health report.
struct LayerCounters {
  std::uint64_t commands_accepted = 0;
  std::uint64_t commands_rejected = 0;
  std::uint64_t publish_errors = 0;
};

class HealthMessage {
 public:
  explicit HealthMessage(std::string frame_id);
  HealthMessage(const HealthMessage&) = delete;
  HealthMessage& operator=(const HealthMessage&) = delete;
  Status fill(const msg::HealthSample& sample, const LayerCounters& counters);
  const visvol_msgs_msg_dds__LoopHealth_& message() const { return msg_; }

 private:
  std::string frame_id_;
  char reason_[msg::kReasonCapacity] = {};
  visvol_msgs_msg_dds__LoopHealth_ msg_{};
};

class DeviceStatusMessage {
 public:
  explicit DeviceStatusMessage(std::string frame_id);
  DeviceStatusMessage(const DeviceStatusMessage&) = delete;
  DeviceStatusMessage& operator=(const DeviceStatusMessage&) = delete;
  Status fill(const msg::DeviceStatusSample& sample);
  const visvol_msgs_msg_dds__DeviceStatus_& message() const { return msg_; }

 private:
  std::string frame_id_;
  char device_[msg::kDeviceNameCapacity] = {};
  visvol_msgs_msg_dds__DeviceStatus_ msg_{};
};

// sensor_msgs/CompressedImage with format "png".
class ThumbnailMessage {
 public:
  explicit ThumbnailMessage(std::string frame_id);
  ThumbnailMessage(const ThumbnailMessage&) = delete;
  ThumbnailMessage& operator=(const ThumbnailMessage&) = delete;
  // invalid_argument when png_size_bytes is 0, above kMaxThumbnailBytes, or
  // the bytes do not start with the PNG signature. Points at sample.png.
  Status fill(const msg::ThumbnailSample& sample);
  const sensor_msgs_msg_dds__CompressedImage_& message() const { return msg_; }

 private:
  std::string frame_id_;
  std::string format_ = "png";
  sensor_msgs_msg_dds__CompressedImage_ msg_{};
};

class TerrainMessage {
 public:
  explicit TerrainMessage(std::string frame_id);
  TerrainMessage(const TerrainMessage&) = delete;
  TerrainMessage& operator=(const TerrainMessage&) = delete;
  Status fill(const msg::TerrainInfo& info);
  const visvol_msgs_msg_dds__TerrainInfo_& message() const { return msg_; }

 private:
  std::string frame_id_;
  char pack_id_[msg::kPackIdCapacity] = {};
  char crs_[msg::kCrsCapacity] = {};
  char crs_wkt_[msg::kCrsWktCapacity] = {};
  visvol_msgs_msg_dds__TerrainInfo_ msg_{};
};

// The terrain catalogue; the message's strings and entries point into this
// object (allocated once: a catalogue is some 80 KB).
class CatalogueMessage {
 public:
  explicit CatalogueMessage(std::string frame_id);
  CatalogueMessage(const CatalogueMessage&) = delete;
  CatalogueMessage& operator=(const CatalogueMessage&) = delete;
  // invalid_argument when count exceeds kMaxCatalogueEntries, an entry has no
  // pack id, or its state is not one of CatalogueState's.
  Status fill(const msg::TerrainCatalogue& catalogue);
  const visvol_msgs_msg_dds__TerrainCatalogue_& message() const { return msg_; }

 private:
  std::string frame_id_;
  std::unique_ptr<msg::TerrainCatalogue> text_;  // the strings, NUL-terminated
  std::unique_ptr<visvol_msgs_msg_dds__TerrainCatalogueEntry_[]> entries_;
  visvol_msgs_msg_dds__TerrainCatalogue_ msg_{};
};

// Subscriber side: a received catalogue back into plain data (texts cut to
// their capacities). invalid_argument past kMaxCatalogueEntries or for an
// unknown state.
Status decode_catalogue(const visvol_msgs_msg_dds__TerrainCatalogue_& wire, msg::TerrainCatalogue& out);

// Subscriber side: a received PathUpdate back into a PathSample.
// invalid_argument when it holds more vertices than kMaxPathVertices, its
// three per-vertex sequences differ in length, or a text does not fit.
Status decode_path_update(const visvol_msgs_msg_dds__PathUpdate_& msg, msg::PathSample& out);

}  // namespace visvol::dds

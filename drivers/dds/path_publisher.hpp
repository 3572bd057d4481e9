// Publishes paths, thumbnails and the terrain on their topics (topics.hpp):
// the part shared by the console's publisher thread (live_publisher.hpp) and
// the offline planner (`visvol plan ... --publish`), which calls it directly
// for each improvement and the final path, then waits for delivery:
//
//   auto participant = Participant::create({domain, xml, ns});
//   auto publisher = PathPublisher::create(**participant);
//   (*publisher)->publish(terrain);            // once: pack and CRS
//   (*publisher)->publish(path);               // each improvement, the final one
//   Status s = (*publisher)->wait_for_delivery(5.0);  // before exiting
//
// Every topic is reliable and transient-local with a history of one, so a
// subscriber that joins while the publisher lives gets the latest of each.
//
// Ownership: owns its writers and message buffers; the Participant must
// outlive it. Thread-safety: one thread at a time. Cost: publish() converts
// in place (no allocation of ours) and calls dds_write, which allocates and
// may block up to 50 ms: never from the real-time thread.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "base/status.hpp"
#include "drivers/dds/message_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "msg/samples.hpp"

namespace visvol::dds {

class PathPublisher {
 public:
  // frame_id: the world frame of every header (topics.hpp, kDefaultFrameId).
  static Result<std::unique_ptr<PathPublisher>> create(const Participant& participant,
                                                       const std::string& frame_id = kDefaultFrameId);

  // The path as nav_msgs/Path and as visvol_msgs/PathUpdate.
  Status publish(const msg::PathSample& path);
  // The thumbnail as sensor_msgs/CompressedImage ("png").
  Status publish(const msg::ThumbnailSample& thumbnail);
  // The pack and its CRS.
  Status publish(const msg::TerrainInfo& terrain);

  // Waits until every matched subscriber has acknowledged everything
  // published (reliable delivery), at most timeout_s. A timeout says how many
  // subscribers were matched and that they may have missed the last path.
  Status wait_for_delivery(double timeout_s) const;
  // Waits until `count` subscribers are matched (PathUpdate readers and
  // nav_msgs/Path readers, as ROS 2 nodes take paths, together; an offline
  // planner may want one before it starts), at most timeout_s.
  Status wait_for_subscribers(std::uint32_t count, double timeout_s) const;
  // Subscribers matched now: nav_msgs/Path readers, PathUpdate readers, both.
  std::uint32_t path_subscribers() const;
  std::uint32_t path_update_subscribers() const;
  std::uint32_t subscribers() const { return path_subscribers() + path_update_subscribers(); }

 private:
  PathPublisher(const std::string& frame_id, Writer path, Writer update, Writer thumbnail, Writer terrain);

  Writer path_writer_;
  Writer update_writer_;
  Writer thumbnail_writer_;
  Writer terrain_writer_;
  PathMessages path_;
  ThumbnailMessage thumbnail_;
  TerrainMessage terrain_;
};

}  // namespace visvol::dds

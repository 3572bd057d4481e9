// `visvol plan --publish`: the offline planner's path on DDS while it settles
// (throttled) and once more when it is done, so that a console display or
// `visvol-echo path` shows the rope as it moves. Topics, QoS and message
// types are the console's (drivers/dds/topics.hpp): subscribers cannot tell
// a planner from a console.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "drivers/dds/participant.hpp"
#include "drivers/dds/path_publisher.hpp"
#include "msg/samples.hpp"
#include "rt/rope/path_metrics.hpp"

namespace visvol::cli {

struct PublishOptions {
  std::uint32_t domain_id = 0;
  std::string cyclone_config_path;  // empty: the compiled-in loopback configuration
  std::string topic_namespace;
  double rate_hz = 10.0;  // path updates while the rope settles, at most
  double linger_s = 5.0;  // waiting for subscribers to acknowledge the last path
};
Status validate(const PublishOptions& options);

// Which of n vertices a sample of at most `max` keeps: evenly spaced, both
// ends always. n <= max keeps them all.
std::vector<int> subsample_indices(int n, int max);

// Per-vertex F_p and clearance for a path (the finest level's sampler).
using VertexProbe = std::function<void(const rt::Vec3& v, double& visibility, double& clearance_m)>;

class PlanPublisher {
 public:
  static Result<std::unique_ptr<PlanPublisher>> create(const PublishOptions& options, const msg::TerrainInfo& terrain,
                                                       msg::Objective objective, VertexProbe probe);

  // A path while the rope settles: published when rate_hz allows, else dropped.
  // Errors are counted, not returned: publishing never stops planning.
  void progress(const rt::Vec3* vertices, int count, double f_c);
  // The final path, then waits (up to linger_s) for matched subscribers to
  // acknowledge it. `inside_envelope`: the check found every envelope limit
  // met (sent as such only when no vertex had to be dropped to fit the
  // message). An error says what was not delivered.
  Status finish(const std::vector<rt::Vec3>& vertices, const rt::PathMetrics& metrics, bool converged,
                bool inside_envelope);

  std::uint64_t published() const { return sequence_; }
  std::uint64_t errors() const { return errors_; }
  // matched now: PathUpdate readers and nav_msgs/Path readers (ROS 2 nodes)
  std::uint32_t subscribers() const { return publisher_->subscribers(); }
  std::uint32_t path_subscribers() const { return publisher_->path_subscribers(); }

 private:
  PlanPublisher(const PublishOptions& options, std::unique_ptr<dds::Participant> participant,
                std::unique_ptr<dds::PathPublisher> publisher, const msg::TerrainInfo& terrain,
                msg::Objective objective, VertexProbe probe);
  // min_clearance_m NaN: the lowest of the published vertices.
  Status publish(const rt::Vec3* vertices, int count, double f_c, double length_m, double min_clearance_m,
                 bool converged, bool inside_envelope);

  PublishOptions options_;
  std::unique_ptr<dds::Participant> participant_;
  std::unique_ptr<dds::PathPublisher> publisher_;
  std::unique_ptr<msg::PathSample> sample_;  // 20 KiB: on the heap, reused
  VertexProbe probe_;
  std::chrono::steady_clock::time_point last_{};
  std::uint64_t sequence_ = 0;
  std::uint64_t errors_ = 0;
};

}  // namespace visvol::cli

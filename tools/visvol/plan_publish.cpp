#include "plan_publish.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "drivers/dds/message_codec.hpp"

namespace visvol::cli {

Status validate(const PublishOptions& o) {
  if (o.domain_id > dds::kMaxDomainId) {
    return invalid_argument("--domain: " + std::to_string(o.domain_id) + " is above " +
                            std::to_string(dds::kMaxDomainId));
  }
  if (!(o.rate_hz > 0 && o.rate_hz <= 1000)) {
    return invalid_argument("--publish-hz: must be in (0, 1000] Hz");
  }
  if (!(o.linger_s >= 0 && o.linger_s <= 600)) {
    return invalid_argument("--linger: must be in [0, 600] s");
  }
  return {};
}

std::vector<int> subsample_indices(int n, int max) {
  std::vector<int> out;
  if (n <= 0) return out;
  if (n <= max) {
    for (int i = 0; i < n; ++i) out.push_back(i);
    return out;
  }
  if (max < 2) return {0};
  // rounded even spacing: strictly increasing because (n-1)/(max-1) > 1
  for (int k = 0; k < max; ++k) {
    const double t = static_cast<double>(k) * (n - 1) / (max - 1);
    out.push_back(static_cast<int>(std::lround(t)));
  }
  return out;
}

Result<std::unique_ptr<PlanPublisher>> PlanPublisher::create(const PublishOptions& options,
                                                             const msg::TerrainInfo& terrain, msg::Objective objective,
                                                             VertexProbe probe) {
  VISVOL_RETURN_IF_ERROR(validate(options));
  dds::ParticipantConfig config;
  config.domain_id = options.domain_id;
  config.topic_namespace = options.topic_namespace;
  if (options.cyclone_config_path.empty()) {
    config.cyclone_xml = std::string(dds::loopback_config());
  } else {
    Result<std::string> xml = dds::read_cyclone_config(options.cyclone_config_path);
    if (!xml.ok()) return xml.status();
    config.cyclone_xml = std::move(*xml);
  }
  Result<std::unique_ptr<dds::Participant>> participant = dds::Participant::create(config);
  if (!participant.ok()) return participant.status();
  Result<std::unique_ptr<dds::PathPublisher>> publisher = dds::PathPublisher::create(**participant);
  if (!publisher.ok()) return publisher.status();
  VISVOL_RETURN_IF_ERROR((*publisher)->publish(terrain));
  return std::unique_ptr<PlanPublisher>(
      new PlanPublisher(options, std::move(*participant), std::move(*publisher), terrain, objective, std::move(probe)));
}

PlanPublisher::PlanPublisher(const PublishOptions& options, std::unique_ptr<dds::Participant> participant,
                             std::unique_ptr<dds::PathPublisher> publisher, const msg::TerrainInfo& terrain,
                             msg::Objective objective, VertexProbe probe)
    : options_(options),
      participant_(std::move(participant)),
      publisher_(std::move(publisher)),
      sample_(std::make_unique<msg::PathSample>()),
      probe_(std::move(probe)) {
  std::memcpy(sample_->pack_id, terrain.pack_id, sizeof sample_->pack_id);
  sample_->objective = objective;
}

void PlanPublisher::progress(const rt::Vec3* vertices, int count, double f_c) {
  const auto now = std::chrono::steady_clock::now();
  if (sequence_ > 0 && std::chrono::duration<double>(now - last_).count() < 1.0 / options_.rate_hz) return;
  last_ = now;
  double length_m = 0;
  for (int i = 1; i < count; ++i) length_m += (vertices[i] - vertices[i - 1]).norm();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // the rope as it settles, not fitted: not said to be inside the envelope
  if (!publish(vertices, count, f_c, length_m, nan, false, false).ok()) ++errors_;
}

Status PlanPublisher::finish(const std::vector<rt::Vec3>& vertices, const rt::PathMetrics& metrics, bool converged,
                             bool inside_envelope) {
  VISVOL_RETURN_IF_ERROR(publish(vertices.data(), static_cast<int>(vertices.size()), metrics.fc, metrics.length_m,
                                 metrics.min_clearance_m, converged, inside_envelope));
  return publisher_->wait_for_delivery(options_.linger_s);
}

Status PlanPublisher::publish(const rt::Vec3* vertices, int count, double f_c, double length_m, double min_clearance_m,
                              bool converged, bool inside_envelope) {
  msg::PathSample& s = *sample_;
  s.sequence = ++sequence_;
  s.stamp_ns = msg::now_stamp_ns();
  s.converged = converged;
  // thinned to fit the message, the straight legs between kept vertices are unchecked
  s.inside_envelope = inside_envelope && count <= static_cast<int>(msg::kMaxPathVertices);
  s.f_c = f_c;
  s.length_m = length_m;
  s.min_clearance_m = std::numeric_limits<double>::infinity();
  const std::vector<int> keep = subsample_indices(count, static_cast<int>(msg::kMaxPathVertices));
  s.vertex_count = static_cast<std::uint32_t>(keep.size());
  for (std::size_t k = 0; k < keep.size(); ++k) {
    const rt::Vec3& v = vertices[keep[k]];
    msg::PathVertex& out = s.vertices[k];
    out.position = {v.x(), v.y(), v.z()};
    probe_(v, out.visibility, out.clearance_m);
    s.min_clearance_m = std::min(s.min_clearance_m, out.clearance_m);
  }
  // the planner's own figure samples between vertices too
  if (!std::isnan(min_clearance_m)) s.min_clearance_m = min_clearance_m;
  return publisher_->publish(s);
}

}  // namespace visvol::cli

// The executive's reports: what a tick hands to other threads (the path, the device's status, the rope's
// box to the tile pager). Loop thread (real-time rules: no allocation, no lock, no logging, no blocking).
#include "rt/exec/executive.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rt/exec/executive_detail.hpp"

namespace visvol::rt {

using detail::finite_rope;

namespace {

msg::DeviceState device_state_of(HapticState s, bool forces) {
  switch (s) {
    case HapticState::boot: return msg::DeviceState::disconnected;
    case HapticState::pre_operational: return msg::DeviceState::idle;
    case HapticState::operational: return forces ? msg::DeviceState::active : msg::DeviceState::idle;
    case HapticState::fault: return msg::DeviceState::fault;
  }
  return msg::DeviceState::unknown;
}

}  // namespace

void Executive::hand_off_path(std::int64_t stamp_ns) {
  if (outputs_.path == nullptr && outputs_.path_render == nullptr && outputs_.limited_path == nullptr) return;
  if (!finite_rope(*rope_)) return;  // a rope that could not be recovered is not published
  msg::PathSample& p = *path_sample_;
  const storage::ResidentSampler& s = forces_->sampler();
  p.sequence = ++path_sequence_;
  p.stamp_ns = stamp_ns;
  std::memcpy(p.pack_id, config_.pack_id, sizeof p.pack_id);
  p.objective = objective_ == Objective::show ? msg::Objective::show : msg::Objective::hide;
  p.converged = counters_.converged;
  p.inside_envelope = false;  // the rope's own path: the flyable-path thread fits it
  p.f_c = counters_.fc;
  p.length_m = rope_->length_m();
  p.mode = mode_;
  p.spool_paid_out_m = mode_ == msg::InteractionMode::spool ? counters_.spool_paid_out_m : 0.0;
  const int count = rope_->segments() + 1;
  const int keep = std::min(count, static_cast<int>(msg::kMaxPathVertices));
  const Vec3* v = rope_->vertices();
  double lowest = INFINITY;
  for (int k = 0; k < keep; ++k) {
    // evenly spaced, both ends kept
    const int i = keep == count ? k : static_cast<int>(std::lround(static_cast<double>(k) * (count - 1) / (keep - 1)));
    const Vec3& x = v[i];
    msg::PathVertex& out = p.vertices[k];
    out.position = {x.x(), x.y(), x.z()};
    out.visibility = s.visibility(x.x(), x.y(), x.z());
    out.clearance_m = x.z() - s.height(x.x(), x.y());
    lowest = std::min(lowest, out.clearance_m);
  }
  p.vertex_count = static_cast<std::uint32_t>(keep);
  p.min_clearance_m = lowest;
  if (outputs_.limited_path != nullptr) {
    LimitedPath& l = outputs_.limited_path->back();
    std::memcpy(&l.path, &p, sizeof p);
    l.limits.gains = forces_->gains();
    l.limits.observers = in_force_ != nullptr ? in_force_->request : HullRequest{};
    outputs_.limited_path->publish();
  }
  for (LatestValue<msg::PathSample>* sink : {outputs_.path, outputs_.path_render}) {
    if (sink == nullptr) continue;
    std::memcpy(&sink->back(), &p, sizeof p);
    sink->publish();
  }
  ++counters_.paths;
}

void Executive::hand_off_device(std::int64_t stamp_ns) {
  if (outputs_.device == nullptr || device_ == nullptr) return;
  msg::DeviceStatusSample& d = outputs_.device->back();
  d.sequence = ++device_sequence_;
  d.stamp_ns = stamp_ns;
  msg::copy_text(d.device, "haptic");
  const HapticHealth health = device_->health();
  d.state = device_state_of(health.state, out_.forces_enabled);
  d.fault_bits = health.fault_bits;
  d.motor_temperature_c = health.motor_temperature_c;
  const HapticSample& sample = device_->sample();
  d.last_position_age_ms =
      sample.timestamp_ns > 0 ? static_cast<double>(device_now_ns_ - sample.timestamp_ns) * 1e-6 : INFINITY;
  d.can_rx_frames = health.rx_frames;
  d.can_tx_frames = health.tx_frames;
  d.can_errors = health.errors;
  d.bus_off_count = static_cast<std::uint32_t>(health.bus_off_count);
  outputs_.device->publish();
}

void Executive::hand_off_focus() {
  const Vec3* v = rope_->vertices();
  storage::WorldBox b{INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (int i = 0; i <= rope_->segments(); ++i) {
    b.x0_m = std::min(b.x0_m, v[i].x());
    b.y0_m = std::min(b.y0_m, v[i].y());
    b.x1_m = std::max(b.x1_m, v[i].x());
    b.y1_m = std::max(b.y1_m, v[i].y());
  }
  const double lead = config_.focus_lead_m;
  field_.set_focus({b.x0_m - lead, b.y0_m - lead, b.x1_m + lead, b.y1_m + lead});
}

}  // namespace visvol::rt

// The executive's interaction modes: pull (mode A) and spool (mode B, the
// paper's second interaction: the rope pays out of the start while the
// operator drags its free end toward the destination). Loop thread,
// real-time rules: no allocation, no lock, no logging, no blocking.
#include <algorithm>
#include <cmath>

#include "rt/exec/executive.hpp"

namespace visvol::rt {

Errc Executive::apply_mode(const msg::Command& c, const char*& reason) {
  const Errc e = set_mode(c.mode);
  if (e == Errc::ok) return Errc::ok;
  if (c.mode == msg::InteractionMode::spool && device_ == nullptr) {
    reason = "spool mode needs the haptic device (the operator drags the rope out)";
  } else if (e == Errc::unsupported) {
    reason = "the rope would step outside its stability margin at the loop's period";
  } else {
    reason = "the rope could not be laid for that mode";
  }
  return Errc::invalid_argument;
}

Errc Executive::set_mode(msg::InteractionMode mode) {
  if (mode == mode_) return Errc::ok;
  Errc e = Errc::ok;
  if (mode == msg::InteractionMode::spool) {
    e = start_spool();
  } else if (counters_.spool_arrived) {
    mode_ = msg::InteractionMode::pull;  // the spooled rope already holds both ends: kept
    counters_.mode = mode_;
    ++counters_.mode_switches;
    let_go(true);
    equilibrium_.reset();
  } else {
    e = start_run();  // lays the rope between the ends again, in pull mode (counts the switch, lets go)
  }
  if (e != Errc::ok) return e;
  counters_.running = true;  // a switch starts the rope stepping, as start does
  return Errc::ok;
}

void Executive::let_go(bool scene_mapping) {
  grasping_ = false;
  rope_->clear_point_force();
  pull_n_ = Vec3::Zero();
  if (!servo_) return;
  servo_->release_grasp();
  if (scene_mapping) servo_->restore_mapping();
  last_proxy_m_ = servo_->proxy_m();
}

// A lead of kSpoolLeadSegments from the start toward the end, its far end
// free, with the pull mode's segment length and springs.
Errc Executive::start_spool() {
  if (device_ == nullptr) return Errc::unsupported;
  const double segment_m = pull_segment_m(start_m_, end_m_, rope_->model(), segments_, config_.slack);
  const Vec3 lead_end = spool_lead_end_m(start_m_, end_m_, rope_->model(), segments_, config_.slack);
  Vec3 lead[kSpoolLeadSegments + 1];
  for (int i = 0; i <= kSpoolLeadSegments; ++i) {
    lead[i] = start_m_ + (static_cast<double>(i) / kSpoolLeadSegments) * (lead_end - start_m_);
  }
  if (check_polyline(lead, kSpoolLeadSegments + 1, kSpoolLeadSegments, 1, config_.max_segments) != Errc::ok) {
    return Errc::invalid_argument;
  }
  const RopeParams p = params_for(rope_->model(), segments_, segment_m);
  if (!steps_stably(p, forces_->gains())) return Errc::unsupported;
  if (rope_->set_params(p) != Errc::ok) return Errc::invalid_argument;
  // The far end free before the rope is laid: a straight lead pinned at both
  // ends is a singular constraint system for the articulated rope.
  RopeEnds ends;
  ends.start_m = start_m_;
  ends.end_m = end_m_;
  ends.end_fixed = false;
  rope_->set_ends(ends);
  if (!rope_->reset(lead, kSpoolLeadSegments + 1, kSpoolLeadSegments).ok()) {
    set_ends(start_m_, end_m_);
    return Errc::invalid_argument;
  }
  rope_->set_ends(ends);
  // the handle, wherever it is, now holds the proxy at the lead's free end
  if (servo_) servo_->reindex(lead[kSpoolLeadSegments]);
  let_go(false);
  mode_ = msg::InteractionMode::spool;
  spool_segment_m_ = segment_m;
  ticks_since_pay_out_ = 0;
  arriving_ = false;
  arrival_ticks_ = -1;
  equilibrium_.reset();
  counters_.converged = false;
  counters_.run_s = 0;
  counters_.equilibrium_s = 0;
  counters_.spool_arrived = false;
  counters_.spool_at_capacity = false;
  counters_.spool_segments = rope_->segments();
  counters_.spool_paid_out_m = rope_->segments() * segment_m;
  counters_.spool_gap_m = (lead[kSpoolLeadSegments] - end_m_).norm();
  counters_.mode = mode_;
  ++counters_.mode_switches;
  ++counters_.runs;
  relaid_ = false;
  return Errc::ok;
}

void Executive::spool() {
  if (mode_ != msg::InteractionMode::spool || !counters_.running) return;
  if (arrival_ticks_ >= 0) {
    hold_arrived_end();
    return;
  }
  const int n = rope_->segments();
  const Vec3 free_end = rope_->point(n - 1, 1.0);
  counters_.spool_gap_m = (free_end - end_m_).norm();
  // Rope out of the spool: segments of spool_segment_m_ (the spring model's
  // rest length; its geometric length stretches).
  const double out_m = n * spool_segment_m_;
  if (arriving_ || counters_.spool_gap_m <= spool_segment_m_) {
    // Arrived. Held at the end once the rope has kSpoolArrivalSlack over the
    // straight line (a rope as long as the line, or shorter, pinned at both
    // ends pulls itself apart): one more segment a tick until it has. Each
    // moves the free end on, past the end perhaps: it is arriving from then
    // on, and its anchor is moved back onto the end.
    arriving_ = true;
    if (out_m < (1.0 + kSpoolArrivalSlack) * (end_m_ - start_m_).norm()) {
      if (rope_->pay_out_at_start()) {
        paid_out();
      } else {
        counters_.spool_at_capacity = true;  // too short to hold: stays free (switch to pull)
      }
      return;
    }
    // the end anchored where the free end is, then moved onto the end
    arrival_from_m_ = free_end;
    arrival_ticks_ = 0;
    hold_arrived_end();
    return;
  }
  if (!grasping_ || ++ticks_since_pay_out_ < kSpoolEveryTicks) return;
  // Paid out while the hand pulls the free end on along the rope's last
  // segment (where the new segment goes) harder than the saturated field
  // pulls one segment: the spool's drag.
  const Vec3 tip = free_end - rope_->point(n - 1, 0.0);
  const double tip_m = tip.norm();
  if (!(tip_m > 0) || pull_n_.dot(tip) <= saturated_n_ * tip_m) return;
  if (!rope_->pay_out_at_start()) {
    counters_.spool_at_capacity = true;
    return;
  }
  paid_out();
}

// The arrived end's anchor, moved from where the free end was to the end
// over kSpoolArrivalTicks (a jump of up to a segment at once would be a hard
// kick for the joint solver).
void Executive::hold_arrived_end() {
  const int k = std::min(arrival_ticks_, kSpoolArrivalTicks);
  const double t = static_cast<double>(k) / kSpoolArrivalTicks;
  set_ends(start_m_, arrival_from_m_ + t * (end_m_ - arrival_from_m_));
  if (arrival_ticks_ < kSpoolArrivalTicks) {
    ++arrival_ticks_;
    counters_.spool_gap_m = (1.0 - t) * (end_m_ - arrival_from_m_).norm();
    return;
  }
  if (!counters_.spool_arrived) {
    counters_.spool_arrived = true;
    counters_.spool_gap_m = 0.0;
    equilibrium_.reset();
  }
}

void Executive::paid_out() {
  ticks_since_pay_out_ = 0;
  grasp_segment_ = rope_->segments() - 1;  // the grasp stays on the free end
  counters_.spool_segments = rope_->segments();
  counters_.spool_paid_out_m = rope_->segments() * spool_segment_m_;
  equilibrium_.reset();
}

}  // namespace visvol::rt

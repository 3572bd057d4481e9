// Equilibrium of a settling rope (paper, section 4): at rest when, over the
// last window, the rope's RMS vertex speed stayed under a threshold and the
// path measure F_c changed by less than a fraction of itself per second (plus
// 1e-6): what is left is a slow creep along a flat ridge of the objective that
// no longer changes F_c.
//
// Fixed capacity, no allocation: the planner and the console's 1 kHz loop
// share it. One thread at a time.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

namespace visvol::rt {

struct EquilibriumCriteria {
  double check_interval_s = 0.02;      // how often add() is called
  double window_s = 0.5;               // the span every check must hold over
  double max_rms_speed_m_per_s = 1.0;  // the planner uses a tenth of a post spacing per second
  double max_fc_rate = 2e-3;           // |dF_c/dt| / F_c, per second
};

class EquilibriumDetector {
 public:
  static constexpr int kMaxWindow = 128;

  explicit EquilibriumDetector(const EquilibriumCriteria& c = {}) { configure(c); }

  void configure(const EquilibriumCriteria& c) {
    criteria_ = c;
    const double interval = c.check_interval_s > 0 ? c.check_interval_s : 0.02;
    window_ = std::clamp(static_cast<int>(std::lround(c.window_s / interval)), 2, kMaxWindow);
    reset();
  }
  void reset() {
    count_ = 0;
    head_ = 0;
  }

  // One check: the rope's RMS speed (m/s) and F_c now. True at rest.
  bool add(double rms_speed_m_per_s, double fc) {
    speed_[static_cast<std::size_t>(head_)] = rms_speed_m_per_s;
    fc_[static_cast<std::size_t>(head_)] = fc;
    head_ = (head_ + 1) % window_;
    count_ = std::min(count_ + 1, window_);
    if (count_ < window_) return false;
    double max_speed = 0;
    for (int i = 0; i < window_; ++i) max_speed = std::max(max_speed, speed_[static_cast<std::size_t>(i)]);
    const double oldest = fc_[static_cast<std::size_t>(head_)];  // head_ now points at the oldest
    const double span_s = (window_ - 1) * criteria_.check_interval_s;
    const double rate = std::fabs(fc - oldest) / span_s;
    return max_speed < criteria_.max_rms_speed_m_per_s && rate < criteria_.max_fc_rate * std::fabs(fc) + 1e-6;
  }

  const EquilibriumCriteria& criteria() const { return criteria_; }

 private:
  EquilibriumCriteria criteria_;
  int window_ = 2;
  int count_ = 0;
  int head_ = 0;
  std::array<double, kMaxWindow> speed_{};
  std::array<double, kMaxWindow> fc_{};
};

}  // namespace visvol::rt

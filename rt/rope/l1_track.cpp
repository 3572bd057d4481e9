#include "rt/rope/l1_track.hpp"

#include <algorithm>
#include <cmath>

#include "base/angles.hpp"
#include "rt/rope/path_metrics.hpp"

namespace visvol::rt {

// Without the three trigonometric calls of the formula (l1_track.hpp): they
// were the longest chain of a flight's step. |eta1| is at most 45 degrees,
// so where the sum passes 90 degrees (its cosine negative) it does so on
// eta2's side.
double l1_sin_eta(double sin_eta1, double cross_v, double dot_v) {
  const double r = std::sqrt(cross_v * cross_v + dot_v * dot_v);  // speeds: no overflow
  if (!(r > 0)) {  // atan2(+-0, +0) = +-0; atan2(+-0, -0) = +-pi: clamped to +-1
    if (!std::signbit(dot_v)) return sin_eta1;
    return std::signbit(cross_v) ? -1.0 : 1.0;
  }
  const double cos_eta1 = std::sqrt(1.0 - sin_eta1 * sin_eta1);
  const double sin_eta2 = cross_v / r, cos_eta2 = dot_v / r;
  if (cos_eta1 * cos_eta2 - sin_eta1 * sin_eta2 < 0) {
    return cross_v > 0 || (cross_v == 0 && !std::signbit(cross_v)) ? 1.0 : -1.0;
  }
  return sin_eta1 * cos_eta2 + cos_eta1 * sin_eta2;
}

namespace {

constexpr double kGravityMPerS2 = 9.80665;
// PX4's line tracking aims at most 45 degrees off the line (sin 0.7071), and
// flies straight to the leg's start while more than 45 degrees behind it.
constexpr double kSinMaxEta1 = 0.7071;
// Past the leg's end (its bearing from the end within 100 degrees of the
// leg's direction): back to the end.
constexpr double kCosPastEnd = -0.17364817766693033;  // cos 100 degrees

using Vec2 = Eigen::Vector2d;

Vec2 xy(const Vec3& p) { return {p.x(), p.y()}; }
double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// sin(eta) for a heading error eta towards `direction`, eta clamped to 90
// degrees either way (a direction behind turns at the full 90).
double sin_eta_towards(const Vec2& velocity, const Vec2& direction) {
  const double norms = velocity.norm() * direction.norm();
  if (!(norms > 0)) return 0.0;
  const double c = cross(velocity, direction);
  if (velocity.dot(direction) < 0) return c < 0 ? -1.0 : 1.0;
  return c / norms;
}

// The lateral acceleration PX4 1.13 commands to fly from `a` to `b`, m/s^2
// (positive turns left, counter-clockwise).
// `leg_unit` is the leg's direction (leg_direction), and
// `accel_per_sin_m_per_s2` the gain times V^2 / L1 at the flight's constant
// speed (|velocity|): both the same for every step of a leg.
double l1_lateral_accel(const Vec2& a, const Vec2& b, const Vec2& leg_unit, const Vec2& pos, const Vec2& velocity,
                        double l1_m, double accel_per_sin_m_per_s2) {
  Vec2 ab = leg_unit;
  if (ab.isZero()) {  // a leg under a millimetre: towards its end
    ab = b - pos;
    ab.normalize();
  }
  const Vec2 a_to_p = pos - a;
  const double distance_a = a_to_p.norm();
  const double along = a_to_p.dot(ab);
  const Vec2 b_to_p = pos - b;
  const double distance_b = b_to_p.norm();
  // past the end: within 100 degrees of the leg's direction seen from it
  const bool past_end = !(distance_b > 0) || b_to_p.dot(ab) > kCosPastEnd * distance_b;
  double sin_eta = 0;
  if (distance_a > l1_m && along / std::max(distance_a, 1.0) < -kSinMaxEta1) {
    sin_eta = sin_eta_towards(velocity, -a_to_p);  // far behind the start: to it
  } else if (past_end) {
    sin_eta = sin_eta_towards(velocity, -b_to_p);  // past the end: back to it
  } else {
    const double sine_eta1 = std::clamp(cross(a_to_p, ab) / std::max(l1_m, 0.1), -kSinMaxEta1, kSinMaxEta1);
    sin_eta = l1_sin_eta(sine_eta1, cross(velocity, ab), velocity.dot(ab));
  }
  return accel_per_sin_m_per_s2 * sin_eta;
}

// A leg's direction, a unit vector; zero for a leg under a millimetre.
Vec2 leg_direction(const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  return ab.norm() < 1e-3 ? Vec2::Zero() : Vec2(ab.normalized());
}

// The planned height at the point of leg a-b nearest `pos`.
double leg_height_m(const Vec3& a, const Vec3& b, const Vec2& pos) {
  return a.z() + leg_fraction(a, b, pos.x(), pos.y()) * (b.z() - a.z());
}

// PX4 1.13's first-order hold of a leg's height (l1_track.hpp), and the
// aircraft's height following it within its climb and sink rates.
class HeightHold {
 public:
  HeightHold(const L1Flight& flight, double hold_m, double start_height_m)
      : hold_m_(hold_m),
        climb_m_per_s_(flight.max_climb_m_per_s),
        sink_m_per_s_(flight.max_sink_m_per_s),
        z_m_(start_height_m) {}
  bool on() const { return hold_m_ > 0; }
  double height_m() const { return z_m_; }
  // PX4's navigator takes a waypoint only within its altitude acceptance
  // (NAV_FW_ALT_RAD) of its height
  bool within(double gate_m, const Vec3& waypoint) const { return !on() || std::abs(z_m_ - waypoint.z()) <= gate_m; }
  // PX4 keeps the least distance to the current waypoint since it was taken
  void next_leg() { nearest_m_ = std::numeric_limits<double>::infinity(); }
  // one controller step of dt_s on leg a-b at pos
  void step(const Vec3& a, const Vec3& b, const Vec2& pos, double dt_s) {
    if (!on()) return;
    const double leg_m = (xy(b) - xy(a)).norm();
    nearest_m_ = std::min({nearest_m_, (xy(b) - pos).norm(), leg_m});
    const double setpoint_m = leg_m > hold_m_ && nearest_m_ > hold_m_
                                  ? a.z() + (b.z() - a.z()) * (leg_m - nearest_m_) / (leg_m - hold_m_)
                                  : b.z();
    z_m_ += std::clamp(setpoint_m - z_m_, -sink_m_per_s_ * dt_s, climb_m_per_s_ * dt_s);
  }

 private:
  double hold_m_;
  double climb_m_per_s_, sink_m_per_s_;
  double z_m_;
  double nearest_m_ = std::numeric_limits<double>::infinity();
};

double horizontal_length_m(const std::vector<Vec3>& path) {
  double total = 0;
  for (std::size_t i = 1; i < path.size(); ++i) total += (xy(path[i]) - xy(path[i - 1])).norm();
  return total;
}

// The longest a flight may take, s: three times what it takes to fly the
// path's horizontal length at the ground speed and, with a hold, to climb and
// sink its heights at the vehicle's rates (an aircraft that reaches a
// waypoint low circles until it is within the gate), and two minutes more.
double flight_time_bound_s(const std::vector<Vec3>& path, const L1Flight& flight, bool hold) {
  double t_s = horizontal_length_m(path) / flight.ground_speed_m_per_s;
  for (std::size_t i = 1; hold && i < path.size(); ++i) {
    const double dz_m = path[i].z() - path[i - 1].z();
    if (dz_m > 0) t_s += dz_m / flight.max_climb_m_per_s;
    if (dz_m < 0) t_s += -dz_m / flight.max_sink_m_per_s;
  }
  return 3.0 * t_s + 120.0;
}

}  // namespace

double leg_fraction(const Vec3& a, const Vec3& b, double x, double y) {
  const Vec2 ab = xy(b) - xy(a);
  const double l2 = ab.squaredNorm();
  return l2 > 0 ? std::clamp((Vec2(x, y) - xy(a)).dot(ab) / l2, 0.0, 1.0) : 0.0;
}

double L1Flight::l1_distance_m() const { return damping * period_s * ground_speed_m_per_s / kPi; }

double L1Flight::accept_distance_m() const { return std::max(switch_distance_m, l1_distance_m()); }

FlownTrack fly_l1(const std::vector<Vec3>& path, const L1Flight& flight) {
  FlownTrack out;
  const int n = static_cast<int>(path.size());
  const double v = flight.ground_speed_m_per_s, dt = flight.step_s;
  if (n < 2 || !(v > 0) || !(dt > 0)) return out;
  // the first waypoint off the start's spot sets the heading (a climb on the spot first)
  int first_off = 1;
  while (first_off < n && (xy(path[static_cast<std::size_t>(first_off)]) - xy(path[0])).norm() < kSameSpotM) {
    ++first_off;
  }
  if (first_off == n) return out;
  const double l1_m = flight.l1_distance_m();
  const double gain = 4.0 * flight.damping * flight.damping;
  // PX4's 4 damping^2 V^2 / L1 sin(eta); the heading turns accel / V a second
  const double accel_per_sin = gain * v * v / l1_m, dt_per_v = dt / v;
  Vec2 leg_unit = Vec2::Zero();  // of leg leg_of_unit
  int leg_of_unit = -1;
  const double accept_m = flight.accept_distance_m();
  const double max_accel = kGravityMPerS2 * std::tan(flight.max_roll_deg * kRadPerDeg);
  const double hold_m = std::max(flight.altitude_hold_m, 0.0);
  // fmin: a rate of 0 (an infinite time) or NaN flies kMaxL1Steps
  const double max_steps = std::fmin(flight_time_bound_s(path, flight, hold_m > 0) / dt, kMaxL1Steps);
  const double record_m = std::max(flight.record_every_m, 0.0);
  Vec2 pos = xy(path[0]);
  Vec2 heading = (xy(path[static_cast<std::size_t>(first_off)]) - pos).normalized();  // unit
  int from = 0;
  HeightHold hold(flight, hold_m, path[0].z());
  out.points.push_back({path[0], 0});
  Vec2 recorded = pos;
  auto record = [&]() {
    const Vec3& a = path[static_cast<std::size_t>(from)];
    const Vec3& b = path[static_cast<std::size_t>(from + 1)];
    out.points.push_back({Vec3(pos.x(), pos.y(), hold.on() ? hold.height_m() : leg_height_m(a, b, pos)), from});
    recorded = pos;
  };
  for (double step = 0; step < max_steps; ++step) {
    const Vec3& next = path[static_cast<std::size_t>(from + 1)];
    if ((xy(next) - pos).norm() <= accept_m && hold.within(flight.altitude_gate_m, next)) {
      if (from + 2 == n) {
        out.reached_end = true;
        break;
      }
      ++from;  // one waypoint a step
      hold.next_leg();
    }
    const Vec3& a = path[static_cast<std::size_t>(from)];
    const Vec3& b = path[static_cast<std::size_t>(from + 1)];
    hold.step(a, b, pos, dt);
    const Vec2 velocity = v * heading;
    if (leg_of_unit != from) leg_unit = leg_direction(xy(a), xy(b)), leg_of_unit = from;
    const double accel =
        std::clamp(l1_lateral_accel(xy(a), xy(b), leg_unit, pos, velocity, l1_m, accel_per_sin), -max_accel, max_accel);
    pos += velocity * dt;
    // turned by accel / v dt (a hundredth of a radian a step at most): along
    // its left normal, then back to unit length
    heading = (heading + Vec2(-heading.y(), heading.x()) * (accel * dt_per_v)).normalized();
    if ((pos - recorded).norm() >= record_m) record();
  }
  if ((pos - recorded).norm() > 0) record();  // where it stopped, recorded or not
  return out;
}

}  // namespace visvol::rt

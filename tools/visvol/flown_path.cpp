#include "flown_path.hpp"

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <limits>

#include "base/angles.hpp"
#include "path_io_detail.hpp"
#include "rt/rope/fillet.hpp"

namespace visvol::cli {

namespace {

constexpr double kTwoPi = 2.0 * kPi;
// Points closer than this horizontally are one spot.
constexpr double kSpotM = rt::kSameSpotM;
// A turn radius the path's geometry decides (rt::turn_radii_m).
constexpr double kGeometry = std::numeric_limits<double>::quiet_NaN();
// The highest a loiter may be, m from the datum (as `check` takes vertices).
constexpr double kMaxLoiterAltitudeM = 1e5;

using Vec2 = Eigen::Vector2d;

Vec2 xy(const Vec3& p) { return {p.x(), p.y()}; }

// A circle flown in one sense: sense +1 counter-clockwise (seen from above,
// x east, y north), -1 clockwise.
struct Circle {
  Vec2 centre;
  double radius_m = 0;
  double sense = -1;
  Vec2 at(double angle) const { return centre + radius_m * Vec2(std::cos(angle), std::sin(angle)); }
  Vec2 velocity(double angle) const { return sense * Vec2(-std::sin(angle), std::cos(angle)); }
};

// The angle where the circle meets a line through `p` along the direction
// of flight: arriving from p (`arriving`) or leaving towards p. Outside the
// circle, the tangent point whose sense matches; inside, straight out (from
// the centre: along `heading`).
double tangent_angle(const Circle& c, const Vec2& p, bool arriving, const Vec2& heading) {
  const Vec2 d = p - c.centre;
  const double dist = d.norm();
  if (dist <= c.radius_m) {
    const Vec2 out = dist > kSpotM ? d : heading;
    return std::atan2(out.y(), out.x());
  }
  const double base = std::atan2(d.y(), d.x()), spread = std::acos(c.radius_m / dist);
  for (double angle : {base + spread, base - spread}) {
    const Vec2 along = arriving ? Vec2(c.at(angle) - p) : Vec2(p - c.at(angle));
    if (along.dot(c.velocity(angle)) > 0) return angle;
  }
  return base;  // not reached: one tangent always matches
}

// The tangent of the steepest climb (dz > 0) or descent the vehicle flies,
// a hair under it so that a chord at it never reads as over; infinite at 90.
double steepest_slope(const rt::VehicleEnvelope& e, double dz_m) {
  const double angle_deg = dz_m > 0 ? e.max_climb_deg : e.max_descent_deg;
  if (angle_deg >= 90.0 - 1e-9) return std::numeric_limits<double>::infinity();
  return std::tan(angle_deg * kRadPerDeg) * (1.0 - 1e-9);
}

// The turns a loiter item asks for (LOITER_TO_ALT: none; the altitude, which
// every loiter reaches before it leaves, asks for its own).
double loiter_turns(const LoiterItem& l, const rt::VehicleEnvelope& e, double radius_m) {
  switch (l.kind) {
    case LoiterKind::unlimited: return 1.0;
    case LoiterKind::turns: return l.amount;
    case LoiterKind::time: return l.amount * e.speed_m_per_s / (kTwoPi * radius_m);
    case LoiterKind::to_altitude: return 0.0;
  }
  return 0.0;
}

// A number for a message: 1 decimal, or 6 digits where that would be long.
std::string describe_number(double v) { return detail::shown(v, 1); }

std::string describe(const LoiterItem& l, double turns, double radius_m, double sense, std::size_t points) {
  char text[200];
  std::snprintf(text, sizeof text, "%s: %.1f turns of %.0f m %s at %.1f m (%zu points)", l.item.c_str(), turns,
                radius_m, sense > 0 ? "counter-clockwise" : "clockwise", l.altitude_m, points);
  return text;
}

class Flight {
 public:
  Flight(const PathFile& file, const rt::VehicleEnvelope& e) : file_(file), e_(e) {}

  void add(const Vec3& p, double turn_radius_m = kGeometry, int vertex = -1) {
    out_.points.push_back(p);
    out_.turn_radius_m.push_back(turn_radius_m);
    out_.vertex_of.push_back(vertex);
    out_.hold_s.push_back(0.0);
  }

  // The heading the aircraft arrives with (east when it has not moved).
  Vec2 heading() const {
    const std::vector<Vec3>& p = out_.points;
    for (std::size_t k = p.size(); k-- > 1;) {
      const Vec2 d = xy(p.back()) - xy(p[k - 1]);
      if (d.norm() > kSpotM) return d / d.norm();
    }
    return {1, 0};
  }

  // A loiter from where the aircraft is, towards `next` (or none).
  Status loiter(const LoiterItem& l, const Vec3& centre, const Vec3* next) {
    if (!(std::fabs(l.altitude_m) <= kMaxLoiterAltitudeM)) {
      return invalid_argument(l.item + ": altitude " + describe_number(l.altitude_m) + " m is beyond +-" +
                              describe_number(kMaxLoiterAltitudeM / 1000) + " km of the datum");
    }
    // A multirotor hovers over a loiter's point, but ArduCopter flies turns
    // of a radius as the circle (checked as a hover at the centre, a 250 m
    // circle 7 m over the ground read as met). The autopilot: --autopilot,
    // else the mission's firmwareType, else the vehicle's (check's notes).
    const bool ardupilot = e_.autopilot == rt::Autopilot::ardupilot;
    const bool circles = ardupilot && l.kind == LoiterKind::turns && std::fabs(l.radius_m) >= kSpotM;
    if (e_.type == rt::VehicleType::multirotor && !circles) return hover(l, centre);
    const double radius_m = l.radius_m != 0 ? std::fabs(l.radius_m) : e_.min_turn_radius_m;
    if (radius_m < kSpotM) return turn_on_the_spot(l, centre, radius_m);
    const Circle c{xy(centre), radius_m, l.radius_m < 0 ? 1.0 : -1.0};
    const Vec3 from = out_.points.empty() ? centre : out_.points.back();
    const double entry = tangent_angle(c, xy(from), true, heading());
    const double leg_m = (c.at(entry) - xy(from)).norm(), dz_m = l.altitude_m - from.z();
    // a turn of the polygon flown: its chords, kLoiterStepDeg of arc at most
    const double chord_turn_m =
        kTwoPi * radius_m * std::sin(0.5 * kLoiterStepDeg * kRadPerDeg) / (0.5 * kLoiterStepDeg * kRadPerDeg);
    // the turns the item asks for, or more: the loiter's altitude is reached
    // on the circle (an autopilot climbs or descends there until it is). Its
    // chords climb at the share of the steepest slope the checker's arcs by
    // their corners leave (rt::arc_slope_share): a helix climbs at the slope
    // itself, the chords with an arc at each corner would climb more steeply.
    const double slope = steepest_slope(e_, dz_m), sign = dz_m > 0 ? 1.0 : -1.0;
    const double circle_slope = slope * rt::arc_slope_share(kLoiterStepDeg * kRadPerDeg);
    const double to_altitude = std::max(0.0, std::fabs(dz_m) - leg_m * slope) / circle_slope / chord_turn_m;
    const double turns = std::max(loiter_turns(l, e_, radius_m), to_altitude);
    if (!(turns <= kMaxLoiterTurns)) {
      return invalid_argument(l.item + ": " + describe_number(turns) + " turns of " + describe_number(radius_m) +
                              " m; a check flies at most " + describe_number(kMaxLoiterTurns));
    }
    // the arc from the entry to the tangent towards the next vertex
    double exit_arc = 0;
    bool exit_inside = false;
    if (next != nullptr) {
      const double exit = tangent_angle(c, xy(*next), false, c.velocity(entry));
      exit_arc = std::fmod(c.sense * (exit - entry) + 2 * kTwoPi, kTwoPi);
      exit_inside = (xy(*next) - c.centre).norm() < radius_m - kSpotM;
    }
    const double sweep = turns * kTwoPi + exit_arc;
    const int steps = std::max(1, static_cast<int>(std::ceil(sweep / (kLoiterStepDeg * kRadPerDeg))));
    double z = from.z(), left_m = std::fabs(dz_m);
    auto climb_over = [&](double horizontal_m, double along_slope) {
      const double step = std::min(left_m, horizontal_m * along_slope);
      left_m -= step;
      z += sign * step;
    };
    // the circle's points turn at its radius; where it is joined or left
    // along a tangent the geometry judges the join, and from or towards a
    // point inside the circle (straight out, straight in) it is the radius
    const bool entry_inside = (xy(from) - c.centre).norm() < radius_m - kSpotM;
    const int last_step = sweep > 0 ? steps : 0;
    const std::size_t first = out_.points.size();
    Vec2 last = xy(from);
    for (int k = 0; k <= last_step; ++k) {
      const Vec2 p = c.at(entry + c.sense * sweep * k / steps);
      climb_over((p - last).norm(), k == 0 ? slope : circle_slope);  // the leg in, then the chords
      last = p;
      const bool join = (k == 0 && !entry_inside) || (k == last_step && !exit_inside);
      add({p.x(), p.y(), z}, join ? kGeometry : radius_m);
    }
    out_.loiters.push_back(describe(l, turns, radius_m, c.sense, out_.points.size() - first));
    if (out_.points.size() > kMaxFlownPoints) {
      return invalid_argument(l.item + ": the loiters so far fly more than " +
                              describe_number(static_cast<double>(kMaxFlownPoints)) + " points; a check flies fewer");
    }
    return Status::ok_status();
  }

  // A multirotor stops over the point (climbing or descending on the spot).
  Status hover(const LoiterItem& l, const Vec3& centre) {
    const Vec3 over(centre.x(), centre.y(), l.altitude_m);
    if (out_.points.empty() || (out_.points.back() - over).norm() >= kSpotM) add(over);
    // LOITER_TIME waits its seconds there; the others no time (an unlimited
    // loiter would hold for ever: the check counts none, as for a fixed-wing's)
    const double wait_s = l.kind == LoiterKind::time ? l.amount : 0.0;
    out_.hold_s.back() += wait_s;
    out_.loiters.push_back(l.item + ": hovers at " + describe_number(l.altitude_m) + " m" +
                           (wait_s > 0 ? " for " + describe_number(wait_s) + " s" : std::string()));
    return Status::ok_status();
  }

  // A fixed-wing asked for a circle too small to draw: a point that turns at
  // that radius (min-turn-radius judges it).
  Status turn_on_the_spot(const LoiterItem& l, const Vec3& centre, double radius_m) {
    add({centre.x(), centre.y(), l.altitude_m}, radius_m);
    out_.loiters.push_back(l.item + ": turns on the spot (radius " + describe_number(radius_m) + " m) at " +
                           describe_number(l.altitude_m) + " m");
    return Status::ok_status();
  }

  Result<FlownPath> fly() {
    const std::vector<Vec3>& v = file_.points;
    std::size_t next_loiter = 0;
    for (std::size_t k = 0; k < v.size(); ++k) {
      const std::size_t first = next_loiter;
      while (next_loiter < file_.loiters.size() && file_.loiters[next_loiter].vertex == k) ++next_loiter;
      // a loiter's own vertex is its centre, which the aircraft circles
      const bool centre_only = first < next_loiter && !file_.loiters[first].over_waypoint;
      if (!centre_only) {
        add(v[k], kGeometry, static_cast<int>(k));
        // a waypoint's hold: a multirotor waits there (a fixed-wing flies on)
        if (e_.type == rt::VehicleType::multirotor && k < file_.hold_s.size()) out_.hold_s.back() += file_.hold_s[k];
      }
      for (std::size_t i = first; i < next_loiter; ++i) {
        const Vec3* next = k + 1 < v.size() ? &v[k + 1] : nullptr;
        VISVOL_RETURN_IF_ERROR(loiter(file_.loiters[i], v[k], next));
      }
    }
    return std::move(out_);
  }

 private:
  const PathFile& file_;
  const rt::VehicleEnvelope& e_;
  FlownPath out_;
};

}  // namespace

Result<FlownPath> fly_path(const PathFile& file, const rt::VehicleEnvelope& e) { return Flight(file, e).fly(); }

}  // namespace visvol::cli

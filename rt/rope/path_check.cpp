#include "rt/rope/path_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>

#include "base/angles.hpp"
#include "base/tolerances.hpp"
#include "fields/exact_visibility.hpp"
#include "rt/rope/fillet.hpp"
#include "rt/rope/terrain_probe.hpp"
#include "rt/rope/track_ground.hpp"

namespace visvol::rt {

namespace {

constexpr double kAngleTolDeg = 1e-6;

// A length for a message: metres to the centimetre.
std::string metres(double v_m) {
  char text[48];
  std::snprintf(text, sizeof text, "%.2f", v_m);
  return text;
}

// Running tally of one requirement over weighted samples, and points of no
// weight (the terrain probes) that can only fail it.
struct Tally {
  double ok_weight = 0, weight = 0;
  bool failed = false;
  void add(bool ok, double w) {
    weight += w;
    if (ok) ok_weight += w;
    failed = failed || !ok;
  }
  void probe(bool ok) { failed = failed || !ok; }
  // a requirement that fails somewhere never holds on all of the length
  double fraction() const {
    const double f = weight > 0 ? ok_weight / weight : (failed ? 0.0 : 1.0);
    return failed ? std::min(f, std::nextafter(1.0, 0.0)) : f;
  }
};

// Samples `step_m` apart along a fillet, its ends (on the segments) left out.
int fillet_samples(const Fillet& f, double step_m) {
  const double wanted = std::ceil(f.length_m() / step_m);
  return wanted >= 1 ? static_cast<int>(std::min(wanted, double(PathChecker::kMaxSegmentSamples))) : 1;
}

// The horizontal distance from p to the nearest point of the legs around
// the one it flies (two either way: a corner cut across legs shorter than
// the switch distance), not the whole path's (quadratic on a long one).
double off_path_m(const std::vector<Vec3>& path, const FlownPoint& flown) {
  double best = std::numeric_limits<double>::infinity();
  const Vec3& p = flown.p_m;
  const Eigen::Vector2d q(p.x(), p.y());
  const std::size_t leg = static_cast<std::size_t>(flown.leg);
  const std::size_t first = leg >= 2 ? leg - 2 : 0, last = std::min(leg + 3, path.size() - 1);
  for (std::size_t s = first; s < last; ++s) {
    const Eigen::Vector2d a(path[s].x(), path[s].y()), ab = Eigen::Vector2d(path[s + 1].x(), path[s + 1].y()) - a;
    best = std::min(best, (q - a - leg_fraction(path[s], path[s + 1], q.x(), q.y()) * ab).norm());
  }
  return best;
}

// One flight of a finite path (PathChecker::fly): a sample every sample
// step of the track (or a controller step, the longer: 0.4 m at 20 m/s),
// standing for the track since the last. The sight lines and the distance
// off the legs only where `report` (check() takes the clearance alone, into
// `clearance_out`).
FlownCheck fly_once(const PathChecker& checker, const std::vector<Vec3>& path, const L1Flight& flight, bool report,
                    Tally* clearance_out) {
  FlownCheck out;
  out.ground_speed_m_per_s = flight.ground_speed_m_per_s;
  out.switch_distance_m = flight.accept_distance_m();
  out.altitude_hold_m = flight.altitude_hold_m;
  L1Flight sampled = flight;
  sampled.record_every_m = checker.spec().sample_step_m;
  const FlownTrack track = fly_l1(path, sampled);
  out.reached_end = track.reached_end;
  const PathCheckSpec& spec = checker.spec();
  const std::size_t nc = report ? spec.constraints.size() : 0;
  std::vector<Tally> constraint_tally(nc);
  Tally clearance;
  auto sample = [&](const FlownPoint& flown, double w) {
    const Vec3& p = flown.p_m;
    const double h = p.z() - checker.ground_m(p.x(), p.y());
    if (h < out.least_clearance_m) out.least_clearance_m = h, out.least_at_m = p;
    const bool clear = h >= spec.envelope.clearance_m - kHeightTolM;
    clearance.add(clear, w);
    if (clearance_out) clearance_out->add(clear, w);
    if (report) out.max_off_path_m = std::max(out.max_off_path_m, off_path_m(path, flown));
    for (std::size_t c = 0; c < nc; ++c) {
      const bool seen = checker.sees(spec.constraints[c], p);
      constraint_tally[c].add(seen == (spec.constraints[c].kind == ConstraintKind::visible_to), w);
    }
  };
  // the track keeps its points a sample step apart: each is a sample
  for (std::size_t i = 0; i < track.points.size(); ++i) {
    const double step_m = i > 0 ? (track.points[i].p_m - track.points[i - 1].p_m).head<2>().norm() : 0.0;
    out.length_m += step_m;
    sample(track.points[i], step_m);
  }
  out.clearance_fraction = clearance.fraction();
  for (const Tally& t : constraint_tally) out.constraint_fractions.push_back(t.fraction());
  return out;
}

LimitResult limit(const char* name, const char* unit, double limit_value, double worst, const Tally& t,
                  bool lower = false) {
  LimitResult r;
  r.lower = lower;
  r.name = name;
  r.unit = unit;
  r.limit = limit_value;
  r.worst = worst;
  r.satisfied_fraction = t.fraction();
  r.met = !t.failed;
  return r;
}

}  // namespace

int worst_decimals(const LimitResult& l) {
  if (l.met || !std::isfinite(l.worst) || !std::isfinite(l.limit)) return 1;
  for (int decimals = 1; decimals < kMaxWorstDecimals; ++decimals) {
    const double scale = std::pow(10.0, decimals);
    const double shown = std::round(l.worst * scale) / scale, limit_shown = std::round(l.limit * scale) / scale;
    if (l.lower ? shown < limit_shown : shown > limit_shown) return decimals;
  }
  return kMaxWorstDecimals;
}

const char* to_string(ConstraintKind kind) { return kind == ConstraintKind::visible_to ? "visible-to" : "hidden-from"; }

std::vector<std::string> PathCheck::unmet() const {
  std::vector<std::string> out;
  for (const ConstraintResult& c : constraints) {
    if (c.met) continue;
    std::ostringstream s;
    s.precision(1);
    s << std::fixed << to_string(c.constraint.kind) << " (" << c.constraint.point_m.x() << ", "
      << c.constraint.point_m.y() << ", " << c.constraint.point_m.z() << "): holds on " << std::setprecision(3)
      << fraction_shown(c.satisfied_fraction) << " of the length";
    out.push_back(s.str());
  }
  for (const LimitResult& l : envelope) {
    if (l.met) continue;
    std::ostringstream s;
    s.precision(1);
    s << std::fixed << std::setprecision(worst_decimals(l)) << l.name << " " << l.limit << " " << l.unit << ": worst "
      << l.worst << " " << l.unit << ", holds on " << std::setprecision(3) << fraction_shown(l.satisfied_fraction)
      << (l.name == kFlownClearance ? " of the flown length" : " of the length");
    out.push_back(s.str());
  }
  if (!inside_planning_bounds) {
    std::ostringstream s;
    s.precision(3);
    s << "planning bounds: " << fraction_shown(inside_bounds_fraction) << " of the length inside";
    out.push_back(s.str());
  }
  return out;
}

Result<PathChecker> PathChecker::create(fields::Heightfield terrain, const PathField* field, PathCheckSpec spec) {
  if (terrain.nx < 2 || terrain.ny < 2 || !(terrain.spacing_m > 0) || terrain.height_m.size() != terrain.size()) {
    return invalid_argument("path check: the terrain is empty");
  }
  VISVOL_RETURN_IF_ERROR(validate(spec.envelope));
  if (!(spec.sample_step_m >= 0 && std::isfinite(spec.sample_step_m))) {
    return invalid_argument("path check: the sample step must be a finite length");
  }
  if (spec.sample_step_m == 0) spec.sample_step_m = kSightStepPosts * terrain.spacing_m;
  PathChecker c;
  c.terrain_ = std::move(terrain);
  c.field_ = field;
  const fields::Heightfield& t = c.terrain_;
  for (const ConstraintPoint& p : spec.constraints) {
    const std::string name = std::string("--") + to_string(p.kind);
    if (!p.point_m.allFinite() || !std::isfinite(p.eye_height_m) || p.eye_height_m < 0 || p.eye_height_m > 1e4) {
      return invalid_argument(name + ": the point and the eye height must be finite (eye 0..10000 m)");
    }
    const double i = t.i_of(p.point_m.x()), j = t.j_of(p.point_m.y());
    if (!(i >= 0 && j >= 0 && i <= t.nx - 1 && j <= t.ny - 1)) {
      return invalid_argument(name + ": (" + std::to_string(p.point_m.x()) + ", " + std::to_string(p.point_m.y()) +
                              ") is outside the terrain");
    }
    const double ground = fields::bilinear_height(t, i, j);
    if (p.point_m.z() < ground - kHeightTolM) {
      return invalid_argument(name + ": the point is " + metres(ground - p.point_m.z()) +
                              " m below the finest terrain (" + metres(ground) + " m there)");
    }
  }
  // one eye named both ways: no path is hidden from it and in its sight
  for (const ConstraintPoint& h : spec.constraints) {
    if (h.kind != ConstraintKind::hidden_from) continue;
    for (const ConstraintPoint& v : spec.constraints) {
      const Vec3 e = h.eye_m(), f = v.eye_m();
      if (v.kind == ConstraintKind::visible_to && same_point(e.x(), e.y(), e.z(), f.x(), f.y(), f.z())) {
        return invalid_argument("--hidden-from and --visible-to name the same eye (" + metres(e.x()) + ", " +
                                metres(e.y()) + ", " + metres(e.z()) +
                                " m): no path is both hidden from it and in its sight");
      }
    }
  }
  c.spec_ = std::move(spec);
  return c;
}

Status check_observer_altitude(const std::string& name, double z_m) {
  if (!(z_m > kMaxObserverAltitudeM)) return Status::ok_status();
  std::ostringstream msg;
  msg << name << ": Z " << z_m << " m is above the " << kMaxObserverAltitudeM << " m an observer may be";
  return invalid_argument(msg.str());
}

double PathChecker::ground_m(double x, double y) const {
  return fields::bilinear_height(terrain_, terrain_.i_of(x), terrain_.j_of(y));  // clamped to the grid
}

bool PathChecker::sees(const ConstraintPoint& c, const Vec3& p) const {
  const Vec3 eye = c.eye_m();
  return fields::r3_visible(terrain_, terrain_.i_of(eye.x()), terrain_.j_of(eye.y()), eye.z(), terrain_.i_of(p.x()),
                            terrain_.j_of(p.y()), p.z(), spec_.curvature_coeff);
}

double PathChecker::sample_count(const std::vector<Vec3>& path) const {
  double total = static_cast<double>(path.size());
  for (std::size_t s = 0; s + 1 < path.size(); ++s) {
    if (!path[s].allFinite() || !path[s + 1].allFinite()) return std::numeric_limits<double>::infinity();
    total += std::ceil((path[s + 1] - path[s]).norm() / spec_.sample_step_m);
  }
  for (const std::optional<Fillet>& f :
       corner_fillets(path.data(), static_cast<int>(path.size()), spec_.envelope.min_turn_radius_m)) {
    if (f) total += std::ceil(f->length_m() / spec_.sample_step_m);
  }
  return total;
}

PathCheck PathChecker::check(const Vec3* v, int count, const double* turn_radius_m) const {
  PathCheck out;
  const VehicleEnvelope& e = spec_.envelope;
  const std::size_t nc = spec_.constraints.size();
  if (count < 2 || v == nullptr) {
    out.violation = out.flight_violation = 1;
    return out;
  }
  std::vector<Tally> constraint_tally(nc);
  std::vector<double> seen_m(nc, 0.0);
  Tally clearance, agl, altitude, bounds, climb, descent, turn;
  double lowest = std::numeric_limits<double>::infinity(), highest_agl = -lowest, highest = -lowest;
  double steepest_climb = 0, steepest_descent = 0, tightest = std::numeric_limits<double>::infinity();

  std::vector<std::vector<bool>> vertex_seen(static_cast<std::size_t>(count), std::vector<bool>(nc));
  auto inside_bounds = [&](const Vec3& p) {
    if (!spec_.planning_bounds) return true;
    const fields::Bounds2D& b = *spec_.planning_bounds;
    return p.x() >= b.xmin_m - kBoundsTolM && p.x() <= b.xmax_m + kBoundsTolM && p.y() >= b.ymin_m - kBoundsTolM &&
           p.y() <= b.ymax_m + kBoundsTolM;
  };
  // `seen` (or null): where the sight lines of a vertex's sample go
  auto sample = [&](const Vec3& p, double w, std::vector<bool>* seen_out) {
    const double ground = ground_m(p.x(), p.y());
    const double h = p.z() - ground;
    lowest = std::min(lowest, h);
    highest_agl = std::max(highest_agl, h);
    highest = std::max(highest, p.z());
    clearance.add(h >= e.clearance_m - kHeightTolM, w);
    agl.add(h <= e.max_agl_m + kHeightTolM, w);
    altitude.add(p.z() <= e.max_altitude_m + kHeightTolM, w);
    bounds.add(inside_bounds(p), w);
    for (std::size_t c = 0; c < nc; ++c) {
      const bool seen = sees(spec_.constraints[c], p);
      if (seen_out) (*seen_out)[c] = seen;
      if (seen) seen_m[c] += w;
      constraint_tally[c].add(seen == (spec_.constraints[c].kind == ConstraintKind::visible_to), w);
    }
  };

  // where the height above the terrain is extreme between samples (no share
  // of the length: it can only fail clearance or max-agl)
  auto terrain_probe = [&](const Vec3& p, double) {
    const double h = p.z() - ground_m(p.x(), p.y());
    lowest = std::min(lowest, h);
    highest_agl = std::max(highest_agl, h);
    clearance.probe(h >= e.clearance_m - kHeightTolM);
    agl.probe(h <= e.max_agl_m + kHeightTolM);
  };

  // The clearance of an aircraft that takes each height up to its hold
  // early (track_ground.hpp; the hold and the switch distance grow with the
  // wind: rt::switch_distance_m): at each sample, over the highest ground
  // that far behind it and one sample step more (so that a path met at the
  // samples is met between them); on a segment no longer than the hold, no
  // more than the lower of its two heights over its held stretch, which
  // begins the switch distance before the segment's start.
  const double early_m = altitude_hold_m(e);     // how early a height may be flown
  const double switch_m = switch_distance_m(e);  // where the next waypoint is taken
  std::optional<TrackGround> track;
  if (early_m > 0) track.emplace(terrain_, v, count);
  Tally early;
  double early_lowest = std::numeric_limits<double>::infinity();
  std::vector<double> segment_early(static_cast<std::size_t>(count), std::numeric_limits<double>::infinity());

  // samples along every segment, trapezoid weights by length
  for (int s = 0; s + 1 < count; ++s) {
    const Vec3 a = v[s], b = v[s + 1];
    const double len = (b - a).norm();
    out.length_m += len;
    // bounded before the conversion (a segment of 1e10 m, or infinite)
    const double wanted = std::ceil(len / spec_.sample_step_m);
    const int m = wanted >= 1 ? static_cast<int>(std::min(wanted, double(kMaxSegmentSamples))) : 1;
    const double leg_m = track ? track->at_vertex_m(s + 1) - track->at_vertex_m(s) : 0.0;
    const double held_m = track && leg_m <= early_m ? track->held_clearance_m(s, s + 1, a.z(), b.z(), switch_m)
                                                    : std::numeric_limits<double>::infinity();
    for (int k = 0; k <= m; ++k) {
      const double w = len / m * ((k == 0 || k == m) ? 0.5 : 1.0);
      // the segment's ends are the vertices themselves
      const Vec3 p = k == 0 ? a : k == m ? b : Vec3(a + (b - a) * (static_cast<double>(k) / m));
      std::vector<bool>* at_vertex = k == 0   ? &vertex_seen[static_cast<std::size_t>(s)]
                                     : k == m ? &vertex_seen[static_cast<std::size_t>(s + 1)]
                                              : nullptr;
      sample(p, w, at_vertex);
      if (track) {
        const double at_m = track->at_vertex_m(s) + leg_m * (static_cast<double>(k) / m);
        const double h = std::min(p.z() - track->highest_m(at_m - early_m - leg_m / m, at_m), held_m);
        early_lowest = std::min(early_lowest, h);
        segment_early[static_cast<std::size_t>(s)] = std::min(segment_early[static_cast<std::size_t>(s)], h);
        early.add(h >= e.clearance_m - kHeightTolM, w);
      }
    }
    for_each_terrain_probe(terrain_, a, b, terrain_probe);
    const double horizontal = std::hypot(b.x() - a.x(), b.y() - a.y());
    const double angle = len > 1e-9 ? std::atan2(b.z() - a.z(), horizontal) * kDegPerRad : 0.0;
    steepest_climb = std::max(steepest_climb, angle);
    steepest_descent = std::max(steepest_descent, -angle);
    climb.add(angle <= e.max_climb_deg + kAngleTolDeg, len);
    descent.add(-angle <= e.max_descent_deg + kAngleTolDeg, len);
  }

  // a fixed-wing flies by a corner on an arc inside it: its samples judge
  // the constraints, clearance, heights and bounds at no share of the length
  // (they can only fail a requirement), and clearance and max-agl are exact
  // along the arc's chords between them (a chord is step^2 / 8R from the
  // arc: under a centimetre at the default step on a 30 m grid and 80 m). The arc is shorter
  // than the legs it cuts, so it climbs or descends more steeply than they
  // do on average (a right-angle corner between two legs at the same slope:
  // 4 / pi times their slope): judged too, at no share of the length.
  for (const std::optional<Fillet>& f : corner_fillets(v, count, e.min_turn_radius_m)) {
    if (!f) continue;
    for_each_arc_point(
        *f, fillet_samples(*f, spec_.sample_step_m), terrain_, [&](const Vec3& p) { sample(p, 0.0, nullptr); },
        terrain_probe);
    const double angle = std::atan2(f->z_end_m - f->z_start_m, f->length_m()) * kDegPerRad;
    steepest_climb = std::max(steepest_climb, angle);
    steepest_descent = std::max(steepest_descent, -angle);
    climb.probe(angle <= e.max_climb_deg + kAngleTolDeg);
    descent.probe(-angle <= e.max_descent_deg + kAngleTolDeg);
  }

  // A PX4 fixed-wing cuts each corner deeper than the arc, across several
  // where the legs are shorter than its switch distance: the clearance along
  // its flights (px4_flights, fly_l1), at the height it flies (the
  // first-order hold at its climb and sink rates), over the flown track's
  // own length. Not where the caller gives
  // turn radii (a loiter's circle, which PX4 flies by another controller).
  Tally flown;
  double flown_lowest = std::numeric_limits<double>::infinity();
  bool flies = true;
  for (int i = 0; i < count; ++i) {
    if (!v[i].allFinite() || (turn_radius_m != nullptr && !std::isnan(turn_radius_m[i]))) flies = false;
  }
  const std::vector<L1Flight> flights = flies ? px4_flights(e) : std::vector<L1Flight>();
  bool any_flown = false;  // a path on one spot is not flown (its climb fails)
  if (!flights.empty()) {
    const std::vector<Vec3> path(v, v + count);
    for (const L1Flight& f : flights) {
      const FlownCheck flight = fly_once(*this, path, f, false, &flown);
      flown_lowest = std::min(flown_lowest, flight.least_clearance_m);
      any_flown = any_flown || flight.length_m > 0;
      if (!flight.reached_end) flown.probe(false);  // the legs it did not reach are not judged
    }
  }

  out.per_vertex.resize(static_cast<std::size_t>(count));
  const std::vector<double> radii = turn_radii_m(v, count);
  for (int i = 0; i < count; ++i) {
    VertexCheck& vc = out.per_vertex[static_cast<std::size_t>(i)];
    vc.ground_m = ground_m(v[i].x(), v[i].y());
    vc.clearance_m = v[i].z() - vc.ground_m;
    vc.fp = field_ ? field_->visibility(v[i]) : 0.0;
    vc.turn_radius_m = std::numeric_limits<double>::infinity();
    vc.early_m = segment_early[static_cast<std::size_t>(i)];
    if (i + 1 < count) {
      const Vec3 d = v[i + 1] - v[i];
      vc.climb_deg = d.norm() > 1e-9 ? std::atan2(d.z(), std::hypot(d.x(), d.y())) * kDegPerRad : 0.0;
    }
    if (i > 0 && i + 1 < count) {
      const bool given = turn_radius_m != nullptr && !std::isnan(turn_radius_m[i]);
      vc.turn_radius_m = given ? turn_radius_m[i] : radii[static_cast<std::size_t>(i)];
      tightest = std::min(tightest, vc.turn_radius_m);
      const double w = 0.5 * ((v[i] - v[i - 1]).norm() + (v[i + 1] - v[i]).norm());
      turn.add(vc.turn_radius_m >= e.min_turn_radius_m - 1e-6, w);
    }
    vc.seen_by = std::move(vertex_seen[static_cast<std::size_t>(i)]);
  }

  out.fc = field_ ? path_fc(v, count, *field_, 256) : 0.0;
  out.duration_s = out.length_m / e.speed_m_per_s;
  for (std::size_t c = 0; c < nc; ++c) {
    ConstraintResult r;
    r.constraint = spec_.constraints[c];
    r.satisfied_fraction = constraint_tally[c].fraction();
    r.seen_m = seen_m[c];
    r.met = !constraint_tally[c].failed;
    out.constraints.push_back(r);
  }
  out.envelope.push_back(limit("clearance", "m", e.clearance_m, lowest, clearance, true));
  out.envelope.push_back(limit("max-agl", "m", e.max_agl_m, highest_agl, agl));
  out.envelope.push_back(limit("max-altitude", "m", e.max_altitude_m, highest, altitude));
  out.envelope.push_back(limit("max-climb", "deg", e.max_climb_deg, steepest_climb, climb));
  out.envelope.push_back(limit("max-descent", "deg", e.max_descent_deg, steepest_descent, descent));
  out.envelope.push_back(limit("min-turn-radius", "m", e.min_turn_radius_m, tightest, turn, true));
  if (track) out.envelope.push_back(limit("early-descent", "m", e.clearance_m, early_lowest, early, true));
  if (any_flown) out.envelope.push_back(limit(kFlownClearance, "m", e.clearance_m, flown_lowest, flown, true));
  out.inside_bounds_fraction = bounds.fraction();
  out.inside_planning_bounds = !bounds.failed;

  out.all_met = out.inside_planning_bounds;
  auto count_violation = [&](bool met, double fraction, bool flight) {
    if (met) return;
    out.all_met = false;
    // a limit broken only where a probe found it (a fraction within a
    // rounding of 1) still counts: well over the tie, so it ranks
    const double unmet = std::max(PathCheck::kMinUnmetShare, 1.0 - fraction);
    out.violation += unmet;
    if (flight) out.flight_violation += unmet;
  };
  for (const ConstraintResult& r : out.constraints) count_violation(r.met, r.satisfied_fraction, false);
  for (const LimitResult& l : out.envelope) count_violation(l.met, l.satisfied_fraction, true);
  count_violation(out.inside_planning_bounds, out.inside_bounds_fraction, true);
  return out;
}

std::vector<FlownCheck> PathChecker::fly(const std::vector<Vec3>& path) const {
  std::vector<FlownCheck> out;
  for (const Vec3& p : path) {
    if (!p.allFinite()) return out;
  }
  const std::vector<L1Flight> flights = px4_flights(spec_.envelope);
  if (flights.empty()) return out;
  // the lowest flight found without sight lines (one that stops short of
  // the end first: that fails the check too), then reported with them
  std::size_t lowest = 0;
  std::pair<bool, double> lowest_key(true, std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < flights.size(); ++i) {
    const FlownCheck f = fly_once(*this, path, flights[i], false, nullptr);
    const std::pair<bool, double> key(f.reached_end, f.least_clearance_m);
    if (key < lowest_key) lowest_key = key, lowest = i;
  }
  for (std::size_t i = 0; i < flights.size(); ++i) {
    if (i != 0 && i + 1 != flights.size() && i != lowest) continue;
    out.push_back(fly_once(*this, path, flights[i], true, nullptr));
    out.back().lowest = i == lowest;
    out.back().flights_flown = static_cast<int>(flights.size());
  }
  return out;
}

std::vector<L1Flight> px4_flights(const VehicleEnvelope& e) {
  std::vector<L1Flight> out;
  if (!is_px4_fixed_wing(e) || !(e.acceptance_radius_m > 0) || !(e.speed_m_per_s > 0)) return out;
  // PX4 1.13 (L1) at its ground speed: the next waypoint within the mission's
  // radius or the L1 distance, the larger (fly_l1 takes the larger); the
  // height held the L1 distance or the loiter radius early, the larger
  // (FixedwingPositionControl::control_auto_position); climb and sink at the
  // envelope's angles at cruise airspeed, whatever the wind, so that a
  // tailwind climbs less a metre flown; a waypoint taken only within
  // NAV_FW_ALT_RAD of its height.
  auto at = [&e](double ground_speed_m_per_s) {
    L1Flight f;
    f.ground_speed_m_per_s = ground_speed_m_per_s;
    f.switch_distance_m = e.acceptance_radius_m;
    f.altitude_hold_m = std::max(f.l1_distance_m(), kPx4LoiterRadiusM);
    f.max_climb_m_per_s = e.speed_m_per_s * std::tan(e.max_climb_deg * kRadPerDeg);
    f.max_sink_m_per_s = e.speed_m_per_s * std::tan(e.max_descent_deg * kRadPerDeg);
    f.altitude_gate_m = kPx4AltitudeAcceptanceM;
    return f;
  };
  const int steps = e.max_wind_m_per_s > 0
                        ? static_cast<int>(std::ceil(std::min(e.max_wind_m_per_s / kPx4GroundSpeedStepMPerS,
                                                              static_cast<double>(kMaxPx4Flights - 1))))
                        : 0;
  for (int i = 0; i <= steps; ++i) out.push_back(at(e.speed_m_per_s + e.max_wind_m_per_s * i / std::max(steps, 1)));
  return out;
}

bool meets_less(const PathCheck& a, const PathCheck& b) {
  if (a.all_met != b.all_met) return b.all_met;
  if (a.all_met) return false;
  // as better() ranks them: the envelope and the bounds first
  if (std::abs(a.flight_violation - b.flight_violation) > PathCheck::kViolationTie) {
    return a.flight_violation > b.flight_violation;
  }
  return a.violation > b.violation + PathCheck::kViolationTie;
}

}  // namespace visvol::rt

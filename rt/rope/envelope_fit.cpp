#include "rt/rope/envelope_fit.hpp"

#include <algorithm>
#include <cmath>

#include "base/angles.hpp"
#include "base/tolerances.hpp"
#include "rt/rope/fillet.hpp"
#include "rt/rope/l1_track.hpp"
#include "rt/rope/path_check.hpp"
#include "rt/rope/terrain_probe.hpp"
#include "rt/rope/track_ground.hpp"

namespace visvol::rt {

namespace {

constexpr int kTurnPasses = 400;
constexpr int kHeightPasses = 60;
// Rounds of turns then heights: a vertex the heights insert shortens the
// segments beside it, and with them the fillets their turns may use.
constexpr int kTurnRounds = 4;
// Where a segment is split, as a fraction of it: never at its ends, where the
// split would leave the turns beside it no room.
constexpr double kSplitMin = 0.25, kSplitMax = 0.75;
// Segments shorter than this (horizontally, m) are not split: the pieces
// would be under a metre, where a millimetre of rounding in a written file
// moves a slope by more than the fit's angle margin, and a band that a
// segment this short cannot hold is not held by splitting it (a skeptic
// found plans whose first segment was split to millimetres, 220 waypoints
// within 2.5 cm of the start).
constexpr double kMinSplitM = 4.0;

struct Band {
  double lo = 0, hi = 0;
};

constexpr double kNoGround = -std::numeric_limits<double>::infinity();

// Heights allowed above (x, y): the envelope first; the hulls narrow it but
// yield to it (clearance before a hidden-from hull, the ceiling before a
// visible-to hull). `behind_m`: the highest ground under the track behind
// the point that a vehicle taking its heights early may be over at this
// height (track_ground.hpp). `margins`: false for the limits themselves,
// without the fit's margins inside them.
Band band_at(const EnvelopeFitSpec& s, const fields::Heightfield& t, double x, double y, double behind_m = kNoGround,
             bool margins = true) {
  const VehicleEnvelope& e = s.envelope;
  const double g = fields::bilinear_height(t, t.i_of(x), t.j_of(y));  // clamped to the grid
  const double margin_m = margins ? s.margin_m : 0.0, hull_margin_m = margins ? s.hull_margin_m : 0.0;
  Band b;
  b.lo = std::max(g, behind_m) + e.clearance_m + margin_m;
  b.hi = std::min({g + e.max_agl_m - margin_m, e.max_altitude_m - margin_m, s.top_m});
  double lo = b.lo, hi = b.hi;
  for (const PointHull* h : s.above) lo = std::max(lo, h->at(x, y) + hull_margin_m);
  for (const PointHull* h : s.below) hi = std::min(hi, h->at(x, y) - hull_margin_m);
  b.hi = std::max(b.lo, std::min(b.hi, hi));
  b.lo = std::min(b.hi, std::max(b.lo, lo));
  return b;
}

// Without points standing on (or within `min_m` horizontally of) the one
// before them: a vertical step is never flyable, and the heights are fitted
// afterwards anyway. The ends stay.
std::vector<Vec3> without_repeats(const std::vector<Vec3>& path, double min_m) {
  std::vector<Vec3> out;
  auto apart = [&](const Vec3& a, const Vec3& b) { return std::hypot(a.x() - b.x(), a.y() - b.y()) > min_m; };
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (out.empty()) {
      out.push_back(path[i]);
    } else if (i + 1 == path.size()) {
      if (out.size() > 1 && !apart(path[i], out.back())) out.pop_back();  // the end wins
      out.push_back(path[i]);
    } else if (apart(path[i], out.back())) {
      out.push_back(path[i]);
    }
  }
  return out;
}

void clamp_to_bounds(std::vector<Vec3>& p, const fields::Bounds2D& b) {
  for (std::size_t i = 1; i + 1 < p.size(); ++i) {
    p[i].x() = std::clamp(p[i].x(), b.xmin_m, b.xmax_m);
    p[i].y() = std::clamp(p[i].y(), b.ymin_m, b.ymax_m);
  }
}

// Laplacian passes on the horizontal position of the vertices whose fillet
// is too tight.
bool turns_fit(const std::vector<Vec3>& p, double radius_m) {
  if (!(radius_m > 0)) return true;
  for (double r : turn_radii_m(p.data(), static_cast<int>(p.size())))
    if (r < radius_m) return false;
  return true;
}

void relax_turns(std::vector<Vec3>& p, double radius_m) {
  if (!(radius_m > 0) || p.size() < 3) return;
  for (int pass = 0; pass < kTurnPasses; ++pass) {
    bool moved = false;
    const std::vector<double> radii = turn_radii_m(p.data(), static_cast<int>(p.size()));
    for (std::size_t i = 1; i + 1 < p.size(); ++i) {
      if (radii[i] >= radius_m) continue;
      const double mx = 0.5 * (p[i - 1].x() + p[i + 1].x()), my = 0.5 * (p[i - 1].y() + p[i + 1].y());
      p[i].x() += 0.5 * (mx - p[i].x());
      p[i].y() += 0.5 * (my - p[i].y());
      moved = true;
    }
    if (!moved) return;
  }
}

// The heights nearest `target` within [lo, hi] per vertex and the slope
// limits per segment, ends fixed; false when no heights satisfy them all
// (the heights then keep the slopes and come as near the band as they can).
bool fit_heights(const std::vector<Vec3>& p, const std::vector<double>& lo, const std::vector<double>& hi,
                 double climb_per_m, double descent_per_m, const std::vector<double>& slope_share,
                 std::vector<double>& z) {
  const std::size_t n = p.size();
  std::vector<double> rise(n - 1), drop(n - 1), C(n), D(n);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double h = std::hypot(p[i + 1].x() - p[i].x(), p[i + 1].y() - p[i].y());
    rise[i] = climb_per_m * h * slope_share[i];
    drop[i] = descent_per_m * h * slope_share[i];
  }
  // backwards: heights from which the end stays reachable
  C[n - 1] = D[n - 1] = p[n - 1].z();
  bool feasible = true;
  for (std::size_t i = n - 1; i-- > 0;) {
    C[i] = std::max(lo[i], C[i + 1] - rise[i]);
    D[i] = std::min(hi[i], D[i + 1] + drop[i]);
    feasible = feasible && C[i] <= D[i] + 1e-9;
  }
  // forwards: nearest the target inside both
  z.assign(n, 0.0);
  z[0] = p[0].z();
  for (std::size_t i = 1; i < n; ++i) {
    const double step_lo = z[i - 1] - drop[i - 1], step_hi = z[i - 1] + rise[i - 1];
    const double a = std::max(C[i], step_lo), b = std::min(D[i], step_hi);
    if (a <= b + 1e-9) {
      z[i] = std::clamp(p[i].z(), a, std::max(a, b));
    } else {
      feasible = false;
      z[i] = std::clamp(C[i] <= D[i] ? std::clamp(p[i].z(), C[i], D[i]) : C[i], step_lo, step_hi);
    }
  }
  z[n - 1] = p[n - 1].z();  // the ends are the user's: where they cannot be reached, the check says so
  return feasible;
}

// The share of the slope limits each segment may use so that the arcs a
// fixed-wing flies by the corners hold them too: an arc of turn theta at a
// corner climbs (s_in + s_out) / 2 / k, k = theta / (2 tan(theta / 2)) <= 1
// (it is shorter than the legs it cuts), so both legs keep to k of the
// limit. 1 everywhere without arcs.
std::vector<double> slope_shares(const std::vector<Vec3>& p, double min_turn_radius_m) {
  std::vector<double> share(p.size() > 1 ? p.size() - 1 : 0, 1.0);
  const std::vector<std::optional<Fillet>> arcs =
      corner_fillets(p.data(), static_cast<int>(p.size()), min_turn_radius_m);
  for (std::size_t first = 0; first < arcs.size(); ++first) {
    if (!arcs[first]) continue;
    const double k = arc_slope_share(arcs[first]->turn_rad);
    std::size_t last = first;  // the corner's run of vertices on one spot
    while (last + 1 < p.size() && same_spot(p[last + 1], p[first])) ++last;
    share[first - 1] = std::min(share[first - 1], k);
    if (last < share.size()) share[last] = std::min(share[last], k);
  }
  return share;
}

// The least share of a worst sample's height a vertex beside a fixed end is
// moved for (a sample at the end itself would ask for an unbounded move).
constexpr double kMinEndShare = 0.05;

struct SegmentMiss {
  double deficit = 0, excess = 0;          // worst under the band's floor, over its ceiling (m)
  double worst_t = 0.5;                    // where the larger of them is, as a fraction of the segment
  double deficit_t = 0.5, excess_t = 0.5;  // where each is
  // under the floor of the ground behind where the fixed ends put it out of
  // reach: not inside the envelope, and nothing the fit can move mends it
  bool out_of_reach = false;
};

// The highest ground behind a point of the track, `along_m` from its start,
// that the vehicle may be over at the point's height (kNoGround without an
// acceptance radius). Never more than the ends let the path clear: a floor
// the fixed ends put out of reach (an end low after a ridge) is the check's
// to report, not the fit's to chase for its every pass.
struct GroundBehind {
  const TrackGround* track = nullptr;
  double reach_m = 0;   // the altitude hold (rt::altitude_hold_m) and two of the fit's sample steps
  double hold_m = 0;    // the altitude hold: a segment no longer than it is held
  double radius_m = 0;  // the switch distance (rt::switch_distance_m): where the next waypoint is taken
  double start_z = 0, end_z = 0, length_m = 0;
  double climb_per_m = 0, descent_per_m = 0;
  double above_m = 0;  // the clearance and the fit's margin
  // as the checker judges it (its window at most a step past the radius, no margin)
  double judged_reach_m = 0, clearance_m = 0;
  bool out_of_reach(double along_m, double z_m) const {
    return track != nullptr && uncapped(along_m) > (*this)(along_m) &&
           z_m < track->highest_m(along_m - judged_reach_m, along_m) + clearance_m - kHeightTolM;
  }
  double uncapped(double along_m) const {
    return track != nullptr ? track->highest_m(along_m - reach_m, along_m) : kNoGround;
  }
  double operator()(double along_m) const {
    if (track == nullptr) return kNoGround;
    return std::min(uncapped(along_m), reachable(along_m));
  }
  double reachable(double along_m) const {
    return std::min(start_z + climb_per_m * along_m, end_z + descent_per_m * (length_m - along_m)) - above_m;
  }

  // The held stretches of the segments no longer than the hold beside
  // vertex i of a path whose vertices lie `along` the track (a split point
  // lies on it): flown no lower than the lower of their two heights, so
  // vertex i's height must clear their ground (track_ground.hpp).
  double held_uncapped(const std::vector<double>& along, std::size_t i) const {
    if (track == nullptr || along.size() < 2) return kNoGround;
    const std::size_t n = along.size();
    double ground = kNoGround;
    auto stretch = [&](std::size_t first) {  // segment first..first+1, at its lower height either way
      if (along[first + 1] - along[first] > hold_m) return;
      const TrackGround::Stretch s = track->held_stretch_at(along[first], along[first + 1], radius_m);
      if (!s.empty()) ground = std::max(ground, track->highest_m(s.from_m, s.to_m));
    };
    if (i > 0) stretch(i - 1);
    if (i + 1 < n) stretch(i);
    return ground;
  }
  double held(const std::vector<double>& along, std::size_t i) const {
    const double ground = held_uncapped(along, i);
    return ground == kNoGround ? kNoGround : std::min(ground, reachable(along[i]));
  }
  // Segment i (heights z_i to z_next) no longer than the hold, judged as
  // the checker judges it (TrackGround::held_clearance_m, by position).
  bool held_unmet(const std::vector<double>& along, std::size_t i, double z_i, double z_next) const {
    if (track == nullptr || along[i + 1] - along[i] > hold_m) return false;
    return track->held_clearance_at_m(along[i], along[i + 1], z_i, z_next, radius_m) < clearance_m - kHeightTolM;
  }
};

// Horizontal distance along the path to each vertex.
std::vector<double> along_m(const std::vector<Vec3>& p) {
  std::vector<double> out(p.size(), 0.0);
  for (std::size_t i = 1; i < p.size(); ++i) {
    out[i] = out[i - 1] + std::hypot(p[i].x() - p[i - 1].x(), p[i].y() - p[i - 1].y());
  }
  return out;
}

// What a fixed end lacks of its band: the segment beside it is asked for
// that much less at the end, tapering to nothing at its other vertex (a
// sample beside the end cannot be mended by moving the other vertex: it
// was asked for the miss over the sample's share of its height,
// kMinEndShare, pass after pass; a path 130 m over a 100 m plain, its ends
// exactly at the clearance, had its corner raised to 282 m and no fit).
// Never below the limits themselves but by what the end lacks of them
// (`bare_*`): a hull's 5 m margin at the end is no licence to pass under
// the clearance over a knoll beside it. `outside`: the end lacks some of
// the limits, so the path is not inside the envelope.
struct EndRelief {
  double lo_m = 0, hi_m = 0;            // under the band's floor, over its ceiling
  double bare_lo_m = 0, bare_hi_m = 0;  // the same without the fit's margins
  bool outside = false;
  bool any() const { return lo_m > 0 || hi_m > 0; }
};
EndRelief end_relief(const EnvelopeFitSpec& s, const fields::Heightfield& t, const Vec3& end, double behind_m) {
  const Band with = band_at(s, t, end.x(), end.y(), behind_m);
  const Band bare = band_at(s, t, end.x(), end.y(), behind_m, false);
  EndRelief r;
  r.lo_m = std::max(0.0, with.lo - end.z());
  r.hi_m = std::max(0.0, end.z() - with.hi);
  r.bare_lo_m = std::max(0.0, bare.lo - end.z());
  r.bare_hi_m = std::max(0.0, end.z() - bare.hi);
  r.outside = r.bare_lo_m > kHeightTolM || r.bare_hi_m > kHeightTolM;
  return r;
}

// Segment a-b starts `a_m` along the track (GroundBehind); relief_a and
// relief_b: what its ends lack of their bands where they are fixed ends.
SegmentMiss segment_miss(const EnvelopeFitSpec& s, const fields::Heightfield& t, const Vec3& a, const Vec3& b,
                         double step_m, const GroundBehind& behind, double a_m, const EndRelief& relief_a = {},
                         const EndRelief& relief_b = {}) {
  SegmentMiss m;
  const double len = std::hypot(b.x() - a.x(), b.y() - a.y());
  const int k = std::max(2, static_cast<int>(std::ceil(len / step_m)));
  double worst = 0;
  auto judge = [&](const Vec3& p, double f) {
    const double at_m = a_m + f * len, ground_behind_m = behind(at_m);
    const Band band = band_at(s, t, p.x(), p.y(), ground_behind_m);
    double floor_m = band.lo - ((1 - f) * relief_a.lo_m + f * relief_b.lo_m);
    double ceiling_m = band.hi + ((1 - f) * relief_a.hi_m + f * relief_b.hi_m);
    if (relief_a.any() || relief_b.any()) {
      const Band bare = band_at(s, t, p.x(), p.y(), ground_behind_m, false);
      floor_m = std::max(floor_m, bare.lo - ((1 - f) * relief_a.bare_lo_m + f * relief_b.bare_lo_m));
      ceiling_m = std::min(ceiling_m, bare.hi + ((1 - f) * relief_a.bare_hi_m + f * relief_b.bare_hi_m));
    }
    const double d = floor_m - p.z(), e = p.z() - ceiling_m;
    if (d > m.deficit) m.deficit = d, m.deficit_t = f;
    if (e > m.excess) m.excess = e, m.excess_t = f;
    if (behind.out_of_reach(at_m, p.z())) m.out_of_reach = true;
    if (std::max(d, e) > worst) {
      worst = std::max(d, e);
      m.worst_t = f;
    }
  };
  for (int q = 1; q < k; ++q) {
    const double f = static_cast<double>(q) / k;
    judge(a + f * (b - a), f);
  }
  // and where the terrain under the segment is extreme between the samples
  // (the checker finds those exactly): the band's terrain terms are held there
  for_each_terrain_probe(t, a, b, [&](const Vec3& p, double f) {
    if (f > 0 && f < 1) judge(p, f);
  });
  return m;
}

// An arc whose heights follow less of its corner's move than this is moved
// as if they followed this much: the band then ends the fit (not feasible)
// in a few passes rather than creeping.
constexpr double kMinCornerShare = 0.1;

// How far an arc a fixed-wing flies by a corner on (rt/rope/fillet.hpp)
// leaves the band, at the checker's samples along it.
SegmentMiss arc_miss(const EnvelopeFitSpec& s, const fields::Heightfield& t, const Fillet& f, double step_m) {
  SegmentMiss m;
  const int k = std::max(2, static_cast<int>(std::ceil(f.length_m() / step_m)));
  auto judge = [&](const Vec3& p) {
    const Band band = band_at(s, t, p.x(), p.y());
    m.deficit = std::max(m.deficit, band.lo - p.z());
    m.excess = std::max(m.excess, p.z() - band.hi);
  };
  for_each_arc_point(f, k, t, judge, [&](const Vec3& p, double) { judge(p); });
  return m;
}

// Where a PX4 fixed-wing's flights (rt::px4_flights) come under the
// clearance, cutting the corners or climbing behind the legs: the legs they fly there are raised by the
// deficit and the margin, each vertex by that over its share of the flown
// point's height (beside a fixed end, as segments' misses are), where the
// share is at least half (a point nearer a fixed end than the vertex is the
// end's: the check reports it). The track sampled as the check samples it. True
// when a bound moved; `short_of` true when a flight came under the
// clearance at all (raised or not).
bool raise_for_flights(const EnvelopeFitSpec& spec, const fields::Heightfield& t, const std::vector<Vec3>& fitted,
                       const std::vector<double>& z, std::vector<double>& lo, const std::vector<double>& hi,
                       bool& short_of) {
  bool moved = false;
  const std::size_t n = fitted.size();
  for (L1Flight flight : px4_flights(spec.envelope)) {
    flight.record_every_m = kSightStepPosts * t.spacing_m;  // as the check samples it
    for (const FlownPoint& q : fly_l1(fitted, flight).points) {
      const double ground = fields::bilinear_height(t, t.i_of(q.p_m.x()), t.j_of(q.p_m.y()));
      const double deficit = ground + spec.envelope.clearance_m - q.p_m.z();
      if (deficit <= 0.5 * kHeightTolM) continue;
      short_of = true;
      const auto a = static_cast<std::size_t>(q.leg);
      const double u = leg_fraction(fitted[a], fitted[a + 1], q.p_m.x(), q.p_m.y());
      for (std::size_t v : {a, a + 1}) {
        if (v == 0 || v + 1 == n) continue;
        const double share = v == a ? (a + 2 == n ? 1.0 - u : 1.0) : (a == 0 ? u : 1.0);
        if (share < 0.5) continue;
        const double raised = std::min(z[v] + (deficit + spec.margin_m) / share, hi[v]);
        if (raised > lo[v] + 1e-9) lo[v] = raised, moved = true;
      }
    }
  }
  return moved;
}

EnvelopeFit fit_once(const std::vector<Vec3>& path, const EnvelopeFitSpec& spec, const fields::Heightfield& terrain) {
  EnvelopeFit out;
  std::vector<Vec3> p = without_repeats(path, 0.05 * terrain.spacing_m);
  if (p.size() < 2) {
    out.path = p;
    return out;
  }
  if (spec.planning_bounds) clamp_to_bounds(p, *spec.planning_bounds);
  relax_turns(p, spec.envelope.min_turn_radius_m * (1 + spec.turn_margin));
  const double step = spec.step_m > 0 ? spec.step_m : 0.25 * terrain.spacing_m;
  auto slope = [&](double limit_deg) {
    const double aim_deg = limit_deg - std::min(spec.angle_margin_deg, 0.5 * limit_deg);
    return std::tan(std::min(aim_deg, 89.99) * kRadPerDeg);
  };
  const double climb = slope(spec.envelope.max_climb_deg);
  const double descent = slope(spec.envelope.max_descent_deg);
  const std::size_t max_points = spec.max_points > 0 ? spec.max_points : 4 * p.size() + 64;

  // an acceptance radius: the track's ground behind each point, made anew
  // when the turns move the track (a split leaves it as it is). Two sample
  // steps more than the radius: a path held at the samples then clears it
  // everywhere, and at the checker's finer samples with one step more.
  std::optional<TrackGround> track;
  GroundBehind behind;
  auto set_track = [&]() {
    const double switch_m = switch_distance_m(spec.envelope);
    if (!(switch_m > 0)) return;
    track.emplace(terrain, p.data(), static_cast<int>(p.size()));
    const double hold_m = altitude_hold_m(spec.envelope);
    behind = {&*track,       hold_m + 2 * step,        hold_m, switch_m, p.front().z(),
              p.back().z(),  track->length_m(),        climb,  descent,  spec.envelope.clearance_m + spec.margin_m,
              hold_m + step, spec.envelope.clearance_m};
  };
  std::vector<double> lo(p.size()), hi(p.size()), z;
  auto set_band = [&](std::size_t i, const std::vector<double>& along) {
    const bool end = i == 0 || i + 1 == p.size();
    const double ground = std::max(behind(along[i]), behind.held(along, i));
    const Band b = end ? Band{p[i].z(), p[i].z()} : band_at(spec, terrain, p[i].x(), p[i].y(), ground);
    lo[i] = b.lo;
    hi[i] = b.hi;
  };
  auto set_bands = [&]() {
    set_track();
    const std::vector<double> along = along_m(p);
    for (std::size_t i = 0; i < p.size(); ++i) set_band(i, along);
  };
  set_bands();

  bool feasible = false;
  int round = 1;
  for (int pass = 0; pass < kHeightPasses * kTurnRounds; ++pass) {
    feasible = fit_heights(p, lo, hi, climb, descent, slope_shares(p, spec.envelope.min_turn_radius_m), z);
    std::vector<Vec3> fitted = p;
    for (std::size_t i = 0; i < p.size(); ++i) fitted[i].z() = z[i];
    bool changed = false;
    // Every segment that cannot hold the band gets a vertex at its worst
    // sample, all in one pass (one a pass ran out of passes on paths that
    // needed hundreds, and left them over the band between their vertices).
    std::vector<std::pair<std::size_t, Vec3>> splits;
    const std::vector<double> along = along_m(p);  // of the vertices before the splits
    const EndRelief relief_start = end_relief(spec, terrain, p.front(), behind(along.front()));
    const EndRelief relief_end = end_relief(spec, terrain, p.back(), behind(along.back()));
    if (relief_start.outside || relief_end.outside) feasible = false;
    // every segment no longer than the hold judged as the checker judges it:
    // a floor the ends put out of reach, a fixed end under its segment's
    // stretch or a floor under a lowered ceiling is the check's to report
    for (std::size_t i = 0; i + 1 < p.size(); ++i)
      if (behind.held_unmet(along, i, z[i], z[i + 1])) feasible = false;
    for (std::size_t i = 0; i + 1 < p.size(); ++i) {
      const EndRelief relief_a = i == 0 ? relief_start : EndRelief{};
      const EndRelief relief_b = i + 2 == p.size() ? relief_end : EndRelief{};
      const SegmentMiss m =
          segment_miss(spec, terrain, fitted[i], fitted[i + 1], step, behind, along[i], relief_a, relief_b);
      if (m.out_of_reach) feasible = false;
      if (m.deficit <= 1e-6 && m.excess <= 1e-6) continue;
      feasible = false;
      // between the vertices the band asks both vertices to move by the miss;
      // beside a fixed end, the other by the miss over its share of the
      // worst sample's height (by the miss alone it crept there a pass at a
      // time: an early-descent floor near the end took hundreds of passes)
      const double shift = m.deficit > 1e-6 ? m.deficit : -m.excess;
      const double shift_t = m.deficit > 1e-6 ? m.deficit_t : m.excess_t;
      const bool fixed_i = i == 0, fixed_next = i + 2 == p.size();
      const double share_i = fixed_next ? 1.0 - shift_t : 1.0, share_next = fixed_i ? shift_t : 1.0;
      bool moved = false, held = true;
      for (std::size_t v : {i, i + 1}) {
        if (v == 0 || v + 1 == p.size()) continue;
        const double share = std::max(v == i ? share_i : share_next, kMinEndShare);
        const double want = z[v] + shift / share;
        if (shift > 0) {
          held = held && want <= hi[v];
          const double raised = std::min(want, hi[v]);
          if (raised > lo[v] + 1e-9) lo[v] = raised, moved = true;
        } else {
          held = held && want >= lo[v];
          const double lowered = std::max(want, lo[v]);
          if (lowered < hi[v] - 1e-9) hi[v] = lowered, moved = true;
        }
      }
      changed = changed || moved;
      if ((held && moved) || p.size() + splits.size() >= max_points) continue;
      if (std::hypot(p[i + 1].x() - p[i].x(), p[i + 1].y() - p[i].y()) < kMinSplitM) continue;
      // the segment cannot hold the band: a vertex at its worst sample
      splits.emplace_back(i, p[i] + std::clamp(m.worst_t, kSplitMin, kSplitMax) * (p[i + 1] - p[i]));
    }
    // from the last, so that the indices before stay; then heights again
    for (auto split = splits.rbegin(); split != splits.rend(); ++split) {
      const auto at = static_cast<std::ptrdiff_t>(split->first) + 1;
      p.insert(p.begin() + at, split->second);
      lo.insert(lo.begin() + at, 0.0);
      hi.insert(hi.begin() + at, 0.0);
      changed = true;
    }
    // the new vertices' bands, between their neighbours after every split;
    // a neighbour's floor only rises (a split may make a segment beside it
    // short enough to be held)
    if (!splits.empty()) {
      const std::vector<double> split_along = along_m(p);
      for (std::size_t k = 0; k < splits.size(); ++k) {
        const std::size_t at = splits[k].first + 1 + k;
        set_band(at, split_along);
        for (std::size_t v : {at - 1, at + 1}) {
          if (v == 0 || v + 1 >= p.size()) continue;
          const double ground = behind.held(split_along, v);
          const double floor = band_at(spec, terrain, p[v].x(), p[v].y(), ground).lo;
          lo[v] = std::max(lo[v], std::min(floor, hi[v]));
        }
      }
    }
    // the arcs inside the corners: the corner (every vertex on its spot)
    // moves by the miss over the share of that move the arc's heights
    // follow; where it cannot (an arc that spans a segment follows the
    // ends), the fit is not feasible
    const std::vector<std::optional<Fillet>> arcs =
        changed ? std::vector<std::optional<Fillet>>()
                : corner_fillets(fitted.data(), static_cast<int>(fitted.size()), spec.envelope.min_turn_radius_m);
    for (std::size_t i = 1; !changed && i + 1 < p.size(); ++i) {
      if (!arcs[i]) continue;
      const SegmentMiss m = arc_miss(spec, terrain, *arcs[i], step);
      if (m.deficit <= 1e-6 && m.excess <= 1e-6) continue;
      feasible = false;
      const double follow = std::max(arcs[i]->corner_share, kMinCornerShare);
      for (std::size_t j = i; j + 1 < p.size() && (j == i || same_spot(p[j], p[i])); ++j) {
        if (m.deficit > 1e-6) {
          const double raised = std::min(z[j] + m.deficit / follow, hi[j]);
          if (raised > lo[j] + 1e-9) lo[j] = raised, changed = true;
        } else {
          const double lowered = std::max(z[j] - m.excess / follow, lo[j]);
          if (lowered < hi[j] - 1e-9) hi[j] = lowered, changed = true;
        }
      }
    }
    if (!changed) {
      bool short_of = false;
      changed = raise_for_flights(spec, terrain, fitted, z, lo, hi, short_of);
      if (short_of) feasible = false;
    }
    if (!changed) {
      for (std::size_t i = 0; i < p.size(); ++i) p[i].z() = z[i];
      const bool turns = turns_fit(p, spec.envelope.min_turn_radius_m);
      if (!turns && round < kTurnRounds) {
        // the splits tightened some turns: open them again, then the heights
        ++round;
        relax_turns(p, spec.envelope.min_turn_radius_m * (1 + spec.turn_margin));
        if (spec.planning_bounds) clamp_to_bounds(p, *spec.planning_bounds);
        set_bands();
        continue;
      }
      out.feasible = feasible && turns;
      out.path = std::move(p);
      return out;
    }
  }
  // the passes ran out: the last heights, not proven
  (void)fit_heights(p, lo, hi, climb, descent, slope_shares(p, spec.envelope.min_turn_radius_m), z);
  for (std::size_t i = 0; i < p.size(); ++i) p[i].z() = z[i];
  out.path = std::move(p);
  return out;
}

}  // namespace

EnvelopeFit fit_to_envelope(const std::vector<Vec3>& path, const EnvelopeFitSpec& spec,
                            const fields::Heightfield& terrain) {
  EnvelopeFit fit = fit_once(path, spec, terrain);
  if (fit.feasible || (spec.below.empty() && spec.above.empty())) return fit;
  // The hulls are the observers' wishes, the envelope the vehicle's limits:
  // where both cannot hold, the envelope does. (A visible-to hull over the
  // ceiling pinned every vertex to it, and the last leg dropped 21 m in 5 m
  // to an end 58 m above the ground under a 45 degree descent limit.)
  // The hulls then only aim the heights: each vertex starts inside them, and
  // the fit keeps it as near there as the envelope lets it.
  std::vector<Vec3> aimed = path;
  for (std::size_t i = 1; i + 1 < aimed.size(); ++i) {
    const Band b = band_at(spec, terrain, aimed[i].x(), aimed[i].y());
    aimed[i].z() = std::clamp(aimed[i].z(), b.lo, b.hi);
  }
  EnvelopeFitSpec bare = spec;
  bare.below.clear();
  bare.above.clear();
  EnvelopeFit flyable = fit_once(aimed, bare, terrain);
  return flyable.feasible ? flyable : fit;
}

}  // namespace visvol::rt

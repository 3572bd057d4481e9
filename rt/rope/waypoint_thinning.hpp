// Waypoint thinning: the fewest vertices of a path that stay within a
// tolerance of it.
//
// The envelope fit splits segments where the terrain or an observer's hull
// needs it, and on a straight stretch every split point lies on one line: a
// fixed-wing mission of the SF North and Taunus packs had a waypoint every 2
// to 4 m over half its length (200 to 300 legs under 10 m, 0.2 s apart at 20
// m/s), which an autopilot reaches several at a time. Thinning keeps the
// vertices the shape needs: Douglas-Peucker, each removed vertex within
// `horizontal_m` across and `vertical_m` above or below the leg that replaces
// it (measured at its horizontal projection onto the leg). The ends are
// always kept. What the thinned path meets is for rt::PathChecker to judge:
// a leg may pass over other terrain than the vertices it replaced.
// Offline: allocates.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "rt/rope/global_search.hpp"
#include "rt/rope/path_check.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

struct ThinningTolerance {
  double horizontal_m = 0.5;
  double vertical_m = 0.2;
};

// How far point p lies from leg a-b, as a multiple of the tolerance (the
// larger of its horizontal and vertical shares): <= 1 is within it. The
// vertical share is taken where p lies seen from above, so a steep leg is
// judged strictly (a point on a multirotor's climb but off its spot stays);
// infinite where a coordinate is not finite.
double thinning_deviation(const Vec3& a, const Vec3& b, const Vec3& p, const ThinningTolerance& tol);

// Whether vertices `first` and `last` of a path may be joined by one leg
// (the vertices between dropped) for more than the shape: the held heights
// of an acceptance radius (held_legs below).
using LegTest = std::function<bool(int first, int last)>;

// The indices of `path` that the thinned path keeps, in order: the first and
// the last, those `keep` marks (where given: one flag a vertex), and every
// vertex the shape needs; where `leg_holds` is given, a span it refuses
// keeps its middle vertex too. Douglas-Peucker costs n log n on a path and
// up to n^2 on a contrived one: past kMaxThinningWork deviations a vertex,
// nothing is dropped (every index is returned).
inline constexpr double kMaxThinningWork = 64.0;
std::vector<int> thinned_indices(const std::vector<Vec3>& path, const ThinningTolerance& tol,
                                 const std::vector<bool>* keep = nullptr, const LegTest* leg_holds = nullptr);

// The thinned path itself.
std::vector<Vec3> thin_waypoints(const std::vector<Vec3>& path, const ThinningTolerance& tol,
                                 const std::vector<bool>* keep = nullptr, const LegTest* leg_holds = nullptr);

// For a vehicle with an acceptance radius (track_ground.hpp; its switch
// distance and hold grow with the wind, rt::switch_distance_m): a leg
// joining two vertices of `fitted` no farther apart than the hold holds where the
// lower of their heights clears the highest ground of its held stretch on
// the fitted track by the clearance and kThinnedHeldMarginM (PX4 steps to
// the next height on such a leg from the radius before its start: the
// longer the leg, the more ground it is held over). Always true for a longer
// leg and without a radius. Keeps a copy of `fitted` and a pointer to
// `terrain`, which must outlive it.
inline constexpr double kThinnedHeldMarginM = 1.0;
LegTest held_legs(const std::vector<Vec3>& fitted, const VehicleEnvelope& envelope, const fields::Heightfield& terrain);

// The vertices of a path to keep for a vehicle of least turn radius
// `min_turn_radius_m` (0: none): where the path turns within
// kTurnKeptFactor of it. A turn that tight has room for its fillet only
// between legs of near equal length (a circle's chords), and the legs that
// thinning leaves are not: a 200 m arc sampled every 3 m, thinned, left
// 147 m of room at a corner. Straight runs and wide curves thin freely.
inline constexpr double kTurnKeptFactor = 3.0;
std::vector<bool> turns_to_keep(const std::vector<Vec3>& path, double min_turn_radius_m);

// A fitted path thinned for a vehicle: its turns within kTurnKeptFactor of
// `min_turn_radius_m` keep their vertices.
std::vector<Vec3> thin_for_vehicle(const std::vector<Vec3>& fitted, double min_turn_radius_m,
                                   const ThinningTolerance& tol, const LegTest* leg_holds = nullptr);

// The share of F_c a path may lose to have its waypoints thinned (a
// thousandth: the plan bench's answers lost a ten-thousandth at most).
inline constexpr double kThinningFcTie = 1.0e-3;

// `fitted` (judged `fitted_check`) thinned for the checker's vehicle and
// judged again: the thinned path where it meets as much (meets_less) and
// costs under kThinningFcTie of F_c for `objective`; nothing where it does
// not or drops no vertex.
struct ThinnedPath {
  std::vector<Vec3> path;
  PathCheck check;
};
std::optional<ThinnedPath> thinned_as_good(const std::vector<Vec3>& fitted, const PathCheck& fitted_check,
                                           const PathChecker& checker, Objective objective,
                                           const ThinningTolerance& tol = {});

}  // namespace visvol::rt

// The path a crew flies: the rope's path fitted into the vehicle's flight
// envelope off the real-time thread, as `visvol plan` fits its answer
// (rt::fit_to_envelope).
//
//   loop thread   --rope path, limits in force-->  fitter thread
//   fitter thread --flyable path-->                DDS publisher, renderer
//
// The rope stays the operator's: it settles in the field and follows the
// hand. What leaves the console is its projection into the envelope: climb
// and descent within the vehicle's limits on every segment, turns no tighter
// than its radius, inside the pack's planning bounds, heights from the
// clearance up to the ceilings in force
// (the executive's gains, which commands change), under the hull of every
// hidden-from observer in force and over that of every visible-to one (the
// fitter builds its own hulls on the finest level, on its thread, when the
// set in force changes). Where the band of heights and the slope limits
// conflict, the path sent is the nearest the fit found and `unflyable` counts
// it; the session's summary checks the final path exactly (rt::PathChecker):
// the hulls make the observers' requirements likely, the sight lines judge.
//
// Thread-safety: rope_paths() has one producer, the loop thread; the sinks
// have one consumer each; stats() from any thread. Allocates on its own
// thread and at create() only; a failure there (memory) is counted, the last
// path sent stands.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "base/handoff.hpp"
#include "fields/heightfield.hpp"
#include "msg/samples.hpp"
#include "rt/exec/executive.hpp"
#include "rt/rope/envelope_fit.hpp"
#include "rt/rope/field_forces.hpp"
#include "rt/rope/vehicle.hpp"
#include "storage/cached_level.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::app {

// Fits paths on the pack's finest level. Not thread-safe; offline.
class PathFitter {
 public:
  static Result<std::unique_ptr<PathFitter>> create(std::shared_ptr<const storage::Pack> pack,
                                                    const rt::VehicleEnvelope& vehicle, int fc_samples,
                                                    int max_observers);

  // The vehicle's limits with the clearance and the ceilings in force.
  rt::VehicleEnvelope envelope(const rt::ForceGains& gains) const;
  // Builds the hulls of a set of observers on the finest level, each kind
  // folded into one (the lowest hidden-from, the highest visible-to hull),
  // unless they are those of the last set (same sequence). An observer whose
  // hull cannot be built (outside the pack: the executive refused it
  // already) is left out and counted in hull_failures().
  void set_observers(const rt::HullRequest& observers);
  // The path (at most msg::kMaxPathVertices vertices: more are thinned
  // evenly, ends kept) fitted into the envelope; the fit has at most that
  // many vertices too. A path that is not finite gives an empty fit.
  rt::EnvelopeFit fit(const rt::Vec3* vertices, int count, const rt::ForceGains& gains) const;
  // `path` into `out`'s vertices and figures (F_c, length, lowest clearance
  // on the finest level); the header fields are left as they are. False
  // when a brick of the pack the figures need could not be read (the file
  // cut short or changed under the session): the figures are not to be sent.
  bool describe(const std::vector<rt::Vec3>& path, msg::PathSample& out) const;
  // Why the last describe() failed.
  const std::string& read_error() const { return finest_->last_error(); }

  const fields::Heightfield& terrain() const { return terrain_; }
  // Bytes held: the finest level's copies (heights and a cache of bricks),
  // the finest terrain, and two folded hulls of it with observers.
  static std::uint64_t bytes(const storage::Pack& pack, int observers);
  int hull_failures() const { return hull_failures_; }

 private:
  PathFitter() = default;
  rt::VehicleEnvelope vehicle_;
  double top_m_ = 0;
  fields::Bounds2D bounds_;  // the pack's planning bounds: the fit clamps into them
  int fc_samples_ = 128;
  // read through copies, never the mapping: a pack replaced under the
  // session cannot fault this thread
  std::unique_ptr<storage::CachedLevel> finest_;
  std::unique_ptr<rt::FieldForces<storage::CachedLevelRef>> field_;
  fields::Heightfield terrain_;
  std::uint64_t observers_sequence_ = 0;
  std::optional<rt::PointHull> hidden_, visible_;    // the folded hull of each kind
  std::vector<const rt::PointHull*> below_, above_;  // to them, or empty
  bool observers_allowed_ = false;                   // max_observers > 0
  int hull_failures_ = 0;
};

struct FlyableStats {
  std::uint64_t fitted = 0;     // flyable paths sent
  std::uint64_t unflyable = 0;  // of them, outside the envelope somewhere (the nearest the fit found)
  std::uint64_t failed = 0;     // fits that failed (memory, or the pack unreadable), nothing sent
  int hull_failures = 0;        // observers left out of the fit (their hull could not be built)
};

class FlyablePath {
 public:
  // Starts the thread; `to_publisher` and `to_renderer` may be null.
  static Result<std::unique_ptr<FlyablePath>> start(std::unique_ptr<PathFitter> fitter,
                                                    LatestValue<msg::PathSample>* to_publisher,
                                                    LatestValue<msg::PathSample>* to_renderer, double poll_s = 0.02);
  ~FlyablePath();
  FlyablePath(const FlyablePath&) = delete;
  FlyablePath& operator=(const FlyablePath&) = delete;

  // The rope's paths with their limits (rt::ExecutiveOutputs::limited_path).
  LatestValue<rt::LimitedPath>& rope_paths() { return rope_paths_; }
  FlyableStats stats() const;
  // Stops the thread (idempotent); afterwards fitter() may be used.
  void stop();
  const PathFitter& fitter() const { return *fitter_; }
  PathFitter& fitter() { return *fitter_; }  // after stop()

 private:
  FlyablePath(std::unique_ptr<PathFitter> fitter, LatestValue<msg::PathSample>* to_publisher,
              LatestValue<msg::PathSample>* to_renderer, double poll_s);
  void run();
  void send(const rt::LimitedPath& rope);

  std::unique_ptr<PathFitter> fitter_;
  LatestValue<msg::PathSample>* to_publisher_;
  LatestValue<msg::PathSample>* to_renderer_;
  double poll_s_;
  LatestValue<rt::LimitedPath> rope_paths_;
  std::unique_ptr<msg::PathSample> out_;  // large: filled here, copied into the sinks
  std::vector<rt::Vec3> rope_;
  std::atomic<std::uint64_t> fitted_{0}, unflyable_{0}, failed_{0};
  std::atomic<int> hull_failures_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace visvol::app

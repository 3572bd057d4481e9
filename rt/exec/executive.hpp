// The executive: the console's 1 kHz tick, as a PeriodicTask.
//
// Each tick, in this order (the stages of DESIGN.md):
//   1. apply queued commands   (DDS command intake -> CommandQueue; each one
//                               acknowledged applied or failed on the AckQueue;
//                               at most kMaxCommandsPerTick, and work of one
//                               full set-constraints at most: constraint items,
//                               rope vertices laid again),
//                               then put in force hull constraints built since
//                               (every hidden-from and visible-to observer of
//                               the newest set; the clearance and the ceiling
//                               take effect with their command)
//   2. simulated device        (only with a simulation on the in-process bus)
//   3. read the device         (HapticDevice::poll: the CAN driver drains the bus)
//   4. servo                   (proxy, soft joint, force safety)
//   5. rope step               (field forces of the resident level + the grasp)
//   6. command the device      (the force; the CAN driver sends one frame)
//   7. hand off state          (path at path_hz, device status, the rope's box
//                               to the tile pager, the quiescent point)
// Commands are applied at the start of a tick, so a tick computes with one
// consistent set of parameters.
//
// Overruns: the loop calls safe_state() after its limit of overruns in a
// row; the servo then zeroes the device force in the next tick and withholds
// it until the operator grasps again, while the rope keeps stepping.
//
// Operator, pull mode (the paper's mode A): both ends of the rope are held;
// the grasp button grabs the rope point nearest the proxy, which then pulls it
// through the servo's soft joint; the rope side of that force is scaled so that
// 1 mm of hand travel pulls as hard as k3 times the saturated field (the
// paper's k3 U1), capped at ten times that.
// Spool mode (mode B; a set-mode command or the device's mode button switches):
// a short rope (kSpoolLeadSegments) leaves the start toward the end, its far
// end free, and the workspace is re-indexed so that the handle, where it is,
// holds the proxy at that end (as a clutch release re-indexes it: the start
// may lie at the workspace's edge); the grasp button takes that end, and while the operator pulls it
// on along the rope's last segment harder than the saturated field pulls one
// segment (the pull of 1 mm of hand travel at k3 = 1: a slack rope follows
// the hand more closely than that) a segment of the pull mode's length pays
// out, at most one every kSpoolEveryTicks, up to max_segments: the rope slides
// out of the spool at the start along its own path, so the free end moves on
// toward the hand and nothing else moves (Rope::pay_out_at_start). The rope
// settles in the field as it pays out. Once the free end comes within a segment of the end
// (and the rope is kSpoolArrivalSlack longer than the straight line, paying
// out more where it is not) it is held there: both ends fixed, the run goes on as in pull mode (the
// mode stays spool until switched). Switching to pull lays the rope between
// the ends again, unless the spool had arrived (then the rope is kept).
// Commands that lay the rope again (endpoints, start, a rope that stopped being
// finite) return to pull mode; set-model and set-segments are refused while
// the rope is still being spooled out.
//
// Ownership: borrows the resident pack, the haptic device, the simulation and
// every queue and hand-off (all must outlive it); owns the ropes and the servo.
// Thread-safety: tick() and safe_state() on the loop thread; counters() from
// that thread (snapshot() copies them for others through a LatestValue).
// Cost: create() allocates everything (ropes at max_segments, scratch); a
// tick allocates nothing, takes no lock, makes no blocking call.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

#include "base/handoff.hpp"
#include "msg/samples.hpp"
#include "rt/exec/constraint_hulls.hpp"
#include "rt/exec/haptic_device.hpp"
#include "rt/exec/periodic_loop.hpp"
#include "rt/rope/equilibrium.hpp"
#include "rt/rope/field_forces.hpp"
#include "rt/rope/global_search.hpp"
#include "rt/rope/rope.hpp"
#include "rt/servo/servo.hpp"
#include "storage/resident_pack.hpp"

namespace visvol::rt {

// Commands a tick applies at most (a burst waits in the queue for later ticks).
inline constexpr int kMaxCommandsPerTick = 8;
// Spool mode: the rope laid at the start, in segments; ticks between
// pay-outs at least.
inline constexpr int kSpoolLeadSegments = 2;
inline constexpr int kSpoolEveryTicks = 5;
// Length over the straight line a spooled rope has at least once its end is held.
inline constexpr double kSpoolArrivalSlack = 0.02;
// Ticks over which the arrived free end's anchor moves onto the end.
inline constexpr int kSpoolArrivalTicks = 200;
// A mode button press this soon after the last one that switched is ignored
// (a bouncing switch, or a held one seen again after a gap).
inline constexpr std::int64_t kModePressGuardNs = 200'000'000;

struct ExecutiveConfig {
  // The planning problem at start-up (commands change it later).
  Vec3 start_m = Vec3::Zero();  // world metres of the pack's CRS
  Vec3 end_m = Vec3::Zero();
  Objective objective = Objective::hide;
  RopeModel model = RopeModel::articulated;
  int segments = 128;
  int max_segments = 256;  // reserved: set-segments may not exceed it
  double stiffness = 1.0;  // factor on the rope's scaled springs
  double slack = 0.05;     // articulated: extra length over the straight start
  ForceGains gains;        // k1 magnitude (sign from the objective), k2, clearance, ceiling
                           // (max_agl_m, max_altitude_m; infinite: none)
  // Observers in force from the start (hidden-from and visible-to points, as
  // set-constraints gives them): built once set_constraint_hulls() gives the
  // executive a hull builder. Their eyes, and those of every command's
  // observers, are eye_height_m above their points (the planner's --eye-height).
  HullRequest observers;
  double eye_height_m = 2.0;
  // The pack's planning bounds: the rope is pushed back inside them (absent:
  // inside the field's extent).
  std::optional<fields::Bounds2D> planning_bounds;
  double k3_user = 1.0;       // the operator's pull
  bool start_running = true;  // settle from the start, or wait for a start command
  int level = 0;              // the level of detail the rope runs on
  // Hand-offs, in ticks.
  int path_every_ticks = 20;     // 50 Hz
  int fc_every_ticks = 20;       // F_c and the equilibrium check
  int focus_every_ticks = 50;    // the rope's box to the tile pager
  int device_every_ticks = 100;  // device status
  int fc_samples = 128;
  double focus_lead_m = 0.0;  // added around the rope's box (the pager adds its margin too)
  // Haptics (absent without a device).
  servo::ServoConfig servo;               // mapping and coupling are set from the scene when scale is 0
  double workspace_half_mm = 100.0;       // the rope's extent maps onto +-this much hand travel
  double hand_stiffness_n_per_m = 300.0;  // the soft joint as the hand feels it
  double hand_damping_n_s_per_m = 1.0;
  double cue_n = 0.5;  // visibility cue at one reference gradient, N
  char pack_id[msg::kPackIdCapacity] = "pack";
  double period_s = 0.001;  // the loop's period: the rope's time step
  // Springs and gains the step cannot integrate are refused (steps_stably).
  // False only in the test that drives a rope unstable on purpose, to check
  // the finite-state guard behind this check.
  bool refuse_unstable = true;
};

// What the loop thread counts (plain values; copied out through snapshot()).
struct ExecutiveCounters {
  std::uint64_t ticks = 0;
  std::uint64_t commands_applied = 0;
  std::uint64_t commands_failed = 0;
  std::uint64_t acks_dropped = 0;  // the ack queue was full
  std::uint64_t paths = 0;         // path hand-offs
  std::uint64_t safe_states = 0;   // overrun safe states
  std::uint64_t grasps = 0;
  std::uint64_t send_failures = 0;  // device commands refused (the CAN bus: full, down)
  std::uint64_t runs = 0;           // planning runs started
  std::uint64_t hull_sets = 0;      // hidden-from / visible-to hull sets put in force
  std::uint64_t rope_resets = 0;    // the rope's state stopped being finite and was laid again
  std::uint64_t mode_switches = 0;  // pull <-> spool, by command or button
  std::uint64_t mode_refusals = 0;  // mode button presses that could not switch (unstable, no room to lay the rope)
  msg::InteractionMode mode = msg::InteractionMode::pull;
  double spool_paid_out_m = 0.0;   // rope out of the spool in the last spool run (the lead included)
  int spool_segments = 0;          // segments of it
  double spool_gap_m = 0.0;        // from its free end to the end (0 once arrived)
  bool spool_arrived = false;      // its free end reached the end and is held there
  bool spool_at_capacity = false;  // it stopped paying out at max_segments
  bool running = false;            // the rope is stepping
  bool converged = false;
  double fc = 0.0;
  double length_m = 0.0;
  double equilibrium_s = 0.0;  // simulated time of this run when it converged
  double run_s = 0.0;          // simulated time of this run
  HapticState device_state = HapticState::boot;
  servo::SafeReason servo_reason = servo::SafeReason::none;
  bool haptics = false;
};

// The limits in force when a path was handed off (plain data).
struct PathLimits {
  ForceGains gains;       // the clearance and the ceilings
  HullRequest observers;  // the hidden-from and visible-to set in force (none: sequence 0, no points)
};

// A path and the limits in force when it was handed off (plain data).
struct LimitedPath {
  msg::PathSample path;
  PathLimits limits;
};

// Where the executive's outputs go; every pointer may be null.
struct ExecutiveOutputs {
  LatestValue<msg::PathSample>* path = nullptr;         // DDS publisher
  LatestValue<msg::PathSample>* path_render = nullptr;  // renderer
  // Each path with the limits it is held to, in one hand-off: for a
  // consumer that fits it into the envelope.
  LatestValue<LimitedPath>* limited_path = nullptr;
  LatestValue<msg::DeviceStatusSample>* device = nullptr;  // DDS publisher
  msg::AckQueue* acks = nullptr;                           // applied/failed, to command intake
};

// The servo configuration create() derives from a scene: the rope's extent
// (the ends' horizontal distance, at least ten posts of `spacing_m`) onto
// +-workspace_half_mm of hand travel around the ends' midpoint, and the soft
// joint as the hand feels it (the visibility cue is set from the field later).
servo::ServoConfig scene_servo_config(const ExecutiveConfig& c, double spacing_m);
// A pull-mode rope segment between these ends (the articulated rope with its
// slack), m: what spool mode pays out each time.
double pull_segment_m(const Vec3& start_m, const Vec3& end_m, RopeModel model, int segments, double slack);
// Where a spool's lead of kSpoolLeadSegments pull-mode segments ends, m:
// from the start toward the end.
Vec3 spool_lead_end_m(const Vec3& start_m, const Vec3& end_m, RopeModel model, int segments, double slack);
// The hand travel (device frame, mm) that takes a spool's lead free end, as
// the workspace holds it once spool mode begins, to `past` (a fraction of the
// ends' distance) beyond the end: what an operator script drags.
Eigen::Vector3d spool_drag_mm(const ExecutiveConfig& c, double spacing_m, double past);

class Executive final : public PeriodicTask {
 public:
  // Validates the configuration against the pack (endpoints inside and above
  // the terrain, segments within capacity) and reserves everything. `device`
  // may be null (no haptics); `simulation` may be null.
  static Result<std::unique_ptr<Executive>> create(const ExecutiveConfig& config, storage::ResidentPack& field,
                                                   HapticDevice* device, DeviceSimulation* simulation,
                                                   msg::CommandQueue* commands, const ExecutiveOutputs& outputs);
  ~Executive() override;

  void warm_up() override;
  void tick(const TickTime& time) override;
  void safe_state() override;
  // The loop is ending: the servo to its safe state and the device commanded
  // to zero force, disabled (counted in send_failures when the bus refuses).
  void stopping() override;

  // Hidden-from and visible-to constraints (set-constraints) need a hull
  // builder on the executive's level; without one they are refused as
  // unsupported. Requests the configured observers (refused when they are
  // more than the builder takes). Set before the loop starts; `hulls`
  // must outlive the executive.
  Status set_constraint_hulls(ConstraintHulls* hulls);

  // The observers in force (null: none built yet), and whether a newer set
  // is still being built. Loop thread, or any thread once the loop stopped.
  const HullSet* hulls_in_force() const { return in_force_; }
  bool hulls_pending() const { return hull_pending_ != 0; }

  // A switch-terrain command to another pack, once applied: copies its pack
  // id and returns true (any thread; the loop asks nothing more until the
  // console has switched). The console checks the id against its packs first.
  bool terrain_switch(char (&pack_id)[msg::kPackIdCapacity]) const;
  // The console found that pack gone (removed from its catalogue since the
  // command was checked): the session goes on and takes switches again.
  void cancel_terrain_switch() { switch_requested_.store(false, std::memory_order_release); }

  const ExecutiveCounters& counters() const { return counters_; }
  // The counters, handed to another thread every device_every_ticks.
  LatestValue<ExecutiveCounters>& snapshot() { return snapshot_; }
  const Rope& rope() const { return *rope_; }
  const servo::Servo* servo() const { return servo_ ? &*servo_ : nullptr; }
  const HapticDevice* device() const { return device_; }
  const FieldForces<storage::ResidentLevel, storage::ResidentSampler>& forces() const { return *forces_; }
  const ExecutiveConfig& config() const { return config_; }
  // Where the operator's proxy is (world, m), as of the last tick.
  const Vec3& proxy_m() const { return last_proxy_m_; }

 private:
  Executive(const ExecutiveConfig& config, storage::ResidentPack& field);
  Status init(HapticDevice* device, DeviceSimulation* simulation, msg::CommandQueue* commands,
              const ExecutiveOutputs& outputs);

  void apply_commands();
  int command_items(const msg::Command& c) const;
  void install_hulls();
  Status check_observers(const HullRequest& r) const;
  Status check_ceiling(const char* name, const Vec3& p, const ForceGains& g) const;
  bool under_ceiling(const Vec3& p, const ForceGains& g) const;
  const char* observer_problem(const msg::Constraint& k) const;
  const char* constraints_problem(const ForceGains& g, const HullRequest& r) const;
  Errc read_constraints(const msg::Command& c, ForceGains& gains, HullRequest& r, const char*& reason) const;
  Errc apply_constraints(const msg::Command& c, const char*& reason);
  Errc apply(const msg::Command& c, const char*& reason);
  Errc apply_endpoints(const msg::Command& c, const char*& reason);
  Errc apply_weights(const msg::Command& c, const char*& reason);
  Errc apply_stiffness(const msg::Command& c, const char*& reason);
  Errc apply_model(const msg::Command& c, const char*& reason);
  Errc apply_segment_count(const msg::Command& c, const char*& reason);
  Errc apply_switch_terrain(const msg::Command& c, const char*& reason);
  Errc apply_mode(const msg::Command& c, const char*& reason);
  // Pull or spool mode (Errc::unsupported: spool without a device, or the
  // rope would not step stably; the mode and rope unchanged on failure).
  Errc set_mode(msg::InteractionMode mode);
  Errc start_spool();
  void spool();             // spool mode, each tick: pay out, or hold the arrived end
  void hold_arrived_end();  // the end's anchor on its way onto the end, then held there
  void paid_out();          // after a segment paid out
  // A rope laid under the hand: the grasp ends (forces return with a new
  // press of the grasp button); `scene_mapping`: the workspace mapped onto
  // the scene again (pull mode).
  void let_go(bool scene_mapping);
  // the rope is being spooled out (its far end not yet held at the end, or
  // its anchor still on its way there)
  bool spooling() const { return mode_ == msg::InteractionMode::spool && !counters_.spool_arrived; }
  int copy_vertices();  // the rope's vertices into scratch_; their count
  void ack(const msg::Command& c, Errc result, const char* reason);
  Errc restart_rope(const Vec3* polyline, int points, int segments, RopeModel model);
  Errc start_run();
  void set_ends(const Vec3& start, const Vec3& end);
  void update_gains();
  void haptics(std::int64_t now_ns, double t_s);
  void measure();
  void recover_rope();
  void hand_off_path(std::int64_t stamp_ns);
  void hand_off_device(std::int64_t stamp_ns);
  void hand_off_focus();
  int nearest_point(const Vec3& p, double& fraction) const;
  RopeParams params_for(RopeModel model, int segments, double segment_m) const;
  // Whether a rope with these springs steps stably at the loop's period under
  // these gains (rt::stable_step_s, the planner's rule). Commands that would
  // break it are refused (Errc::unsupported) rather than left to diverge.
  bool steps_stably(const RopeParams& p, const ForceGains& g) const;

  ExecutiveConfig config_;
  storage::ResidentPack& field_;
  std::unique_ptr<FieldForces<storage::ResidentLevel, storage::ResidentSampler>> forces_;
  std::unique_ptr<Rope> ropes_[2];  // indexed by RopeModel
  Rope* rope_ = nullptr;
  std::optional<servo::Servo> servo_;
  HapticDevice* device_ = nullptr;
  DeviceSimulation* simulation_ = nullptr;
  ConstraintHulls* hulls_ = nullptr;
  const HullSet* in_force_ = nullptr;                    // the set the forces hold (owned by hulls_)
  fields::FieldSampler<storage::ResidentLevel> finest_;  // level 0's terrain: where observers and ceilings are judged
  std::uint64_t hull_requests_ = 0;                      // hull requests made (their sequence numbers, from 1)
  std::uint64_t hull_pending_ = 0;                       // the one being built, 0: none
  // switch-terrain: the id written by the loop, then the flag (release)
  char switch_pack_id_[msg::kPackIdCapacity] = {};
  std::atomic<bool> switch_requested_{false};
  msg::CommandQueue* commands_ = nullptr;
  ExecutiveOutputs outputs_;
  LatestValue<ExecutiveCounters> snapshot_;
  std::int64_t last_tick_ns_ = 0;  // the last tick's wake-up (stopping() steps the simulation after it)

  // Planning state (loop thread).
  Vec3 start_m_, end_m_;
  Objective objective_;
  int segments_;
  double stiffness_;
  double k1_, k3_;
  std::optional<double> stretch_override_, bend_override_;
  bool relaid_ = false;  // this run was laid again after its state stopped being finite
  EquilibriumDetector equilibrium_;
  std::unique_ptr<Vec3[]> scratch_;               // max_segments + 1 points
  std::unique_ptr<msg::PathSample> path_sample_;  // filled, then copied into each hand-off
  std::unique_ptr<msg::Command> held_;            // the command being applied, or waiting for the next tick
  bool holding_ = false;                          // held_ waits: the last tick's items were spent
  double user_force_per_n_ = 0.0;                 // rope newtons per servo coupling newton
  double max_user_force_n_ = 0.0;
  double saturated_n_ = 0.0;    // the saturated field's pull on one segment
  Vec3 pull_n_ = Vec3::Zero();  // the operator's pull on the rope this tick
  bool grasping_ = false;
  msg::InteractionMode mode_ = msg::InteractionMode::pull;
  double spool_segment_m_ = 0.0;  // a pull-mode segment's length: what each pay-out adds
  int ticks_since_pay_out_ = 0;
  bool arriving_ = false;                       // the free end came within a segment of the end
  int arrival_ticks_ = -1;                      // ticks since the free end arrived (-1: not yet)
  Vec3 arrival_from_m_ = Vec3::Zero();          // where it was then
  bool mode_button_was_ = false;                // the mode button's last valid state (presses are its rising edges)
  std::int64_t mode_press_ns_ = INT64_MIN / 2;  // when a press last switched the mode
  int grasp_segment_ = 0;
  double grasp_fraction_ = 0.0;
  std::uint64_t path_sequence_ = 0;
  std::uint64_t device_sequence_ = 0;
  servo::ServoOutput out_;            // this tick's servo output
  Vec3 last_proxy_m_ = Vec3::Zero();  // where a grasp would take the rope
  std::int64_t device_now_ns_ = 0;
  ExecutiveCounters counters_;
};

}  // namespace visvol::rt

// The messages between visvol's parts: plain samples that the executive, the
// renderer and the console fill and hand off, the commands that command
// intake hands back, the queues that carry them to and from the real-time
// thread, and their time stamps. No transport: drivers/dds converts them to
// and from the wire.
//
// Every struct here is trivially copyable with a fixed capacity, so it travels
// through LatestValue / SpscQueue (base/handoff.hpp) with one memcpy and no
// allocation. Filling one is real-time safe. Conversion to and from the DDS
// message types happens on the DDS layer's own threads
// (drivers/dds/message_codec.hpp, command_codec.hpp), never on the real-time
// thread.
//
// Units are in the names. Positions are world metres: the terrain pack's
// projected CRS, published on the terrain topic (see TerrainInfo). Stamps are
// nanoseconds since the Unix epoch on the system clock (CLOCK_REALTIME, as ROS
// time), read with clock_gettime, which is real-time safe (vDSO).
//
// Strings are fixed char arrays, NUL-terminated; copy_text() fills them.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <type_traits>

#include "base/handoff.hpp"

namespace visvol::msg {

// Capacities reserved at start-up. A sample never holds more; a command asking
// for more is rejected with a reason.
inline constexpr std::size_t kMaxPathVertices = 512;
// Observers (hidden-from and visible-to points) of one kind in a command at
// most, as `visvol plan` takes them (the console folds each kind into one
// hull, so the number costs build time, not memory: rt/exec/constraint_hulls.hpp).
inline constexpr std::size_t kMaxObserversPerKind = 256;
// Both kinds of observers, and one clearance, max-agl and max-altitude.
inline constexpr std::size_t kMaxConstraints = 2 * kMaxObserversPerKind + 3;
inline constexpr std::size_t kMaxThumbnailBytes = 256 * 1024;  // PNG file bytes
inline constexpr std::size_t kPackIdCapacity = 64;             // bytes with the NUL
inline constexpr std::size_t kSourceCapacity = 64;
inline constexpr std::size_t kReasonCapacity = 192;
inline constexpr std::size_t kDeviceNameCapacity = 32;
inline constexpr std::size_t kCrsCapacity = 64;       // "EPSG:32610"
inline constexpr std::size_t kCrsWktCapacity = 4096;  // WKT of a projected CRS

// Values equal the uint8 constants of drivers/dds/idl/visvol_msgs.idl (checked
// by static_assert in the codecs).
enum class Objective : std::uint8_t { hide = 1, show = 2 };
enum class RopeModel : std::uint8_t { spring_mass = 1, articulated = 2 };
// The operator's interaction (paper, section 5): pull (mode A: both ends held,
// a grasped point pulled) or spool (mode B: the rope pays out of the start end
// while the operator drags its free end toward the destination).
enum class InteractionMode : std::uint8_t { pull = 1, spool = 2 };
enum class ConstraintKind : std::uint8_t {
  hidden_from = 1,
  visible_to = 2,
  clearance = 3,     // least height above the terrain
  max_agl = 4,       // most height above the terrain
  max_altitude = 5,  // most height above the datum
};
enum class CommandKind : std::uint8_t {
  set_endpoints = 1,
  set_objective = 2,
  set_weights = 3,
  set_stiffness = 4,
  set_model = 5,
  set_segment_count = 6,
  set_constraints = 7,
  start = 8,
  stop = 9,
  switch_terrain = 10,
  set_mode = 11,
};
enum class AckResult : std::uint8_t { accepted = 1, rejected = 2, applied = 3, failed = 4 };
enum class DeviceState : std::uint8_t {
  unknown = 0,
  disconnected = 1,
  idle = 2,    // connected, forces off
  active = 3,  // connected, forces on
  fault = 4,
};

// Names for messages and the command line ("hide", "set-objective", ...);
// nullptr for a value outside the enumeration.
const char* to_string(Objective value);
const char* to_string(RopeModel value);
const char* to_string(InteractionMode value);
const char* to_string(ConstraintKind value);
const char* to_string(CommandKind value);
const char* to_string(AckResult value);
const char* to_string(DeviceState value);

// Copies text into a fixed array, truncating to fit, always NUL-terminated.
// Returns false when it had to truncate. Real-time safe.
template <std::size_t N>
bool copy_text(char (&dst)[N], std::string_view text) {
  static_assert(N > 0);
  const std::size_t n = std::min(text.size(), N - 1);
  if (n > 0) std::memcpy(dst, text.data(), n);
  dst[n] = '\0';
  return n == text.size();
}

// The text of a fixed array (up to the first NUL, or all of it).
template <std::size_t N>
std::string_view text_of(const char (&src)[N]) {
  const void* nul = std::memchr(src, '\0', N);
  const std::size_t n = nul ? static_cast<std::size_t>(static_cast<const char*>(nul) - src) : N;
  return std::string_view(src, n);
}

struct WorldPoint {
  double x_m;
  double y_m;
  double z_m;
};

struct PathVertex {
  WorldPoint position;
  double visibility;   // F_p at the vertex, dimensionless in [0, 1]
  double clearance_m;  // height above the terrain
};

// One path update. Producer: the executive's 1 kHz thread (or the offline
// planner). Fill back() in place and write only vertex_count vertices; the
// publisher reads no further.
struct PathSample {
  std::uint64_t sequence;  // increases with every update of one planning run
  std::int64_t stamp_ns;   // when the rope was in this state (Unix epoch)
  char pack_id[kPackIdCapacity];
  Objective objective;
  bool converged;        // the rope has come to rest
  bool inside_envelope;  // the path holds the vehicle's envelope, early descent included (false: the rope's own path,
                         // or no fit)
  double f_c;            // path measure F_c (sum of F_p along the path, weighted)
  double length_m;
  double min_clearance_m;
  InteractionMode mode = InteractionMode::pull;
  double spool_paid_out_m;     // spool mode: rope paid out since the mode began (0 in pull mode)
  std::uint32_t vertex_count;  // 0..kMaxPathVertices
  PathVertex vertices[kMaxPathVertices];
};

struct TimingSummary {
  double min_us;
  double mean_us;
  double p99_us;
  double max_us;
  std::uint32_t count;  // samples in the report window
};

// Loop health. Producer: the executive, once per report window. The DDS layer
// adds its own counters (commands, publish errors) when it publishes.
struct HealthSample {
  std::uint64_t sequence;
  std::int64_t stamp_ns;
  double period_us;              // configured loop period
  TimingSummary wakeup_latency;  // actual minus scheduled wake-up
  TimingSummary compute_time;    // work per tick
  std::uint64_t overruns;        // ticks whose work ran past the period (total)
  std::uint64_t misses;          // deadlines missed outright (total)
  bool safe_state;
  char safe_state_reason[kReasonCapacity];
};

// Haptic device and CAN bus status. Producer: the thread that owns the device.
struct DeviceStatusSample {
  std::uint64_t sequence;
  std::int64_t stamp_ns;
  char device[kDeviceNameCapacity];
  DeviceState state;
  std::uint32_t fault_bits;
  double motor_temperature_c;
  double last_position_age_ms;
  std::uint64_t can_rx_frames;
  std::uint64_t can_tx_frames;
  std::uint64_t can_errors;
  std::uint32_t bus_off_count;
};

// A rendered thumbnail: a whole PNG file (its header gives the size in
// pixels). Producer: the renderer thread.
struct ThumbnailSample {
  std::int64_t stamp_ns;         // the stamp of the path it shows, to pair them
  std::uint32_t png_size_bytes;  // 1..kMaxThumbnailBytes
  std::uint8_t png[kMaxThumbnailBytes];
};

// The terrain and its CRS. Producer: the console, on start-up and after a
// terrain switch.
struct TerrainInfo {
  std::int64_t stamp_ns;
  char pack_id[kPackIdCapacity];
  char crs[kCrsCapacity];         // "EPSG:32610"
  char crs_wkt[kCrsWktCapacity];  // may be empty
  WorldPoint min;                 // pack bounds
  WorldPoint max;
  double post_spacing_m;
  WorldPoint planning_min;  // planning bounds (x, y; z unused): endpoints inside them
  WorldPoint planning_max;
};

// The console's terrain catalogue (--catalogue): each pack of its folder, as
// verified. Producer: the console's main thread, when an entry changes.
inline constexpr std::size_t kMaxCatalogueEntries = 64;
inline constexpr std::size_t kCatalogueNameCapacity = 128;    // the source DEM's file name
inline constexpr std::size_t kCatalogueReasonCapacity = 256;  // why a pack was refused
inline constexpr std::size_t kCatalogueBuildCapacity = 512;   // the build's parameters, JSON

enum class CatalogueState : std::uint8_t { verifying = 0, verified = 1, refused = 2 };
const char* to_string(CatalogueState value);

struct CatalogueEntry {
  char pack_id[kPackIdCapacity];  // what switch-terrain names
  char name[kCatalogueNameCapacity];
  char crs[kCrsCapacity];
  WorldPoint min;  // the finest level's posts (z unused)
  WorldPoint max;
  WorldPoint planning_min;  // planning bounds (x, y; z unused)
  WorldPoint planning_max;
  double post_spacing_m;
  std::uint32_t levels;  // levels of detail (0 while unknown)
  CatalogueState state;
  char reason[kCatalogueReasonCapacity];  // refused: why (may be cut short)
  char build[kCatalogueBuildCapacity];    // may be empty when too long
};

struct TerrainCatalogue {
  std::int64_t stamp_ns;
  std::uint32_t count;  // 0..kMaxCatalogueEntries
  CatalogueEntry entries[kMaxCatalogueEntries];
};

// Commands -----------------------------------------------------------------

struct Weights {
  double k1_visibility;  // magnitude; the objective gives its sign
  double k2_terrain;
  double k3_user;
  double k4_constraint;
};

struct Constraint {
  ConstraintKind kind;
  WorldPoint position;  // where the observer stands (hidden_from, visible_to)
  double height_m;      // clearance, max_agl (above the terrain), max_altitude (above the datum)
};

// A validated command for the real-time thread: a tag and the parameters of
// that kind. Only the member named by `kind` carries meaning; the others are
// zero.
struct Command {
  CommandKind kind;
  std::uint64_t sequence;        // the sender's, for its acknowledgement
  char source[kSourceCapacity];  // the sender
  struct Endpoints {
    WorldPoint start;
    WorldPoint end;
  } endpoints;          // set_endpoints
  Objective objective;  // set_objective
  Weights weights;      // set_weights
  struct Stiffness {
    double stretch_n_per_m;
    double bend_n_m_per_rad;
  } stiffness;                  // set_stiffness
  RopeModel model;              // set_model
  std::uint32_t segment_count;  // set_segment_count
  struct Constraints {
    std::uint32_t count;
    Constraint items[kMaxConstraints];
  } constraints;                  // set_constraints
  char pack_id[kPackIdCapacity];  // switch_terrain
  InteractionMode mode;           // set_mode
};

// An acknowledgement. Command intake sends accepted/rejected itself; the
// executive may push applied/failed ones (AckQueue, below)
// once it has acted on a command.
struct CommandAck {
  char source[kSourceCapacity];
  std::uint64_t sequence;
  std::uint8_t kind;  // as received, possibly not a known CommandKind
  AckResult result;
  char reason[kReasonCapacity];
};

// Accepted commands, to the real-time thread (its consumer), and
// acknowledgements from it (applied or failed) back to command intake.
inline constexpr std::size_t kCommandQueueCapacity = 64;
using CommandQueue = SpscQueue<Command, kCommandQueueCapacity>;
using AckQueue = SpscQueue<CommandAck, kCommandQueueCapacity>;

// The system clock now, in Unix-epoch nanoseconds. Real-time safe (vDSO).
std::int64_t now_stamp_ns();

static_assert(std::is_trivially_copyable_v<PathSample>);
static_assert(std::is_trivially_copyable_v<HealthSample>);
static_assert(std::is_trivially_copyable_v<DeviceStatusSample>);
static_assert(std::is_trivially_copyable_v<ThumbnailSample>);
static_assert(std::is_trivially_copyable_v<TerrainInfo>);
static_assert(std::is_trivially_copyable_v<Command>);
static_assert(std::is_trivially_copyable_v<CommandAck>);

}  // namespace visvol::msg

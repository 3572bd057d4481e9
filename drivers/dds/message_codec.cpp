#include "drivers/dds/message_codec.hpp"

#include <cstring>
#include <limits>
#include <utility>

namespace visvol::dds {
namespace {

static_assert(static_cast<int>(msg::Objective::hide) == visvol_msgs_msg_dds__OBJECTIVE_HIDE);
static_assert(static_cast<int>(msg::Objective::show) == visvol_msgs_msg_dds__OBJECTIVE_SHOW);
static_assert(static_cast<int>(msg::DeviceState::unknown) == visvol_msgs_msg_dds__DEVICE_UNKNOWN);
static_assert(static_cast<int>(msg::DeviceState::disconnected) == visvol_msgs_msg_dds__DEVICE_DISCONNECTED);
static_assert(static_cast<int>(msg::DeviceState::idle) == visvol_msgs_msg_dds__DEVICE_IDLE);
static_assert(static_cast<int>(msg::DeviceState::active) == visvol_msgs_msg_dds__DEVICE_ACTIVE);
static_assert(static_cast<int>(msg::DeviceState::fault) == visvol_msgs_msg_dds__DEVICE_FAULT);

constexpr std::int64_t kNsPerS = 1000000000;
constexpr std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

// Cyclone's C types hold non-const char*; it only reads them when writing.
char* c_text(std::string& s) { return s.data(); }

template <std::size_t N>
void copy_terminated(char (&dst)[N], const char (&src)[N]) {
  msg::copy_text(dst, msg::text_of(src));
}

std_msgs_msg_dds__Header_ header(std::int64_t stamp_ns, std::string& frame_id) {
  std_msgs_msg_dds__Header_ h{};
  h.stamp = to_ros_time(stamp_ns);
  h.frame_id = c_text(frame_id);
  return h;
}

geometry_msgs_msg_dds__Point_ to_point(const msg::WorldPoint& p) {
  return geometry_msgs_msg_dds__Point_{p.x_m, p.y_m, p.z_m};
}

visvol_msgs_msg_dds__TimingSummary_ to_summary(const msg::TimingSummary& t) {
  return visvol_msgs_msg_dds__TimingSummary_{t.min_us, t.mean_us, t.p99_us, t.max_us, t.count};
}

}  // namespace

builtin_interfaces_msg_dds__Time_ to_ros_time(std::int64_t stamp_ns) {
  // Floor division, so that nanosec stays in [0, 1e9) before the epoch too.
  std::int64_t sec = stamp_ns / kNsPerS;
  std::int64_t nsec = stamp_ns % kNsPerS;
  if (nsec < 0) {
    nsec += kNsPerS;
    sec -= 1;
  }
  constexpr std::int64_t kMin = std::numeric_limits<std::int32_t>::min();
  constexpr std::int64_t kMax = std::numeric_limits<std::int32_t>::max();
  if (sec < kMin) return {static_cast<std::int32_t>(kMin), 0};
  if (sec > kMax) return {static_cast<std::int32_t>(kMax), static_cast<std::uint32_t>(kNsPerS - 1)};
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nsec)};
}

std::int64_t from_ros_time(const builtin_interfaces_msg_dds__Time_& time) {
  return static_cast<std::int64_t>(time.sec) * kNsPerS + static_cast<std::int64_t>(time.nanosec);
}

// Path -----------------------------------------------------------------------

PathMessages::PathMessages(std::string frame_id) : frame_id_(std::move(frame_id)) {
  // Constant parts, set once: identity orientation (w = 1, which C would leave
  // at 0) and every pose's frame.
  for (geometry_msgs_msg_dds__PoseStamped_& pose : poses_) {
    pose = geometry_msgs_msg_dds__PoseStamped_{};
    pose.header.frame_id = c_text(frame_id_);
    pose.pose.orientation.w = 1.0;
  }
  path_.poses._buffer = poses_;
  path_.poses._maximum = static_cast<std::uint32_t>(msg::kMaxPathVertices);
  path_.poses._release = false;
  update_.pack_id = pack_id_;
  update_.positions_m._buffer = positions_;
  update_.positions_m._maximum = static_cast<std::uint32_t>(msg::kMaxPathVertices);
  update_.visibility._buffer = visibility_;
  update_.visibility._maximum = static_cast<std::uint32_t>(msg::kMaxPathVertices);
  update_.clearance_m._buffer = clearance_m_;
  update_.clearance_m._maximum = static_cast<std::uint32_t>(msg::kMaxPathVertices);
}

Status PathMessages::fill(const msg::PathSample& sample) {
  if (sample.vertex_count > msg::kMaxPathVertices) {
    return invalid_argument("path sample: vertex_count " + std::to_string(sample.vertex_count) +
                            " above the capacity of " + std::to_string(msg::kMaxPathVertices));
  }
  const std::uint32_t n = sample.vertex_count;
  const std_msgs_msg_dds__Header_ h = header(sample.stamp_ns, frame_id_);
  path_.header = h;
  path_.poses._length = n;
  for (std::uint32_t i = 0; i < n; ++i) {
    const msg::PathVertex& v = sample.vertices[i];
    poses_[i].header.stamp = h.stamp;
    poses_[i].pose.position = to_point(v.position);
    positions_[i] = to_point(v.position);
    visibility_[i] = v.visibility;
    clearance_m_[i] = v.clearance_m;
  }
  copy_terminated(pack_id_, sample.pack_id);
  update_.header = h;
  update_.sequence_number = sample.sequence;
  update_.objective = static_cast<std::uint8_t>(sample.objective);
  update_.f_c = sample.f_c;
  update_.length_m = sample.length_m;
  update_.min_clearance_m = sample.min_clearance_m;
  update_.converged = sample.converged;
  update_.inside_envelope = sample.inside_envelope;
  update_.mode = static_cast<std::uint8_t>(sample.mode);
  update_.spool_paid_out_m = sample.spool_paid_out_m;
  update_.positions_m._length = n;
  update_.visibility._length = n;
  update_.clearance_m._length = n;
  return Status();
}

Status decode_path_update(const visvol_msgs_msg_dds__PathUpdate_& wire, msg::PathSample& out) {
  const std::uint32_t n = wire.positions_m._length;
  if (n > msg::kMaxPathVertices) {
    return invalid_argument("path update: " + std::to_string(n) + " vertices, above " +
                            std::to_string(msg::kMaxPathVertices));
  }
  if (wire.visibility._length != n || wire.clearance_m._length != n) {
    return invalid_argument("path update: " + std::to_string(n) + " positions but " +
                            std::to_string(wire.visibility._length) + " visibility and " +
                            std::to_string(wire.clearance_m._length) + " clearance values");
  }
  const char* pack = wire.pack_id ? wire.pack_id : "";
  if (!msg::copy_text(out.pack_id, pack)) {
    return invalid_argument("path update: pack_id longer than " + std::to_string(msg::kPackIdCapacity - 1) +
                            " characters");
  }
  if (wire.mode != static_cast<std::uint8_t>(msg::InteractionMode::pull) &&
      wire.mode != static_cast<std::uint8_t>(msg::InteractionMode::spool)) {
    return invalid_argument("path update: mode " + std::to_string(wire.mode) + " is not known (1 pull, 2 spool)");
  }
  out.mode = static_cast<msg::InteractionMode>(wire.mode);
  out.spool_paid_out_m = wire.spool_paid_out_m;
  out.sequence = wire.sequence_number;
  out.stamp_ns = from_ros_time(wire.header.stamp);
  out.objective = static_cast<msg::Objective>(wire.objective);
  out.converged = wire.converged;
  out.inside_envelope = wire.inside_envelope;
  out.f_c = wire.f_c;
  out.length_m = wire.length_m;
  out.min_clearance_m = wire.min_clearance_m;
  out.vertex_count = n;
  for (std::uint32_t i = 0; i < n; ++i) {
    const geometry_msgs_msg_dds__Point_& p = wire.positions_m._buffer[i];
    out.vertices[i] = msg::PathVertex{{p.x, p.y, p.z}, wire.visibility._buffer[i], wire.clearance_m._buffer[i]};
  }
  return Status();
}

// Health ---------------------------------------------------------------------

HealthMessage::HealthMessage(std::string frame_id) : frame_id_(std::move(frame_id)) {
  msg_.safe_state_reason = reason_;
}

Status HealthMessage::fill(const msg::HealthSample& sample, const LayerCounters& counters) {
  msg_.header = header(sample.stamp_ns, frame_id_);
  msg_.sequence_number = sample.sequence;
  msg_.period_us = sample.period_us;
  msg_.wakeup_latency = to_summary(sample.wakeup_latency);
  msg_.compute_time = to_summary(sample.compute_time);
  msg_.overruns = sample.overruns;
  msg_.misses = sample.misses;
  msg_.safe_state = sample.safe_state;
  copy_terminated(reason_, sample.safe_state_reason);
  msg_.commands_accepted = counters.commands_accepted;
  msg_.commands_rejected = counters.commands_rejected;
  msg_.publish_errors = counters.publish_errors;
  return Status();
}

// Device status --------------------------------------------------------------

DeviceStatusMessage::DeviceStatusMessage(std::string frame_id) : frame_id_(std::move(frame_id)) {
  msg_.device = device_;
}

Status DeviceStatusMessage::fill(const msg::DeviceStatusSample& sample) {
  msg_.header = header(sample.stamp_ns, frame_id_);
  msg_.sequence_number = sample.sequence;
  copy_terminated(device_, sample.device);
  msg_.state = static_cast<std::uint8_t>(sample.state);
  msg_.fault_bits = sample.fault_bits;
  msg_.motor_temperature_c = sample.motor_temperature_c;
  msg_.last_position_age_ms = sample.last_position_age_ms;
  msg_.can_rx_frames = sample.can_rx_frames;
  msg_.can_tx_frames = sample.can_tx_frames;
  msg_.can_errors = sample.can_errors;
  msg_.bus_off_count = sample.bus_off_count;
  return Status();
}

// Thumbnail ------------------------------------------------------------------

ThumbnailMessage::ThumbnailMessage(std::string frame_id) : frame_id_(std::move(frame_id)) {
  msg_.format = c_text(format_);
  msg_.data._release = false;
}

Status ThumbnailMessage::fill(const msg::ThumbnailSample& sample) {
  if (sample.png_size_bytes == 0 || sample.png_size_bytes > msg::kMaxThumbnailBytes) {
    return invalid_argument("thumbnail: png_size_bytes " + std::to_string(sample.png_size_bytes) + " outside 1.." +
                            std::to_string(msg::kMaxThumbnailBytes));
  }
  if (sample.png_size_bytes < sizeof kPngSignature ||
      std::memcmp(sample.png, kPngSignature, sizeof kPngSignature) != 0) {
    return invalid_argument("thumbnail: the bytes are not a PNG file (no PNG signature)");
  }
  msg_.header = header(sample.stamp_ns, frame_id_);
  // Cyclone only reads the buffer while writing; the sample outlives the write.
  msg_.data._buffer = const_cast<std::uint8_t*>(sample.png);
  msg_.data._length = sample.png_size_bytes;
  msg_.data._maximum = sample.png_size_bytes;
  return Status();
}

// Terrain --------------------------------------------------------------------

TerrainMessage::TerrainMessage(std::string frame_id) : frame_id_(std::move(frame_id)) {
  msg_.pack_id = pack_id_;
  msg_.crs = crs_;
  msg_.crs_wkt = crs_wkt_;
}

Status TerrainMessage::fill(const msg::TerrainInfo& info) {
  if (msg::text_of(info.pack_id).empty()) return invalid_argument("terrain info: empty pack_id");
  if (msg::text_of(info.crs).empty() && msg::text_of(info.crs_wkt).empty()) {
    return invalid_argument("terrain info: neither crs nor crs_wkt is set");
  }
  msg_.header = header(info.stamp_ns, frame_id_);
  copy_terminated(pack_id_, info.pack_id);
  copy_terminated(crs_, info.crs);
  copy_terminated(crs_wkt_, info.crs_wkt);
  msg_.min_m = to_point(info.min);
  msg_.max_m = to_point(info.max);
  msg_.post_spacing_m = info.post_spacing_m;
  msg_.planning_min_m = to_point(info.planning_min);
  msg_.planning_max_m = to_point(info.planning_max);
  return Status();
}

CatalogueMessage::CatalogueMessage(std::string frame_id)
    : frame_id_(std::move(frame_id)),
      text_(std::make_unique<msg::TerrainCatalogue>()),
      entries_(std::make_unique<visvol_msgs_msg_dds__TerrainCatalogueEntry_[]>(msg::kMaxCatalogueEntries)) {
  msg_.entries._buffer = entries_.get();
  msg_.entries._maximum = static_cast<std::uint32_t>(msg::kMaxCatalogueEntries);
  msg_.entries._release = false;
  for (std::size_t i = 0; i < msg::kMaxCatalogueEntries; ++i) {
    msg::CatalogueEntry& t = text_->entries[i];
    visvol_msgs_msg_dds__TerrainCatalogueEntry_& w = entries_[i];
    w.pack_id = t.pack_id;
    w.name = t.name;
    w.crs = t.crs;
    w.reason = t.reason;
    w.build = t.build;
  }
}

Status CatalogueMessage::fill(const msg::TerrainCatalogue& c) {
  if (c.count > msg::kMaxCatalogueEntries) {
    return invalid_argument("terrain catalogue: " + std::to_string(c.count) + " entries, at most " +
                            std::to_string(msg::kMaxCatalogueEntries));
  }
  for (std::uint32_t i = 0; i < c.count; ++i) {
    const msg::CatalogueEntry& e = c.entries[i];
    if (msg::text_of(e.pack_id).empty()) return invalid_argument("terrain catalogue: an entry without a pack id");
    if (msg::to_string(e.state) == nullptr) return invalid_argument("terrain catalogue: an unknown state");
  }
  msg_.header = header(c.stamp_ns, frame_id_);
  for (std::uint32_t i = 0; i < c.count; ++i) {
    const msg::CatalogueEntry& e = c.entries[i];
    msg::CatalogueEntry& t = text_->entries[i];
    copy_terminated(t.pack_id, e.pack_id);
    copy_terminated(t.name, e.name);
    copy_terminated(t.crs, e.crs);
    copy_terminated(t.reason, e.reason);
    copy_terminated(t.build, e.build);
    visvol_msgs_msg_dds__TerrainCatalogueEntry_& w = entries_[i];
    w.min_m = to_point(e.min);
    w.max_m = to_point(e.max);
    w.planning_min_m = to_point(e.planning_min);
    w.planning_max_m = to_point(e.planning_max);
    w.post_spacing_m = e.post_spacing_m;
    w.levels = e.levels;
    w.state = static_cast<std::uint8_t>(e.state);
  }
  msg_.entries._length = c.count;
  return Status();
}

Status decode_catalogue(const visvol_msgs_msg_dds__TerrainCatalogue_& wire, msg::TerrainCatalogue& out) {
  if (wire.entries._length > msg::kMaxCatalogueEntries) {
    return invalid_argument("terrain catalogue: " + std::to_string(wire.entries._length) + " entries, at most " +
                            std::to_string(msg::kMaxCatalogueEntries));
  }
  out.stamp_ns = from_ros_time(wire.header.stamp);
  out.count = 0;  // set once every entry decoded
  for (std::uint32_t i = 0; i < wire.entries._length; ++i) {
    const visvol_msgs_msg_dds__TerrainCatalogueEntry_& w = wire.entries._buffer[i];
    msg::CatalogueEntry& e = out.entries[i];
    if (w.state > static_cast<std::uint8_t>(msg::CatalogueState::refused)) {
      return invalid_argument("terrain catalogue: state " + std::to_string(w.state) + " is not a CATALOGUE_*");
    }
    e.state = static_cast<msg::CatalogueState>(w.state);
    msg::copy_text(e.pack_id, w.pack_id != nullptr ? w.pack_id : "");
    msg::copy_text(e.name, w.name != nullptr ? w.name : "");
    msg::copy_text(e.crs, w.crs != nullptr ? w.crs : "");
    msg::copy_text(e.reason, w.reason != nullptr ? w.reason : "");
    msg::copy_text(e.build, w.build != nullptr ? w.build : "");
    e.min = {w.min_m.x, w.min_m.y, w.min_m.z};
    e.max = {w.max_m.x, w.max_m.y, w.max_m.z};
    e.planning_min = {w.planning_min_m.x, w.planning_min_m.y, w.planning_min_m.z};
    e.planning_max = {w.planning_max_m.x, w.planning_max_m.y, w.planning_max_m.z};
    e.post_spacing_m = w.post_spacing_m;
    e.levels = w.levels;
  }
  out.count = wire.entries._length;
  return Status();
}

}  // namespace visvol::dds

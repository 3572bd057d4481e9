#include "format.hpp"

#include <cstdarg>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "io/json_text.hpp"
#include "msg/samples.hpp"

namespace visvol::echo {
namespace {

// printf into a string; lines are short, so one fixed buffer per call suffices.
__attribute__((format(printf, 2, 3))) void add(std::string& out, const char* fmt, ...) {
  char buf[1024];
  va_list args;
  va_start(args, fmt);
  const int n = std::vsnprintf(buf, sizeof buf, fmt, args);
  va_end(args);
  if (n > 0) out.append(buf, static_cast<std::size_t>(n) < sizeof buf ? static_cast<std::size_t>(n) : sizeof buf - 1);
}

// A received string: quoted, with anything unprintable shown as '?'.
std::string quoted(const char* s) {
  std::string out = "\"";
  for (const char* c = s ? s : ""; *c; ++c) {
    out += (*c >= 0x20 && *c <= 0x7e && *c != '"') ? *c : '?';
  }
  return out + "\"";
}

std::string stamp(const builtin_interfaces_msg_dds__Time_& t) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%d.%09u", t.sec, t.nanosec);
  return buf;
}

template <typename E>
const char* name_of(std::uint8_t value) {
  const char* n = msg::to_string(static_cast<E>(value));
  return n ? n : "unknown";
}

void add_timing(std::string& out, const char* key, const visvol_msgs_msg_dds__TimingSummary_& t) {
  add(out, " %s_us(min/mean/p99/max)=%.1f/%.1f/%.1f/%.1f", key, t.min_us, t.mean_us, t.p99_us, t.max_us);
}

}  // namespace

std::string format_path_update(const visvol_msgs_msg_dds__PathUpdate_& m, bool with_vertices) {
  std::string out;
  add(out,
      "path seq=%llu stamp=%s frame=%s pack=%s objective=%s vertices=%u length_m=%.3f "
      "f_c=%.6g min_clearance_m=%.3f converged=%s inside_envelope=%s mode=%s spool_paid_out_m=%.3f",
      static_cast<unsigned long long>(m.sequence_number), stamp(m.header.stamp).c_str(),
      quoted(m.header.frame_id).c_str(), quoted(m.pack_id).c_str(), name_of<msg::Objective>(m.objective),
      m.positions_m._length, m.length_m, m.f_c, m.min_clearance_m, m.converged ? "yes" : "no",
      m.inside_envelope ? "yes" : "no", name_of<msg::InteractionMode>(m.mode), m.spool_paid_out_m);
  if (with_vertices) {
    for (std::uint32_t i = 0; i < m.positions_m._length; ++i) {
      const geometry_msgs_msg_dds__Point_& p = m.positions_m._buffer[i];
      const double vis = i < m.visibility._length ? m.visibility._buffer[i] : 0.0;
      const double clr = i < m.clearance_m._length ? m.clearance_m._buffer[i] : 0.0;
      add(out, "\n  [%u] x_m=%.3f y_m=%.3f z_m=%.3f visibility=%.6f clearance_m=%.3f", i, p.x, p.y, p.z, vis, clr);
    }
  }
  return out;
}

std::string format_health(const visvol_msgs_msg_dds__LoopHealth_& m) {
  std::string out;
  add(out, "health seq=%llu stamp=%s period_us=%.1f", static_cast<unsigned long long>(m.sequence_number),
      stamp(m.header.stamp).c_str(), m.period_us);
  add_timing(out, "wakeup", m.wakeup_latency);
  add_timing(out, "compute", m.compute_time);
  add(out, " overruns=%llu misses=%llu safe_state=%s", static_cast<unsigned long long>(m.overruns),
      static_cast<unsigned long long>(m.misses), m.safe_state ? "yes" : "no");
  if (m.safe_state) add(out, " reason=%s", quoted(m.safe_state_reason).c_str());
  add(out, " commands_accepted=%llu commands_rejected=%llu publish_errors=%llu",
      static_cast<unsigned long long>(m.commands_accepted), static_cast<unsigned long long>(m.commands_rejected),
      static_cast<unsigned long long>(m.publish_errors));
  return out;
}

std::string format_device_status(const visvol_msgs_msg_dds__DeviceStatus_& m) {
  std::string out;
  add(out,
      "device seq=%llu stamp=%s name=%s state=%s fault_bits=0x%08x motor_temperature_c=%.1f "
      "last_position_age_ms=%.1f can_rx=%llu can_tx=%llu can_errors=%llu bus_off=%u",
      static_cast<unsigned long long>(m.sequence_number), stamp(m.header.stamp).c_str(), quoted(m.device).c_str(),
      name_of<msg::DeviceState>(m.state), m.fault_bits, m.motor_temperature_c, m.last_position_age_ms,
      static_cast<unsigned long long>(m.can_rx_frames), static_cast<unsigned long long>(m.can_tx_frames),
      static_cast<unsigned long long>(m.can_errors), m.bus_off_count);
  return out;
}

std::string format_terrain(const visvol_msgs_msg_dds__TerrainInfo_& m) {
  std::string out;
  add(out,
      "terrain stamp=%s frame=%s pack=%s crs=%s min_m=(%.3f, %.3f, %.3f) "
      "max_m=(%.3f, %.3f, %.3f) post_spacing_m=%.3f planning_m=x %.3f..%.3f, y %.3f..%.3f wkt_chars=%zu",
      stamp(m.header.stamp).c_str(), quoted(m.header.frame_id).c_str(), quoted(m.pack_id).c_str(),
      quoted(m.crs).c_str(), m.min_m.x, m.min_m.y, m.min_m.z, m.max_m.x, m.max_m.y, m.max_m.z, m.post_spacing_m,
      m.planning_min_m.x, m.planning_max_m.x, m.planning_min_m.y, m.planning_max_m.y,
      m.crs_wkt ? std::string(m.crs_wkt).size() : 0);
  return out;
}

// One line for the catalogue, then one per entry (indented).
std::string format_catalogue(const visvol_msgs_msg_dds__TerrainCatalogue_& m) {
  std::string out;
  add(out, "terrain_catalogue stamp=%s entries=%u", stamp(m.header.stamp).c_str(), m.entries._length);
  for (std::uint32_t i = 0; i < m.entries._length; ++i) {
    const visvol_msgs_msg_dds__TerrainCatalogueEntry_& e = m.entries._buffer[i];
    add(out, "\n  pack=%s state=%s name=%s crs=%s levels=%u post_spacing_m=%.3f planning_m=x %.3f..%.3f, y %.3f..%.3f",
        quoted(e.pack_id).c_str(), name_of<msg::CatalogueState>(e.state), quoted(e.name).c_str(), quoted(e.crs).c_str(),
        e.levels, e.post_spacing_m, e.planning_min_m.x, e.planning_max_m.x, e.planning_min_m.y, e.planning_max_m.y);
    if (e.state == static_cast<std::uint8_t>(msg::CatalogueState::refused))
      add(out, " reason=%s", quoted(e.reason).c_str());
  }
  return out;
}

std::string format_thumbnail(const sensor_msgs_msg_dds__CompressedImage_& m) {
  std::string out;
  add(out, "thumbnail stamp=%s format=%s bytes=%u", stamp(m.header.stamp).c_str(), quoted(m.format).c_str(),
      m.data._length);
  return out;
}

std::string format_ack(const visvol_msgs_msg_dds__CommandAck_& m) {
  std::string out;
  add(out, "ack source=%s seq=%llu kind=%s result=%s", quoted(m.source).c_str(),
      static_cast<unsigned long long>(m.sequence_number), name_of<msg::CommandKind>(m.kind),
      name_of<msg::AckResult>(m.result));
  if (m.reason && m.reason[0] != '\0') add(out, " reason=%s", quoted(m.reason).c_str());
  return out;
}

// JSON ------------------------------------------------------------------------

namespace {

using nlohmann::json;

std::string text(const char* s) { return s ? s : ""; }

std::int64_t stamp_ns(const builtin_interfaces_msg_dds__Time_& t) {
  return static_cast<std::int64_t>(t.sec) * 1000000000LL + t.nanosec;
}

json point(const geometry_msgs_msg_dds__Point_& p) { return json::array({p.x, p.y, p.z}); }

json timing(const visvol_msgs_msg_dds__TimingSummary_& t) {
  return {{"min_us", t.min_us}, {"mean_us", t.mean_us}, {"p99_us", t.p99_us}, {"max_us", t.max_us}, {"count", t.count}};
}

std::string line_of(const json& j) { return json_text(j); }

}  // namespace

std::string json_path_update(const visvol_msgs_msg_dds__PathUpdate_& m, bool with_vertices) {
  json j = {{"topic", "path"},
            {"sequence_number", m.sequence_number},
            {"stamp_ns", stamp_ns(m.header.stamp)},
            {"frame_id", text(m.header.frame_id)},
            {"pack_id", text(m.pack_id)},
            {"objective", name_of<msg::Objective>(m.objective)},
            {"vertices", m.positions_m._length},
            {"length_m", m.length_m},
            {"f_c", m.f_c},
            {"min_clearance_m", m.min_clearance_m},
            {"converged", m.converged},
            {"inside_envelope", m.inside_envelope},
            {"mode", name_of<msg::InteractionMode>(m.mode)},
            {"spool_paid_out_m", m.spool_paid_out_m}};
  if (with_vertices) {
    json positions = json::array(), visibility = json::array(), clearance = json::array();
    for (std::uint32_t i = 0; i < m.positions_m._length; ++i) {
      positions.push_back(point(m.positions_m._buffer[i]));
      visibility.push_back(i < m.visibility._length ? m.visibility._buffer[i] : 0.0);
      clearance.push_back(i < m.clearance_m._length ? m.clearance_m._buffer[i] : 0.0);
    }
    j["positions_m"] = std::move(positions);
    j["visibility"] = std::move(visibility);
    j["clearance_m"] = std::move(clearance);
  }
  return line_of(j);
}

std::string json_health(const visvol_msgs_msg_dds__LoopHealth_& m) {
  return line_of({{"topic", "health"},
                  {"sequence_number", m.sequence_number},
                  {"stamp_ns", stamp_ns(m.header.stamp)},
                  {"period_us", m.period_us},
                  {"wakeup_latency", timing(m.wakeup_latency)},
                  {"compute_time", timing(m.compute_time)},
                  {"overruns", m.overruns},
                  {"misses", m.misses},
                  {"safe_state", m.safe_state},
                  {"safe_state_reason", text(m.safe_state_reason)},
                  {"commands_accepted", m.commands_accepted},
                  {"commands_rejected", m.commands_rejected},
                  {"publish_errors", m.publish_errors}});
}

std::string json_device_status(const visvol_msgs_msg_dds__DeviceStatus_& m) {
  return line_of({{"topic", "device"},
                  {"sequence_number", m.sequence_number},
                  {"stamp_ns", stamp_ns(m.header.stamp)},
                  {"device", text(m.device)},
                  {"state", name_of<msg::DeviceState>(m.state)},
                  {"fault_bits", m.fault_bits},
                  {"motor_temperature_c", m.motor_temperature_c},
                  {"last_position_age_ms", m.last_position_age_ms},
                  {"can_rx_frames", m.can_rx_frames},
                  {"can_tx_frames", m.can_tx_frames},
                  {"can_errors", m.can_errors},
                  {"bus_off_count", m.bus_off_count}});
}

std::string json_terrain(const visvol_msgs_msg_dds__TerrainInfo_& m) {
  return line_of({{"topic", "terrain"},
                  {"stamp_ns", stamp_ns(m.header.stamp)},
                  {"frame_id", text(m.header.frame_id)},
                  {"pack_id", text(m.pack_id)},
                  {"crs", text(m.crs)},
                  {"crs_wkt", text(m.crs_wkt)},
                  {"min_m", point(m.min_m)},
                  {"max_m", point(m.max_m)},
                  {"post_spacing_m", m.post_spacing_m},
                  {"planning_min_m", point(m.planning_min_m)},
                  {"planning_max_m", point(m.planning_max_m)}});
}

std::string json_catalogue(const visvol_msgs_msg_dds__TerrainCatalogue_& m) {
  nlohmann::json entries = nlohmann::json::array();
  for (std::uint32_t i = 0; i < m.entries._length; ++i) {
    const visvol_msgs_msg_dds__TerrainCatalogueEntry_& e = m.entries._buffer[i];
    const char* state = msg::to_string(static_cast<msg::CatalogueState>(e.state));
    entries.push_back({{"pack_id", text(e.pack_id)},
                       {"state", state != nullptr ? nlohmann::json(state) : nlohmann::json(e.state)},
                       {"name", text(e.name)},
                       {"crs", text(e.crs)},
                       {"min_m", point(e.min_m)},
                       {"max_m", point(e.max_m)},
                       {"planning_min_m", point(e.planning_min_m)},
                       {"planning_max_m", point(e.planning_max_m)},
                       {"post_spacing_m", e.post_spacing_m},
                       {"levels", e.levels},
                       {"reason", text(e.reason)},
                       {"build", text(e.build)}});
  }
  return line_of({{"topic", "catalogue"},
                  {"stamp_ns", stamp_ns(m.header.stamp)},
                  {"frame_id", text(m.header.frame_id)},
                  {"entries", std::move(entries)}});
}

std::string json_thumbnail(const sensor_msgs_msg_dds__CompressedImage_& m) {
  return line_of({{"topic", "thumbnail"},
                  {"stamp_ns", stamp_ns(m.header.stamp)},
                  {"format", text(m.format)},
                  {"bytes", m.data._length}});
}

std::string json_ack(const visvol_msgs_msg_dds__CommandAck_& m) {
  return line_of({{"topic", "acks"},
                  {"source", text(m.source)},
                  {"sequence_number", m.sequence_number},
                  {"kind", name_of<msg::CommandKind>(m.kind)},
                  {"result", name_of<msg::AckResult>(m.result)},
                  {"reason", text(m.reason)}});
}

}  // namespace visvol::echo

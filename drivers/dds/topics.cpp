#include "drivers/dds/topics.hpp"

#include <array>
#include <cmath>

#include "ros2.h"
#include "visvol_msgs.h"

namespace visvol::dds {
namespace {

enum class Profile {
  latest,     // reliable, transient-local, keep-last 1
  telemetry,  // best effort, volatile, keep-last 1
  command,    // reliable, volatile, keep-all
  ack,        // reliable, transient-local, keep-last kAckHistoryDepth
};

struct TopicSpec {
  const char* name;
  const dds_topic_descriptor_t* type;
  Profile profile;
};

// Indexed by Topic.
const std::array<TopicSpec, kTopicCount> kTopics = {{
    {"visvol/path", &nav_msgs_msg_dds__Path__desc, Profile::latest},
    {"visvol/path_update", &visvol_msgs_msg_dds__PathUpdate__desc, Profile::latest},
    {"visvol/thumbnail/compressed", &sensor_msgs_msg_dds__CompressedImage__desc, Profile::latest},
    {"visvol/terrain", &visvol_msgs_msg_dds__TerrainInfo__desc, Profile::latest},
    {"visvol/device_status", &visvol_msgs_msg_dds__DeviceStatus__desc, Profile::latest},
    {"visvol/health", &visvol_msgs_msg_dds__LoopHealth__desc, Profile::telemetry},
    {"visvol/command", &visvol_msgs_msg_dds__Command__desc, Profile::command},
    {"visvol/command_ack", &visvol_msgs_msg_dds__CommandAck__desc, Profile::ack},
    {"visvol/terrain_catalogue", &visvol_msgs_msg_dds__TerrainCatalogue__desc, Profile::latest},
}};

const TopicSpec& spec(Topic topic) { return kTopics.at(static_cast<std::size_t>(topic)); }

const char* describe_profile(Profile profile) {
  switch (profile) {
    case Profile::latest: return "reliable, transient-local, keep-last 1";
    case Profile::telemetry: return "best effort, volatile, keep-last 1";
    case Profile::command: return "reliable, volatile, keep-all";
    case Profile::ack: return "reliable, transient-local, keep-last 1024 (reader: keep-all)";
  }
  return "?";
}

// How long a reliable dds_write may wait for room in the writer's history
// before it fails; bounded so the publisher thread never stalls for long.
constexpr dds_duration_t kMaxBlocking = DDS_MSECS(50);

bool is_segment_start(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool is_segment_char(char c) { return is_segment_start(c) || (c >= '0' && c <= '9'); }

std::string_view strip_leading_slash(std::string_view ns) {
  if (!ns.empty() && ns.front() == '/') ns.remove_prefix(1);
  return ns;
}

QosPtr make_qos(Profile profile, bool reader) {
  QosPtr qos(dds_create_qos());
  switch (profile) {
    case Profile::latest:
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, kMaxBlocking);
      dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
      dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
      break;
    case Profile::telemetry:
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
      dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
      dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
      break;
    case Profile::command:
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, kMaxBlocking);
      dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
      dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
      // Bounded memory on the console side: the reliable protocol holds the
      // rest back at the senders until intake has taken what it has.
      if (reader) {
        dds_qset_resource_limits(qos.get(), kCommandReaderMaxQueued, DDS_LENGTH_UNLIMITED, kCommandReaderMaxQueued);
      }
      break;
    case Profile::ack:
      dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, kMaxBlocking);
      // Discovery is not symmetric: a sender that already sees the console's
      // ack writer may not yet be seen by it, and a volatile writer would drop
      // the answers written before it matched. Transient-local hands them over
      // at the match; senders pick their own by source and sequence.
      dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
      // The writer never blocks on a slow or dead subscriber, yet keeps a
      // flood's worth of acknowledgements for retransmission; a subscriber
      // keeps all, so that its own answer is never pushed out by others'.
      if (reader) {
        dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
      } else {
        dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, kAckHistoryDepth);
        // What a late joiner gets is the durability service's depth, not the
        // history's: Cyclone's default of 1 would hand over only the newest.
        dds_qset_durability_service(qos.get(), 0, DDS_HISTORY_KEEP_LAST, kAckHistoryDepth, DDS_LENGTH_UNLIMITED,
                                    DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
      }
      break;
  }
  return qos;
}

}  // namespace

const char* relative_name(Topic topic) { return spec(topic).name; }
const char* type_name(Topic topic) { return spec(topic).type->m_typename; }
const dds_topic_descriptor_t& descriptor(Topic topic) { return *spec(topic).type; }

std::string describe(Topic topic) {
  std::string line = "rt/";
  line += spec(topic).name;
  line.resize(std::max<std::size_t>(line.size() + 1, 34), ' ');
  line += type_name(topic);
  line.resize(std::max<std::size_t>(line.size() + 1, 78), ' ');
  line += describe_profile(spec(topic).profile);
  return line;
}

Status validate_namespace(std::string_view ns) {
  const std::string_view body = strip_leading_slash(ns);
  if (body.size() > 100) {
    return invalid_argument("namespace '" + std::string(ns) + "': longer than 100 characters");
  }
  if (body.empty()) return Status();
  std::size_t segment_start = 0;
  for (std::size_t i = 0; i <= body.size(); ++i) {
    const bool end = i == body.size() || body[i] == '/';
    if (end) {
      if (i == segment_start) {
        return invalid_argument("namespace '" + std::string(ns) + "': empty segment (double or trailing '/')");
      }
      segment_start = i + 1;
      continue;
    }
    const bool ok = i == segment_start ? is_segment_start(body[i]) : is_segment_char(body[i]);
    if (!ok) {
      return invalid_argument("namespace '" + std::string(ns) + "': character " + std::to_string(i + 1) +
                              " must be a letter or '_' (or a digit after the first)");
    }
  }
  return Status();
}

std::string topic_name(std::string_view ns, Topic topic) {
  const std::string_view body = strip_leading_slash(ns);
  std::string name = "rt/";
  if (!body.empty()) {
    name += body;
    name += '/';
  }
  name += spec(topic).name;
  return name;
}

QosPtr writer_qos(Topic topic) { return make_qos(spec(topic).profile, false); }
QosPtr reader_qos(Topic topic) { return make_qos(spec(topic).profile, true); }

dds_duration_t to_duration(double seconds) {
  if (!(seconds > 0.0)) return 0;  // also NaN
  constexpr double kMaxSeconds = 86400.0;
  return static_cast<dds_duration_t>(std::min(seconds, kMaxSeconds) * 1e9);
}

}  // namespace visvol::dds

// dds_test_peer: the second process of dds_interprocess_test. A real Cyclone
// participant on the loopback configuration, in the domain and namespace the
// test gives, doing one of:
//
//   listen DOMAIN NS LAST_SEQ TIMEOUT_S   subscribe to path updates and paths;
//       print "update SEQ VERTICES" and "path-cdr HEX" (the serialised
//       nav_msgs/Path as received) for each; exit 0 once LAST_SEQ and its
//       path have arrived, 3 on timeout
//   publish DOMAIN NS COUNT LINGER_S      what `visvol plan --publish` does:
//       wait for a subscriber, publish paths 1..COUNT, wait for delivery;
//       print "delivered" and exit 0, or the reason and exit 1
//   commands DOMAIN NS TIMEOUT_S [SOURCE] send bad commands and one good one
//       as SOURCE (default "peer"); print "ack SEQ RESULT REASON" for each
//       acknowledgement to SOURCE; exit 0 when all are acknowledged, 3 on
//       timeout
//
//   oversize DOMAIN NS WAIT_S             a sender of its own limit (64 MiB,
//       in its configuration): a set-constraints command of 2 MiB (sequence
//       1); print "ack SEQ RESULT" for any acknowledgement within WAIT_S;
//       exit 0 (the reliable writer keeps resending what the reader
//       dropped, so its later samples may wait behind it: none is sent)
//
// Exit 2 on bad arguments. Output lines are flushed as they are printed.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "drivers/dds/command_codec.hpp"
#include "drivers/dds/message_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "drivers/dds/path_publisher.hpp"

namespace {

using namespace visvol;
using namespace visvol::dds;

int usage() {
  std::fprintf(stderr, "usage: dds_test_peer listen|publish|commands|oversize DOMAIN NS ARG [ARG]\n");
  return 2;
}

bool parse_number(const char* text, double& out) {
  char* end = nullptr;
  out = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(out) && out >= 0.0;
}

std::unique_ptr<Participant> participant(double domain, const char* ns, bool large_samples) {
  ParticipantConfig c;
  c.domain_id = static_cast<std::uint32_t>(domain);
  c.cyclone_xml = std::string(loopback_config());
  if (large_samples) {
    // a configuration's own sample limit is kept (visvol's 1 MiB is not added)
    const std::size_t end = c.cyclone_xml.rfind("</Domain>");
    c.cyclone_xml.insert(end, "<Internal><MaxSampleSize>64MiB</MaxSampleSize></Internal>");
  }
  c.topic_namespace = ns;
  Result<std::unique_ptr<Participant>> p = Participant::create(c);
  if (!p.ok()) {
    std::printf("error %s\n", p.status().message().c_str());
    return nullptr;
  }
  return std::move(*p);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int listen(Participant& p, std::uint64_t last_seq, double timeout_s) {
  Result<Reader> updates = Reader::create(p, Topic::path_update);
  Result<Reader> paths = Reader::create(p, Topic::path);
  if (!updates.ok() || !paths.ok()) return 1;
  std::printf("ready\n");
  std::fflush(stdout);
  const auto t0 = std::chrono::steady_clock::now();
  bool last_seen = false;
  std::int64_t last_stamp = 0;
  while (seconds_since(t0) < timeout_s) {
    (void)updates->wait(0.05);
    (void)updates->take<visvol_msgs_msg_dds__PathUpdate_>(
        [&](const visvol_msgs_msg_dds__PathUpdate_& m, const dds_sample_info_t&) {
          std::printf("update %llu %u\n", static_cast<unsigned long long>(m.sequence_number), m.positions_m._length);
          if (m.sequence_number == last_seq) {
            last_seen = true;
            last_stamp = from_ros_time(m.header.stamp);
          }
        });
    for (;;) {
      Result<std::vector<std::uint8_t>> cdr = paths->take_serialized();
      if (!cdr.ok() || cdr->empty()) break;
      std::printf("path-cdr ");
      for (const std::uint8_t b : *cdr) std::printf("%02x", b);
      std::printf("\n");
      // the path of the last update carries its stamp: seconds at offset 4
      if (last_seen && cdr->size() >= 12) {
        std::int32_t sec = 0;
        std::uint32_t nsec = 0;
        std::memcpy(&sec, cdr->data() + 4, 4);
        std::memcpy(&nsec, cdr->data() + 8, 4);
        if (from_ros_time({sec, nsec}) == last_stamp) {
          std::fflush(stdout);
          return 0;
        }
      }
    }
    std::fflush(stdout);
  }
  std::printf("timeout\n");
  return 3;
}

int publish(Participant& p, std::uint64_t count, double linger_s) {
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(p);
  if (!pub.ok()) return 1;
  // Without a matched subscriber the samples would go nowhere before exit.
  const Status matched = (*pub)->wait_for_subscribers(1, 10.0);
  if (!matched.ok()) {
    std::printf("error %s\n", matched.message().c_str());
    return 1;
  }
  auto s = std::make_unique<msg::PathSample>();
  for (std::uint64_t seq = 1; seq <= count; ++seq) {
    *s = msg::PathSample{};
    s->sequence = seq;
    s->stamp_ns = msg::now_stamp_ns();
    msg::copy_text(s->pack_id, "sf_north");
    s->objective = msg::Objective::hide;
    s->converged = seq == count;
    s->vertex_count = 8;
    for (std::uint32_t i = 0; i < 8; ++i) {
      s->vertices[i].position = {544000.0 + i, 4189000.0, 100.0 + static_cast<double>(seq)};
    }
    const Status st = (*pub)->publish(*s);
    if (!st.ok()) {
      std::printf("error %s\n", st.message().c_str());
      return 1;
    }
  }
  const Status delivered = (*pub)->wait_for_delivery(linger_s);
  if (!delivered.ok()) {
    std::printf("error %s\n", delivered.message().c_str());
    return 1;
  }
  std::printf("delivered\n");
  return 0;
}

// A sender's command writer and acknowledgement reader, matched with an
// intake: status 0, else 1 (not made) or 3 (no intake within the time, said).
struct CommandEndpoints {
  Result<Writer> writer;
  Result<Reader> acks;
  int status = 0;
};

CommandEndpoints command_endpoints(Participant& p, double timeout_s) {
  CommandEndpoints e{Writer::create(p, Topic::command), Reader::create(p, Topic::command_ack)};
  if (!e.writer.ok() || !e.acks.ok()) {
    e.status = 1;
  } else if (!e.writer->wait_for_readers(1, timeout_s).ok() || !e.acks->wait_for_writers(1, timeout_s).ok()) {
    std::printf("timeout no command intake\n");
    e.status = 3;
  }
  return e;
}

int commands(Participant& p, double timeout_s, const std::string& source) {
  CommandEndpoints e = command_endpoints(p, timeout_s);
  if (e.status != 0) return e.status;
  Result<Writer>& writer = e.writer;
  Result<Reader>& acks = e.acks;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CommandMessage m;
  msg::Command c{};
  msg::copy_text(c.source, source);
  c.kind = msg::CommandKind::set_endpoints;
  c.sequence = 1;
  c.endpoints = {{nan, 0.0, 0.0}, {1.0, 1.0, 1.0}};
  (void)writer->write(&m.fill(c));
  c.kind = msg::CommandKind::set_segment_count;
  c.sequence = 2;
  c.segment_count = 1000000;
  (void)writer->write(&m.fill(c));
  visvol_msgs_msg_dds__Command_ raw = m.fill(c);
  raw.sequence_number = 3;
  raw.kind = 250;
  (void)writer->write(&raw);
  c = msg::Command{};
  msg::copy_text(c.source, source);
  c.kind = msg::CommandKind::start;
  c.sequence = 4;
  (void)writer->write(&m.fill(c));

  std::set<std::uint64_t> answered;
  const auto t0 = std::chrono::steady_clock::now();
  while (answered.size() < 4 && seconds_since(t0) < timeout_s) {
    (void)acks->wait(0.05);
    (void)acks->take<visvol_msgs_msg_dds__CommandAck_>(
        [&](const visvol_msgs_msg_dds__CommandAck_& a, const dds_sample_info_t&) {
          if (std::string(a.source) != source) return;
          answered.insert(a.sequence_number);
          const char* result = to_string(static_cast<msg::AckResult>(a.result));
          std::printf("ack %llu %s %s\n", static_cast<unsigned long long>(a.sequence_number), result ? result : "?",
                      a.reason);
        });
    std::fflush(stdout);
  }
  if (answered.size() < 4) {
    std::printf("timeout\n");
    return 3;
  }
  return 0;
}

int oversize(Participant& p, double timeout_s) {
  CommandEndpoints e = command_endpoints(p, timeout_s);
  if (e.status != 0) return e.status;
  Result<Writer>& writer = e.writer;
  Result<Reader>& acks = e.acks;
  CommandMessage m;
  msg::Command c{};
  msg::copy_text(c.source, "oversize");
  c.kind = msg::CommandKind::set_constraints;
  c.sequence = 1;
  visvol_msgs_msg_dds__Command_ raw = m.fill(c);
  std::vector<visvol_msgs_msg_dds__Constraint_> huge(2 * kMaxSampleBytes / 32);  // 40 bytes each serialised
  raw.constraints._buffer = huge.data();
  raw.constraints._length = static_cast<std::uint32_t>(huge.size());
  raw.constraints._maximum = static_cast<std::uint32_t>(huge.size());
  if (writer->write(&raw) != 0) {
    std::printf("error the oversize command was not sent\n");
    return 1;
  }
  std::printf("sent\n");
  const auto t0 = std::chrono::steady_clock::now();
  while (seconds_since(t0) < timeout_s) {
    (void)acks->wait(0.05);
    (void)acks->take<visvol_msgs_msg_dds__CommandAck_>(
        [&](const visvol_msgs_msg_dds__CommandAck_& a, const dds_sample_info_t&) {
          if (std::string(a.source) != "oversize") return;
          const char* result = to_string(static_cast<msg::AckResult>(a.result));
          std::printf("ack %llu %s\n", static_cast<unsigned long long>(a.sequence_number), result ? result : "?");
        });
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) return usage();
  const std::string mode = argv[1];
  double domain = 0.0, arg = 0.0, arg2 = 0.0;
  if (!parse_number(argv[2], domain) || domain > kMaxDomainId || !parse_number(argv[4], arg)) {
    return usage();
  }
  if (mode != "commands" && mode != "oversize" && (argc < 6 || !parse_number(argv[5], arg2))) return usage();
  std::unique_ptr<Participant> p = participant(domain, argv[3], mode == "oversize");
  if (!p) return 1;
  int rc = 2;
  if (mode == "listen") rc = listen(*p, static_cast<std::uint64_t>(arg), arg2);
  if (mode == "publish") rc = publish(*p, static_cast<std::uint64_t>(arg), arg2);
  if (mode == "commands") rc = commands(*p, arg, argc > 5 ? argv[5] : "peer");
  if (mode == "oversize") rc = oversize(*p, arg);
  std::fflush(stdout);
  return rc;
}

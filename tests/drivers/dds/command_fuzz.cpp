// libFuzzer target: command intake without DDS entities (CommandProcessor:
// rate limit, decode, validate, queue, acknowledge). Whatever a sender puts
// on rt/visvol/command must give an acknowledgement and never a crash, a
// leak or an invalid command in the real-time queue.
//
// The first byte picks how the rest is read:
//   even: a structured recipe for up to 32 Command_ messages (any kind byte,
//         any text, NaN/inf/huge numbers, up to 24 constraints, time steps)
//   odd:  one Command_ as it arrives on the wire (4-byte encapsulation header,
//         then CDR), deserialised by Cyclone's own CDR reader as a subscriber
//         would; what Cyclone refuses never reaches visvol
//
// After every command the oracle checks: the ack is accepted or rejected,
// texts are terminated and printable, a rejection says why, and an accepted
// command is the sender's, passes validation again, and holds only finite
// values inside the limits. set-constraints is judged both ways against a
// model of its rules written from the message alone (at most one clearance,
// max-agl and max-altitude each, a max-agl above the clearance, kinds 1..5,
// at most 256 observers of a kind and `max_observers` (3 here) in all): a
// command the rules allow is accepted unless the rate limit refused it, and
// one they forbid is rejected.
#include <fuzzer/FuzzedDataProvider.h>

#include <dds/ddsi/ddsi_cdrstream.h>
#include <dds/ddsi/ddsi_serdata_default.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/dds/command_processor.hpp"

namespace {

using namespace visvol;
using namespace visvol::dds;

void check(bool ok) {
  if (!ok) __builtin_trap();
}

CommandLimits make_limits() {
  CommandLimits l;
  l.min = {540000.0, 4180000.0, -10.0};
  l.max = {551100.0, 4194000.0, 900.0};
  l.max_segments = 200;
  l.max_constraints = 8;
  l.max_observers = 3;  // below the 256 of a kind and the 8 constraints: the total bound is met
  l.max_weight = 100.0;
  check(add_known_pack(l, "sf_north").ok());
  check(add_known_pack(l, "taunus").ok());
  return l;
}

const CommandLimits& limits() {
  static const CommandLimits l = make_limits();
  return l;
}

template <std::size_t N>
bool terminated_printable(const char (&text)[N]) {
  const std::string_view v = msg::text_of(text);
  if (v.size() >= N) return false;
  for (const char c : v) {
    if (c < 0x20 || c > 0x7e) return false;
  }
  return true;
}

bool finite_inside(const msg::WorldPoint& p, const CommandLimits& l) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.z_m) && p.x_m >= l.min.x_m &&
         p.x_m <= l.max.x_m && p.y_m >= l.min.y_m && p.y_m <= l.max.y_m && p.z_m >= l.min.z_m && p.z_m <= l.max.z_m;
}

bool in_range(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// An accepted command, checked independently of the validator's code.
void check_accepted(const msg::Command& c, const visvol_msgs_msg_dds__Command_& msg) {
  const CommandLimits& l = limits();
  check(c.sequence == msg.sequence_number);
  check(msg.source != nullptr && msg::text_of(c.source) == msg.source);
  check(validate_command(c, l).ok());
  switch (c.kind) {
    case msg::CommandKind::set_endpoints:
      check(finite_inside(c.endpoints.start, l) && finite_inside(c.endpoints.end, l));
      break;
    case msg::CommandKind::set_objective:
      check(c.objective == msg::Objective::hide || c.objective == msg::Objective::show);
      break;
    case msg::CommandKind::set_weights:
      check(in_range(c.weights.k1_visibility, 0.0, l.max_weight) && in_range(c.weights.k2_terrain, 0.0, l.max_weight) &&
            in_range(c.weights.k3_user, 0.0, l.max_weight) && in_range(c.weights.k4_constraint, 0.0, l.max_weight));
      break;
    case msg::CommandKind::set_stiffness:
      check(in_range(c.stiffness.stretch_n_per_m, 0.0, l.max_stretch_stiffness_n_per_m) &&
            c.stiffness.stretch_n_per_m > 0.0 &&
            in_range(c.stiffness.bend_n_m_per_rad, 0.0, l.max_bend_stiffness_n_m_per_rad));
      break;
    case msg::CommandKind::set_model:
      check(c.model == msg::RopeModel::spring_mass || c.model == msg::RopeModel::articulated);
      break;
    case msg::CommandKind::set_segment_count:
      check(c.segment_count >= l.min_segments && c.segment_count <= l.max_segments);
      break;
    case msg::CommandKind::set_constraints: {
      check(c.constraints.count <= l.max_constraints);
      int clearance = -1, max_agl = -1, max_altitude = -1;  // item index, -1: none
      std::uint32_t hidden = 0, visible = 0;
      for (std::uint32_t i = 0; i < c.constraints.count; ++i) {
        const msg::Constraint& k = c.constraints.items[i];
        const int at = static_cast<int>(i);
        if (k.kind == msg::ConstraintKind::clearance) {
          check(clearance < 0);
          clearance = at;
          check(in_range(k.height_m, 0.0, l.max_clearance_m));
        } else if (k.kind == msg::ConstraintKind::max_agl) {
          check(max_agl < 0);
          max_agl = at;
          check(in_range(k.height_m, 0.0, l.max_clearance_m) && k.height_m > 0.0);
        } else if (k.kind == msg::ConstraintKind::max_altitude) {
          check(max_altitude < 0);
          max_altitude = at;
          check(in_range(k.height_m, l.min.z_m, l.max.z_m));
        } else {
          check(k.kind == msg::ConstraintKind::hidden_from || k.kind == msg::ConstraintKind::visible_to);
          check(finite_inside(k.position, l));
          (k.kind == msg::ConstraintKind::hidden_from ? hidden : visible) += 1;
        }
      }
      check(hidden <= msg::kMaxObserversPerKind && visible <= msg::kMaxObserversPerKind);
      check(hidden + visible <= l.max_observers);
      if (clearance >= 0 && max_agl >= 0) {
        check(c.constraints.items[max_agl].height_m > c.constraints.items[clearance].height_m);
      }
      break;
    }
    case msg::CommandKind::switch_terrain:
      check(msg::text_of(c.pack_id) == "sf_north" || msg::text_of(c.pack_id) == "taunus");
      break;
    case msg::CommandKind::set_mode:
      check(c.mode == msg::InteractionMode::pull || c.mode == msg::InteractionMode::spool);
      break;
    case msg::CommandKind::start:
    case msg::CommandKind::stop: break;
    default: check(false);  // an unknown kind reached the queue
  }
}

// Whether the rules of set-constraints allow the message's items, judged
// from the raw message alone (not through decode or validate).
bool constraints_allowed(const visvol_msgs_msg_dds__Command_& msg) {
  const CommandLimits& l = limits();
  const std::uint32_t n = msg.constraints._length;
  if (n > msg::kMaxConstraints || n > l.max_constraints) return false;
  if (n > 0 && msg.constraints._buffer == nullptr) return false;
  int envelope[6] = {0, 0, 0, 0, 0, 0};  // items of each kind (1..5)
  double clearance_m = 0, max_agl_m = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    const visvol_msgs_msg_dds__Constraint_& k = msg.constraints._buffer[i];
    if (k.kind < 1 || k.kind > 5) return false;
    ++envelope[k.kind];
    const double h = k.height_m;
    const msg::WorldPoint p{k.position_m.x, k.position_m.y, k.position_m.z};
    switch (k.kind) {
      case 1:
      case 2:
        if (!finite_inside(p, l)) return false;
        break;
      case 3:
        if (!in_range(h, 0.0, l.max_clearance_m)) return false;
        clearance_m = h;
        break;
      case 4:
        if (!(in_range(h, 0.0, l.max_clearance_m) && h > 0.0)) return false;
        max_agl_m = h;
        break;
      default:
        if (!in_range(h, l.min.z_m, l.max.z_m)) return false;
    }
  }
  if (envelope[3] > 1 || envelope[4] > 1 || envelope[5] > 1) return false;
  const auto hidden = static_cast<std::size_t>(envelope[1]), visible = static_cast<std::size_t>(envelope[2]);
  if (hidden > msg::kMaxObserversPerKind || visible > msg::kMaxObserversPerKind || hidden + visible > l.max_observers) {
    return false;
  }
  // one point (within a centimetre) both hidden from and visible to
  for (std::uint32_t i = 0; i < n; ++i) {
    const auto& h = msg.constraints._buffer[i];
    if (h.kind != 1) continue;
    for (std::uint32_t j = 0; j < n; ++j) {
      const auto& v = msg.constraints._buffer[j];
      // the rule written out again, not the codec's function: an oracle of its own
      if (v.kind == 2 && std::hypot(v.position_m.x - h.position_m.x, v.position_m.y - h.position_m.y,
                                    v.position_m.z - h.position_m.z) < 0.01) {
        return false;
      }
    }
  }
  return !(envelope[3] == 1 && envelope[4] == 1 && !(max_agl_m > clearance_m));
}

// A set-constraints message the processor judged: its verdict is the rules'.
void check_constraints_verdict(const visvol_msgs_msg_dds__Command_& msg, const msg::CommandAck& ack,
                               const CommandCounts& before, const CommandCounts& after) {
  if (msg.kind != static_cast<std::uint8_t>(msg::CommandKind::set_constraints)) return;
  if (after.rate_limited != before.rate_limited || after.queue_full != before.queue_full) return;
  if (!check_source(msg.source != nullptr ? std::string_view(msg.source) : std::string_view()).ok()) return;
  check((ack.result == msg::AckResult::accepted) == constraints_allowed(msg));
}

// One command through the processor, and the oracle.
void run_one(CommandProcessor& processor, msg::CommandQueue& queue, const visvol_msgs_msg_dds__Command_& msg,
             double now_s) {
  const CommandCounts before = processor.counts();
  msg::CommandAck ack;
  std::memset(&ack, 0xa5, sizeof ack);  // nothing may be left unset
  processor.process(msg, now_s, queue, ack);
  const CommandCounts& after = processor.counts();
  check(after.received == before.received + 1);
  check(terminated_printable(ack.source));
  check(terminated_printable(ack.reason));
  check(ack.sequence == msg.sequence_number && ack.kind == msg.kind);
  check_constraints_verdict(msg, ack, before, after);
  msg::Command popped;
  if (ack.result == msg::AckResult::accepted) {
    check(ack.reason[0] == '\0');
    check(after.accepted == before.accepted + 1);
    check(queue.try_pop(popped));
    check_accepted(popped, msg);
  } else {
    check(ack.result == msg::AckResult::rejected);
    check(ack.reason[0] != '\0');
    check(after.rejected == before.rejected + 1);
    check(!queue.try_pop(popped));
  }
}

// A double that is often special: NaN, infinities, huge, tiny, or in range.
double fuzz_double(FuzzedDataProvider& fdp) {
  switch (fdp.ConsumeIntegralInRange<int>(0, 7)) {
    case 0: return std::numeric_limits<double>::quiet_NaN();
    case 1: return std::numeric_limits<double>::infinity();
    case 2: return -std::numeric_limits<double>::infinity();
    case 3: return std::numeric_limits<double>::denorm_min();
    case 4: {
      std::uint64_t bits = fdp.ConsumeIntegral<std::uint64_t>();
      double v;
      std::memcpy(&v, &bits, sizeof v);
      return v;
    }
    case 5: return fdp.ConsumeFloatingPointInRange<double>(-1.0, 1000.0);
    default: return fdp.ConsumeFloatingPointInRange<double>(-1e7, 1e7);
  }
}

// A constraint height: often one of a few round values, so that a clearance
// and a max-agl meet (equal, above, below) as often as operators make them.
double fuzz_height(FuzzedDataProvider& fdp) {
  static constexpr double kRound[] = {0.0, 30.0, 100.0, 400.0};
  if (fdp.ConsumeBool()) return kRound[fdp.ConsumeIntegralInRange<std::size_t>(0, 3)];
  return fuzz_double(fdp);
}

geometry_msgs_msg_dds__Point_ fuzz_point(FuzzedDataProvider& fdp) {
  if (fdp.ConsumeBool()) {  // near or inside the pack
    return {fdp.ConsumeFloatingPointInRange<double>(539000.0, 552000.0),
            fdp.ConsumeFloatingPointInRange<double>(4179000.0, 4195000.0),
            fdp.ConsumeFloatingPointInRange<double>(-20.0, 1000.0)};
  }
  return {fuzz_double(fdp), fuzz_double(fdp), fuzz_double(fdp)};
}

void structured(FuzzedDataProvider& fdp, CommandProcessor& processor, msg::CommandQueue& queue) {
  double now_s = 0.0;
  for (int i = 0; i < 32 && fdp.remaining_bytes() > 0; ++i) {
    std::string source = fdp.ConsumeBool() ? "operator" : fdp.ConsumeRandomLengthString(80);
    std::string pack = fdp.ConsumeBool() ? "sf_north" : fdp.ConsumeRandomLengthString(80);
    std::vector<visvol_msgs_msg_dds__Constraint_> constraints(fdp.ConsumeIntegralInRange<std::size_t>(0, 24));
    for (visvol_msgs_msg_dds__Constraint_& k : constraints) {
      k.kind = fdp.ConsumeIntegralInRange<std::uint8_t>(0, 6);
      k.position_m = fuzz_point(fdp);
      k.height_m = fuzz_height(fdp);
    }
    visvol_msgs_msg_dds__Command_ msg{};
    msg.source = source.data();
    msg.pack_id = pack.data();
    msg.sequence_number = fdp.ConsumeIntegral<std::uint64_t>();
    msg.kind =
        fdp.ConsumeBool() ? fdp.ConsumeIntegralInRange<std::uint8_t>(1, 11) : fdp.ConsumeIntegral<std::uint8_t>();
    msg.start_m = fuzz_point(fdp);
    msg.end_m = fuzz_point(fdp);
    msg.objective = fdp.ConsumeIntegralInRange<std::uint8_t>(0, 3);
    msg.k1_visibility = fuzz_double(fdp);
    msg.k2_terrain = fuzz_double(fdp);
    msg.k3_user = fuzz_double(fdp);
    msg.k4_constraint = fuzz_double(fdp);
    msg.stretch_stiffness_n_per_m = fuzz_double(fdp);
    msg.bend_stiffness_n_m_per_rad = fuzz_double(fdp);
    msg.model = fdp.ConsumeIntegralInRange<std::uint8_t>(0, 3);
    msg.segment_count =
        fdp.ConsumeBool() ? fdp.ConsumeIntegralInRange<std::uint32_t>(0, 300) : fdp.ConsumeIntegral<std::uint32_t>();
    msg.mode = fdp.ConsumeIntegralInRange<std::uint8_t>(0, 3);
    msg.constraints._buffer = constraints.data();
    msg.constraints._length = static_cast<std::uint32_t>(constraints.size());
    msg.constraints._maximum = msg.constraints._length;
    now_s += fdp.ConsumeFloatingPointInRange<double>(0.0, 0.5);
    run_one(processor, queue, msg, now_s);
  }
}

// The Command_ type as Cyclone's CDR reader sees it (what a data reader on
// the command topic would use).
const ddsi_sertype_default& command_sertype() {
  static const ddsi_sertype_default type = [] {
    ddsi_sertype_default t;
    std::memset(&t, 0, sizeof t);
    const dds_topic_descriptor_t& d = visvol_msgs_msg_dds__Command__desc;
    t.encoding_format = CDR_ENC_FORMAT_PLAIN;
    t.write_encoding_version = CDR_ENC_VERSION_1;
    t.type.size = d.m_size;
    t.type.align = d.m_align;
    t.type.flagset = d.m_flagset;
    t.type.ops.nops = d.m_nops;
    t.type.ops.ops = const_cast<std::uint32_t*>(d.m_ops);
    return t;
  }();
  return type;
}

void wire(const std::uint8_t* data, std::size_t size, CommandProcessor& processor, msg::CommandQueue& queue) {
  if (size < 4 || size > (1u << 20)) return;
  // encapsulation: plain CDR, XCDR1 (0x0000 BE, 0x0001 LE) or XCDR2 (0x0006 BE, 0x0007 LE)
  const unsigned id = (static_cast<unsigned>(data[0]) << 8) | data[1];
  bool big_endian = false;
  std::uint32_t version = CDR_ENC_VERSION_1;
  switch (id) {
    case 0x0000: big_endian = true; break;
    case 0x0001: break;
    case 0x0006:
      big_endian = true;
      version = CDR_ENC_VERSION_2;
      break;
    case 0x0007: version = CDR_ENC_VERSION_2; break;
    default: return;  // Cyclone refuses it
  }
  // Cyclone normalises in place, in an aligned buffer of its own
  std::vector<std::uint64_t> buffer((size - 4 + 7) / 8 + 1);
  std::memcpy(buffer.data(), data + 4, size - 4);
  const auto payload = static_cast<std::uint32_t>(size - 4);
  std::uint32_t actual = 0;
  const ddsi_sertype_default& type = command_sertype();
  if (!dds_stream_normalize(buffer.data(), payload, big_endian, version, &type, false, &actual)) {
    return;  // not valid CDR for Command_: dropped before intake
  }
  visvol_msgs_msg_dds__Command_ msg;
  std::memset(&msg, 0, sizeof msg);
  dds_istream_t is;
  dds_istream_init(&is, actual, buffer.data(), version);
  dds_stream_read_sample(&is, &msg, &type);
  run_one(processor, queue, msg, 0.0);
  dds_stream_free_sample(&msg, type.type.ops.ops);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // a tight rate limit, so that the fuzzer meets it often
  const RateLimit rate{4.0, 8.0, 8.0, 16.0};
  Result<CommandProcessor> processor = CommandProcessor::create(limits(), rate);
  check(processor.ok());
  static msg::CommandQueue queue;  // drained after every command by the oracle
  if ((data[0] & 1) == 0) {
    FuzzedDataProvider fdp(data + 1, size - 1);
    structured(fdp, *processor, queue);
  } else {
    wire(data + 1, size - 1, *processor, queue);
  }
  return 0;
}

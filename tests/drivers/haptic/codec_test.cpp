#include "drivers/haptic/codec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

namespace visvol::haptic {
namespace {

constexpr std::uint8_t kNode = 5;

can::CanFrame frame_of(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  can::CanFrame f;
  f.id = id;
  f.len = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (std::uint8_t b : bytes) f.data[i++] = b;
  return f;
}

// The raw value of a signal in a frame (Intel byte order), sign-extended.
double signal_value(const can::CanFrame& f, const SignalSpec& s) {
  std::uint64_t bits = 0;
  for (std::size_t i = 0; i < 8; ++i) bits |= static_cast<std::uint64_t>(f.data[i]) << (8 * i);
  std::uint64_t raw = (bits >> s.start_bit) & ((1ull << s.length_bits) - 1);
  std::int64_t value = static_cast<std::int64_t>(raw);
  if (s.is_signed && (raw >> (s.length_bits - 1)) != 0) value -= static_cast<std::int64_t>(1ull << s.length_bits);
  return static_cast<double>(value) * s.scale;
}

TEST(Codec, IdentifiersFollowTheCanopenLayout) {
  EXPECT_EQ(frame_id(MessageKind::nmt, kNode), 0x000u);
  EXPECT_EQ(frame_id(MessageKind::emergency, kNode), 0x085u);
  EXPECT_EQ(frame_id(MessageKind::position, kNode), 0x185u);
  EXPECT_EQ(frame_id(MessageKind::command, kNode), 0x205u);
  EXPECT_EQ(frame_id(MessageKind::status, kNode), 0x285u);
  EXPECT_EQ(frame_id(MessageKind::heartbeat, kNode), 0x705u);
}

TEST(Codec, PositionRoundTripsAndCarriesUnits) {
  PositionMsg p;
  p.pos_mm = {12.34, -56.78, 190.5};
  p.buttons = kButtonGrasp | kButtonClutch;
  p.sequence = 201;
  const can::CanFrame f = encode(p, kNode);
  EXPECT_EQ(f.id, 0x185u);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(f.data[0], 0xD2);  // 1234 = 0x04D2, little-endian
  EXPECT_EQ(f.data[1], 0x04);
  Message m;
  ASSERT_EQ(decode(f, m), DecodeError::ok);
  EXPECT_EQ(m.kind, MessageKind::position);
  EXPECT_EQ(m.node, kNode);
  EXPECT_NEAR(m.position.pos_mm[0], 12.34, 1e-9);
  EXPECT_NEAR(m.position.pos_mm[1], -56.78, 1e-9);
  EXPECT_NEAR(m.position.pos_mm[2], 190.5, 1e-9);
  EXPECT_EQ(m.position.buttons, kButtonGrasp | kButtonClutch);
  EXPECT_EQ(m.position.sequence, 201);
}

TEST(Codec, EveryPositionCountRoundTripsExactly) {
  for (int c = -32768; c <= 32767; ++c) {
    const auto counts = static_cast<std::int16_t>(c);
    wire::Position w{counts, static_cast<std::int16_t>(-counts - 1), 0, 0, 0};
    can::CanFrame f;
    f.id = 0x185;
    f.len = 8;
    std::memcpy(f.data.data(), &w, 8);
    Message m;
    ASSERT_EQ(decode(f, m), DecodeError::ok);
    const can::CanFrame back = encode(m.position, kNode);
    ASSERT_EQ(std::memcmp(back.data.data(), f.data.data(), 8), 0) << "count " << c;
  }
}

TEST(Codec, PositionsQuantiseToTheEncoderCount) {
  PositionMsg p;
  p.pos_mm = {0.004, 0.006, -0.015};
  Message m;
  ASSERT_EQ(decode(encode(p, kNode), m), DecodeError::ok);
  EXPECT_DOUBLE_EQ(m.position.pos_mm[0], 0.0);
  EXPECT_NEAR(m.position.pos_mm[1], 0.01, 1e-12);
  EXPECT_NEAR(std::fabs(m.position.pos_mm[2]), 0.02, 1e-12);  // half away from zero
}

TEST(Codec, CommandRoundTripsAndNeverGrowsAForce) {
  CommandMsg c;
  c.force_n = {1.2345, -0.0019, 8.5};
  c.enable = true;
  c.sequence = 7;
  Message m;
  ASSERT_EQ(decode(encode(c, kNode), m), DecodeError::ok);
  EXPECT_EQ(m.kind, MessageKind::command);
  EXPECT_NEAR(m.command.force_n[0], 1.234, 1e-12);   // toward zero
  EXPECT_NEAR(m.command.force_n[1], -0.001, 1e-12);  // toward zero
  EXPECT_NEAR(m.command.force_n[2], 8.5, 1e-12);
  EXPECT_TRUE(m.command.enable);
  EXPECT_EQ(m.command.sequence, 7);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> force(-40.0, 40.0);
  for (int i = 0; i < 100000; ++i) {
    const double f = force(rng);
    const double back = to_counts_i16_toward_zero(f, kForceNPerCount) * kForceNPerCount;
    ASSERT_LE(std::fabs(back), std::fabs(f) + 1e-9) << f;
    if (std::fabs(f) < 32.0) {
      ASSERT_GT(std::fabs(back), std::fabs(f) - kForceNPerCount - 1e-9) << f;
    }
  }
}

TEST(Codec, SignalConversionsSaturateAndMapNanToZero) {
  EXPECT_EQ(to_counts_i16(1e9, 0.01), 32767);
  EXPECT_EQ(to_counts_i16(-1e9, 0.01), -32768);
  EXPECT_EQ(to_counts_i16(std::nan(""), 0.01), 0);
  EXPECT_EQ(to_counts_i16_toward_zero(std::nan(""), 0.001), 0);
  EXPECT_EQ(to_counts_i16_toward_zero(-1e9, 0.001), -32768);
  EXPECT_EQ(to_counts_u16(-5.0, 0.001), 0);
  EXPECT_EQ(to_counts_u16(1e9, 0.001), 65535);
  EXPECT_EQ(to_counts_i16(std::numeric_limits<double>::infinity(), 0.1), 32767);
}

TEST(Codec, StatusEmergencyHeartbeatNmtRoundTrip) {
  StatusMsg s;
  s.nmt_state = NmtState::operational;
  s.flags = kStatusForceEnabled | kStatusSaturated;
  s.fault_bits = kFaultOverTemperature | 0x0100;
  s.motor_temperature_c = -12.3;
  s.sequence = 99;
  Message m;
  ASSERT_EQ(decode(encode(s, kNode), m), DecodeError::ok);
  EXPECT_EQ(m.status.nmt_state, NmtState::operational);
  EXPECT_EQ(m.status.flags, s.flags);
  EXPECT_EQ(m.status.fault_bits, s.fault_bits);
  EXPECT_NEAR(m.status.motor_temperature_c, -12.3, 1e-9);
  EXPECT_EQ(m.status.sequence, 99);

  EmergencyMsg e;
  e.code = 0x4210;
  e.error_register = 0x09;
  e.axis = 2;
  e.temperature_c = 91.5;
  e.current_a = 2.345;
  ASSERT_EQ(decode(encode(e, kNode), m), DecodeError::ok);
  EXPECT_EQ(m.kind, MessageKind::emergency);
  EXPECT_EQ(m.emergency.code, 0x4210);
  EXPECT_EQ(m.emergency.error_register, 0x09);
  EXPECT_EQ(m.emergency.axis, 2);
  EXPECT_NEAR(m.emergency.temperature_c, 91.5, 1e-9);
  EXPECT_NEAR(m.emergency.current_a, 2.345, 1e-9);
  EXPECT_STREQ(emergency_name(0x4210), "over-temperature");
  EXPECT_STREQ(emergency_name(0x1234), "unknown");

  for (NmtState st : {NmtState::boot_up, NmtState::stopped, NmtState::operational, NmtState::pre_operational}) {
    HeartbeatMsg hb;
    hb.state = st;
    const can::CanFrame f = encode(hb, kNode);
    EXPECT_EQ(f.id, 0x705u);
    EXPECT_EQ(f.len, 1);
    ASSERT_EQ(decode(f, m), DecodeError::ok);
    EXPECT_EQ(m.heartbeat.state, st);
  }
  NmtMsg n;
  n.command = NmtCommand::start;
  n.node = kNode;
  const can::CanFrame f = encode(n);
  EXPECT_EQ(f.id, 0u);
  EXPECT_EQ(f.len, 2);
  EXPECT_EQ(f.data[0], 0x01);
  EXPECT_EQ(f.data[1], kNode);
  ASSERT_EQ(decode(f, m), DecodeError::ok);
  EXPECT_EQ(m.kind, MessageKind::nmt);
  EXPECT_EQ(m.nmt.command, NmtCommand::start);
  EXPECT_EQ(m.nmt.node, kNode);
}

TEST(Codec, EveryWrongLengthIsMalformed) {
  for (const FrameSpec& spec : kFrames) {
    for (std::uint8_t len = 0; len <= 8; ++len) {
      if (len == spec.dlc) continue;
      can::CanFrame f;
      f.id = frame_id(spec.kind, kNode);
      f.len = len;
      Message m;
      EXPECT_EQ(decode(f, m), DecodeError::wrong_length) << spec.name << " len " << int(len);
    }
  }
  can::CanFrame f;
  f.id = 0x185;
  f.len = 9;  // not classic CAN
  Message m;
  EXPECT_EQ(decode(f, m), DecodeError::wrong_length);
  EXPECT_EQ(decode(0, 0x185, nullptr, 8, m), DecodeError::wrong_length) << "no bytes behind the length";
}

TEST(Codec, ReservedBitsAndUnknownValuesAreMalformed) {
  Message m;
  EXPECT_EQ(decode(frame_of(0x185, {0, 0, 0, 0, 0, 0, 0x08, 0}), m), DecodeError::reserved_bits);
  EXPECT_EQ(decode(frame_of(0x185, {0, 0, 0, 0, 0, 0, 0x04, 0}), m), DecodeError::ok) << "bit 2: the mode button";
  EXPECT_EQ(decode(frame_of(0x185, {0, 0, 0, 0, 0, 0, 0x80, 0}), m), DecodeError::reserved_bits);
  EXPECT_EQ(decode(frame_of(0x205, {0, 0, 0, 0, 0, 0, 0x02, 0}), m), DecodeError::reserved_bits);
  EXPECT_EQ(decode(frame_of(0x285, {0x05, 0x08, 0, 0, 0, 0, 0, 0}), m), DecodeError::reserved_bits);
  EXPECT_EQ(decode(frame_of(0x285, {0x05, 0, 0, 0, 0, 0, 0x01, 0}), m), DecodeError::reserved_bits);
  EXPECT_EQ(decode(frame_of(0x285, {0x06, 0, 0, 0, 0, 0, 0, 0}), m), DecodeError::bad_value);
  EXPECT_EQ(decode(frame_of(0x085, {0x10, 0x42, 0x09, 3, 0, 0, 0, 0}), m), DecodeError::bad_value) << "axis 3";
  EXPECT_EQ(decode(frame_of(0x000, {0x03, kNode}), m), DecodeError::bad_value);
  EXPECT_EQ(decode(frame_of(0x000, {0x01, 128}), m), DecodeError::bad_value);
  int valid_states = 0;
  for (int v = 0; v < 256; ++v) {
    if (decode(frame_of(0x705, {static_cast<std::uint8_t>(v)}), m) == DecodeError::ok) ++valid_states;
  }
  EXPECT_EQ(valid_states, 4);
}

TEST(Codec, ForeignFramesAreNotMessages) {
  Message m;
  can::CanFrame ext = frame_of(0x185, {0, 0, 0, 0, 0, 0, 0, 0});
  ext.flags = can::CanFrame::kExtended;
  EXPECT_EQ(decode(ext, m), DecodeError::not_data_frame);
  can::CanFrame rtr = frame_of(0x185, {});
  rtr.flags = can::CanFrame::kRemote;
  EXPECT_EQ(decode(rtr, m), DecodeError::not_data_frame);
  can::CanFrame err = frame_of(can::err::kBusOff, {0, 0, 0, 0, 0, 0, 0, 0});
  err.flags = can::CanFrame::kError;
  EXPECT_EQ(decode(err, m), DecodeError::not_data_frame);
  for (std::uint32_t id :
       {0x001u, 0x07Fu, 0x080u, 0x100u, 0x105u, 0x180u, 0x300u, 0x385u, 0x580u, 0x605u, 0x680u, 0x7FFu}) {
    EXPECT_EQ(decode(frame_of(id, {0, 0, 0, 0, 0, 0, 0, 0}), m), DecodeError::unknown_id) << std::hex << id;
  }
  const std::uint8_t bytes[8] = {};
  EXPECT_EQ(decode(0, 0x800, bytes, 8, m), DecodeError::unknown_id);
}

// Any frame that decodes re-encodes to exactly the same bytes: one encoding per message.
TEST(Codec, RandomFramesNeverCrashAndValidOnesAreCanonical) {
  std::mt19937_64 rng(11);
  int valid = 0;
  for (int i = 0; i < 200000; ++i) {
    can::CanFrame f;
    const std::uint32_t bases[] = {0x000, 0x080, 0x180, 0x200, 0x280, 0x700};
    f.id = (rng() % 4 == 0) ? static_cast<std::uint32_t>(rng() % 0x800) : bases[rng() % 6] + (rng() % 128);
    f.len = static_cast<std::uint8_t>(rng() % 9);
    for (auto& b : f.data) b = static_cast<std::uint8_t>(rng());
    if (rng() % 2 == 0) {  // often make reserved fields legal, to reach deeper
      if ((f.id & 0x780) == 0x180) f.data[6] &= 0x03;
      if ((f.id & 0x780) == 0x200) f.data[6] &= 0x01;
      if ((f.id & 0x780) == 0x280) {
        f.data[0] = 0x05;
        f.data[1] &= 0x07;
        f.data[6] = 0;
      }
      if ((f.id & 0x780) == 0x700) f.data[0] = 0x7F;
      if ((f.id & 0x780) == 0x080) f.data[3] = 0xFF;
      if (f.id == 0) {
        f.data[0] = 0x01;
        f.data[1] &= 0x7F;
      }
      f.len = frame_spec(f.id == 0 ? MessageKind::nmt : MessageKind::position).dlc;
      if ((f.id & 0x780) == 0x700) f.len = 1;
    }
    Message m;
    if (decode(f, m) != DecodeError::ok) continue;
    ++valid;
    const can::CanFrame back = encode(m);
    ASSERT_EQ(back.id, f.id);
    ASSERT_EQ(back.len, f.len);
    ASSERT_EQ(std::memcmp(back.data.data(), f.data.data(), f.len), 0) << "id " << std::hex << f.id;
  }
  EXPECT_GT(valid, 50000);
}

// Every signal of the table sits where it says in encoded frames.
TEST(Codec, SignalTableMatchesTheEncoder) {
  Message m;
  m.node = kNode;
  std::map<std::string, double> expect;
  auto check = [&](MessageKind kind) {
    m.kind = kind;
    const can::CanFrame f = encode(m);
    for (const SignalSpec& s : kSignals) {
      if (s.kind != kind) continue;
      ASSERT_TRUE(expect.count(s.name)) << s.name;
      EXPECT_NEAR(signal_value(f, s), expect[s.name], 1e-9) << s.name;
    }
  };
  m.position = {{-1.5, 2.25, 100.0}, kButtonClutch | kButtonMode, 42};
  expect = {{"Pos_X", -1.5},         {"Pos_Y", 2.25},       {"Pos_Z", 100.0},           {"Pos_ButtonGrasp", 0},
            {"Pos_ButtonClutch", 1}, {"Pos_ButtonMode", 1}, {"Pos_ButtonsReserved", 0}, {"Pos_Sequence", 42}};
  check(MessageKind::position);
  m.command = {{0.5, -1.25, 3.0}, true, 200};
  expect = {{"Cmd_ForceX", 0.5}, {"Cmd_ForceY", -1.25},    {"Cmd_ForceZ", 3.0},
            {"Cmd_Enable", 1},   {"Cmd_FlagsReserved", 0}, {"Cmd_Sequence", 200}};
  check(MessageKind::command);
  m.status = {NmtState::pre_operational, kStatusWatchdog, static_cast<std::uint16_t>(kFaultEncoder | 0x0120), 45.6, 3};
  expect = {{"St_NmtState", 127},
            {"St_ForceEnabled", 0},
            {"St_Watchdog", 1},
            {"St_Saturated", 0},
            {"St_FlagsReserved", 0},
            {"St_FaultOverCurrent", 0},
            {"St_FaultOverTemperature", 0},
            {"St_FaultAmplifier", 0},
            {"St_FaultEncoder", 1},
            {"St_FaultOther", 0x012},
            {"St_MotorTemperature", 45.6},
            {"St_Reserved", 0},
            {"St_Sequence", 3}};
  check(MessageKind::status);
  m.emergency = {0x2310, 0x03, 1, -5.5, 1.5};
  expect = {
      {"Emcy_Code", 0x2310}, {"Emcy_Register", 3}, {"Emcy_Axis", 1}, {"Emcy_Temperature", -5.5}, {"Emcy_Current", 1.5}};
  check(MessageKind::emergency);
  m.heartbeat = {NmtState::stopped};
  expect = {{"Hb_State", 4}};
  check(MessageKind::heartbeat);
  m.nmt = {NmtCommand::reset_node, 9};
  expect = {{"NMT_Command", 0x81}, {"NMT_Node", 9}};
  check(MessageKind::nmt);
}

// One line of a DBC file, parsed with sscanf (std::regex trips a false
// -Wmaybe-uninitialized in GCC 12's libstdc++ under the sanitizers).
struct DbcFrame {
  std::uint32_t id = 0;
  std::string name;
  unsigned dlc = 0;
  std::string sender;
};
bool parse_frame(const std::string& line, DbcFrame& f) {
  char name[64] = {}, sender[64] = {};
  if (std::sscanf(line.c_str(), "BO_ %u %63[^:]: %u %63s", &f.id, name, &f.dlc, sender) != 4) return false;
  f.name = name;
  f.sender = sender;
  return true;
}
struct DbcSignal {
  std::string name;
  unsigned start = 0, length = 0;
  char sign = '?';
  double scale = 0.0, offset = 0.0;
  std::string unit;
};
bool parse_signal(const std::string& line, DbcSignal& s) {
  char name[64] = {};
  int used = 0;
  if (std::sscanf(line.c_str(), " SG_ %63s : %u|%u@1%c (%lf,%lf)%n", name, &s.start, &s.length, &s.sign, &s.scale,
                  &s.offset, &used) != 6) {
    return false;
  }
  const std::size_t q1 = line.find('"', static_cast<std::size_t>(used));
  const std::size_t q2 = q1 == std::string::npos ? q1 : line.find('"', q1 + 1);
  if (q2 == std::string::npos) return false;
  s.name = name;
  s.unit = line.substr(q1 + 1, q2 - q1 - 1);
  return true;
}

// haptic.dbc declares exactly the frames and signals of protocol.hpp.
TEST(Codec, DbcFileMatchesTheProtocolTables) {
  std::ifstream in(VISVOL_HAPTIC_DBC);
  ASSERT_TRUE(in) << VISVOL_HAPTIC_DBC;
  std::map<std::string, DbcFrame> frames;                            // by name
  std::map<std::string, std::pair<std::string, DbcSignal>> signals;  // name -> (frame, signal)
  std::map<std::uint32_t, int> cycle_ms;
  std::string line, current;
  while (std::getline(in, line)) {
    DbcFrame f;
    DbcSignal sig;
    unsigned id = 0;
    int ms = 0;
    if (parse_frame(line, f)) {
      current = f.name;
      frames[f.name] = f;
    } else if (parse_signal(line, sig)) {
      signals[sig.name] = {current, sig};
    } else if (std::sscanf(line.c_str(), "BA_ \"GenMsgCycleTime\" BO_ %u %d;", &id, &ms) == 2) {
      cycle_ms[id] = ms;
    } else {
      ASSERT_EQ(line.rfind(" SG_", 0), std::string::npos) << "unparsed signal line: " << line;
      ASSERT_EQ(line.rfind("BO_ ", 0), std::string::npos) << "unparsed frame line: " << line;
    }
  }
  ASSERT_EQ(frames.size(), kFrames.size());
  for (const FrameSpec& f : kFrames) {
    ASSERT_TRUE(frames.count(f.name)) << f.name;
    const DbcFrame& d = frames[f.name];
    EXPECT_EQ(d.id, frame_id(f.kind, 1)) << f.name << ": the DBC is for node 1";
    EXPECT_EQ(d.dlc, f.dlc) << f.name;
    EXPECT_EQ(d.sender, f.from_device ? "Device" : "Console") << f.name;
    if (f.rate_hz > 0.0) {
      EXPECT_EQ(cycle_ms[d.id], static_cast<int>(std::lround(1000.0 / f.rate_hz))) << f.name;
    }
  }
  ASSERT_EQ(signals.size(), kSignals.size());
  for (const SignalSpec& s : kSignals) {
    ASSERT_TRUE(signals.count(s.name)) << s.name;
    const auto& [frame, d] = signals[s.name];
    EXPECT_EQ(frame, frame_spec(s.kind).name) << s.name;
    EXPECT_EQ(d.unit, s.unit) << s.name;
    EXPECT_EQ(d.start, s.start_bit) << s.name;
    EXPECT_EQ(d.length, s.length_bits) << s.name;
    EXPECT_EQ(d.sign, s.is_signed ? '-' : '+') << s.name;
    EXPECT_DOUBLE_EQ(d.scale, s.scale) << s.name;
    EXPECT_EQ(d.offset, 0.0) << s.name;
  }
}

TEST(Codec, BusLoadFiguresOfTheChosenFrames) {
  double nominal_bps = 0.0, stuffed_bps = 0.0;
  for (const FrameSpec& f : kFrames) {
    nominal_bps += f.rate_hz * frame_bits(f.dlc);
    stuffed_bps += f.rate_hz * frame_bits_stuffed(f.dlc);
  }
  EXPECT_NEAR(nominal_bps, 234200.0, 1e-6);
  EXPECT_NEAR(stuffed_bps, 284800.0, 1e-6);
  EXPECT_LT(stuffed_bps / 1e6, 0.30) << "leaves room on a 1 Mbit/s bus";
}

}  // namespace
}  // namespace visvol::haptic

#include "drivers/hapticsim/script.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "base/decimal_text.hpp"
#include "io/input_file.hpp"

namespace visvol::hapticsim {
namespace {

constexpr double kMaxSeconds = 1e6;
// far beyond any script written by hand or generated for a test
constexpr std::size_t kMaxScriptBytes = 16u << 20;
constexpr double kDefaultStrokeMm = 60.0;
constexpr int kMaxDragStrokes = 10000;  // 600 m of hand travel in default strokes
// Events a script may hold in all (drags on many lines add up; the console
// loads its script into locked memory): about an hour of a hand at 250 Hz.
constexpr std::size_t kMaxScriptEvents = 1000000;
constexpr double kDefaultRebootS = 0.2;
constexpr std::uint32_t kMaxGarbage = 1'000'000;

std::int64_t to_ns(double s) { return static_cast<std::int64_t>(std::llround(s * 1e9)); }

// Parses one script line's tokens into events, tracking the hand target and
// the end of the current motion across lines.
class LineParser {
 public:
  LineParser(const std::string& source, const std::array<double, 3>& half_mm, Script& out)
      : source_(source), half_mm_(half_mm), out_(out) {}

  Status parse(int line, const std::vector<std::string>& tok);

 private:
  Status error(const std::string& what) const {
    return invalid_argument(source_ + ":" + std::to_string(line_) + ": " + what);
  }
  Status number(const std::string& text, const char* what, double& out) const;
  Status seconds(const std::string& text, const char* what, bool allow_zero, double& out) const;
  Status expect_args(const std::vector<std::string>& tok, std::size_t lo, std::size_t hi) const;
  Status check_target(const std::array<double, 3>& t) const;
  Status start_motion(double t_s) const;
  Status vector3(const std::vector<std::string>& tok, std::array<double, 3>& out) const;
  void push(ScriptEvent e, double busy_s = 0.0);
  void push_move(double t_s, const std::array<double, 3>& to, double dur_s);
  void push_clutch(double t_s, bool on);
  Status push_drag(const std::array<double, 3>& start, const std::array<double, 3>& by_mm, double dur_s,
                   const std::vector<std::string>& tok);

  const std::string& source_;
  std::array<double, 3> half_mm_;
  Script& out_;
  int line_ = 0;
  double time_s_ = 0.0;
  double last_time_s_ = 0.0;
  std::array<double, 3> target_mm_{};
  double motion_end_s_ = 0.0;
  int motion_line_ = 0;
};

Status LineParser::number(const std::string& text, const char* what, double& out) const {
  // decimal only, as a path file's: strtod also reads hexadecimal (0x1p3) and
  // "infinity", which a script should not mean
  const bool decimal = is_decimal_number(text);
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  if (!decimal || end == text.c_str() || *end != '\0' || !std::isfinite(out)) {
    return error(std::string(what) + " '" + text + "' is not a finite number");
  }
  return Status::ok_status();
}

Status LineParser::seconds(const std::string& text, const char* what, bool allow_zero, double& out) const {
  VISVOL_RETURN_IF_ERROR(number(text, what, out));
  if (out < 0.0 || (!allow_zero && out == 0.0) || out > kMaxSeconds) {
    return error(std::string(what) + " " + text + (allow_zero ? " must lie in [0, " : " must lie in (0, ") + "1e6] s");
  }
  return Status::ok_status();
}

Status LineParser::expect_args(const std::vector<std::string>& tok, std::size_t lo, std::size_t hi) const {
  const std::size_t n = tok.size() - 2;
  if (n < lo || n > hi) {
    const std::string want = lo == hi ? std::to_string(lo) : std::to_string(lo) + " to " + std::to_string(hi);
    return error("'" + tok[1] + "' takes " + want + " argument(s), got " + std::to_string(n));
  }
  return Status::ok_status();
}

Status LineParser::check_target(const std::array<double, 3>& t) const {
  for (std::size_t i = 0; i < 3; ++i) {
    if (std::fabs(t[i]) > half_mm_[i]) {
      return error("hand target " + std::to_string(t[i]) + " mm on axis " + "xyz"[i] + " is outside the workspace (+-" +
                   std::to_string(half_mm_[i]) + " mm)");
    }
  }
  return Status::ok_status();
}

Status LineParser::start_motion(double t_s) const {
  if (t_s < motion_end_s_) {
    return error("motion starts at " + std::to_string(t_s) + " s, before the motion of line " +
                 std::to_string(motion_line_) + " ends at " + std::to_string(motion_end_s_) + " s");
  }
  return Status::ok_status();
}

Status LineParser::vector3(const std::vector<std::string>& tok, std::array<double, 3>& out) const {
  for (std::size_t i = 0; i < 3; ++i) VISVOL_RETURN_IF_ERROR(number(tok[2 + i], "distance", out[i]));
  return Status::ok_status();
}

void LineParser::push(ScriptEvent e, double busy_s) {
  e.line = line_;
  out_.end_s = std::max(out_.end_s, e.time_s + busy_s);
  out_.events.push_back(e);
}

void LineParser::push_move(double t_s, const std::array<double, 3>& to, double dur_s) {
  ScriptEvent e;
  e.time_s = t_s;
  e.action = Action::move;
  e.target_mm = to;
  e.duration_s = dur_s;
  push(e, dur_s);
  target_mm_ = to;
  motion_end_s_ = std::max(motion_end_s_, t_s + dur_s);
  motion_line_ = line_;
}

void LineParser::push_clutch(double t_s, bool on) {
  ScriptEvent e;
  e.time_s = t_s;
  e.action = on ? Action::clutch_on : Action::clutch_off;
  push(e);
}

Status LineParser::push_drag(const std::array<double, 3>& start, const std::array<double, 3>& by_mm, double dur_s,
                             const std::vector<std::string>& tok) {
  double stroke_mm = kDefaultStrokeMm;
  if (tok.size() == 7) {
    VISVOL_RETURN_IF_ERROR(number(tok[6], "stroke", stroke_mm));
    if (stroke_mm <= 0.0 || stroke_mm > 1000.0) return error("stroke " + tok[6] + " must lie in (0, 1000] mm");
  }
  const double length_mm = std::sqrt(by_mm[0] * by_mm[0] + by_mm[1] * by_mm[1] + by_mm[2] * by_mm[2]);
  // bounded before the conversion: every stroke is four events, held in memory
  const double stroke_count = std::ceil(length_mm / stroke_mm - 1e-9);
  if (!(stroke_count <= kMaxDragStrokes)) {
    return error("a drag of " + std::to_string(length_mm) + " mm in strokes of " + std::to_string(stroke_mm) +
                 " mm is more than " + std::to_string(kMaxDragStrokes) + " strokes");
  }
  const int strokes = std::max(1, static_cast<int>(stroke_count));
  if (out_.events.size() + 4 * static_cast<std::size_t>(strokes) > kMaxScriptEvents) {
    return error("the script's drags come to more than " + std::to_string(kMaxScriptEvents) + " events");
  }
  const double slot_s = dur_s / strokes;
  const std::array<double, 3> delta = {by_mm[0] / strokes, by_mm[1] / strokes, by_mm[2] / strokes};
  const double t0_s = time_s_;
  for (int k = 0; k < strokes; ++k) {
    const double t_s = t0_s + k * slot_s;
    const std::array<double, 3> to = {start[0] + delta[0], start[1] + delta[1], start[2] + delta[2]};
    VISVOL_RETURN_IF_ERROR(check_target(to));
    if (k == strokes - 1) {
      push_move(t_s, to, slot_s);
      break;
    }
    // Forward with the rope (60% of the slot), back to the stroke's start with
    // the clutch held (25%), rest until the handle settles, release the clutch
    // (at 95%), and the next stroke starts on time.
    const double back_s = t_s + 0.60 * slot_s;
    const double home_s = t_s + 0.85 * slot_s;
    push_move(t_s, to, back_s - t_s);
    push_clutch(back_s, true);
    push_move(back_s, start, home_s - back_s);
    push_clutch(t_s + 0.95 * slot_s, false);
  }
  return Status::ok_status();
}

Status LineParser::parse(int line, const std::vector<std::string>& tok) {
  line_ = line;
  if (out_.events.size() >= kMaxScriptEvents) return error("more than " + std::to_string(kMaxScriptEvents) + " events");
  VISVOL_RETURN_IF_ERROR(seconds(tok[0], "time", true, time_s_));
  if (time_s_ < last_time_s_) {
    return error("time " + tok[0] + " s is before the previous event's " + std::to_string(last_time_s_) + " s");
  }
  last_time_s_ = time_s_;
  if (tok.size() < 2) return error("missing action after the time");
  const std::string& a = tok[1];
  ScriptEvent e;
  e.time_s = time_s_;
  const auto simple = [&](Action action) -> Status {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 0, 0));
    e.action = action;
    push(e);
    return Status::ok_status();
  };
  const auto timed = [&](Action action) -> Status {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 1, 1));
    VISVOL_RETURN_IF_ERROR(seconds(tok[2], "duration", false, e.duration_s));
    e.action = action;
    push(e, e.duration_s);
    return Status::ok_status();
  };

  if (a == "hold") return simple(Action::hold);
  if (a == "let-go") return simple(Action::let_go);
  if (a == "grab") return simple(Action::grab);
  if (a == "release") return simple(Action::release);
  if (a == "end") {
    VISVOL_RETURN_IF_ERROR(simple(Action::end));
    out_.has_end = true;
    out_.end_s = time_s_;
    return Status::ok_status();
  }
  if (a == "clutch") {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 1, 1));
    if (tok[2] != "on" && tok[2] != "off") return error("clutch takes 'on' or 'off', got '" + tok[2] + "'");
    push_clutch(time_s_, tok[2] == "on");
    return Status::ok_status();
  }
  if (a == "mode") {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 1, 1));
    if (tok[2] != "on" && tok[2] != "off") return error("mode takes 'on' or 'off', got '" + tok[2] + "'");
    e.action = tok[2] == "on" ? Action::mode_on : Action::mode_off;
    push(e);
    return Status::ok_status();
  }
  if (a == "move" || a == "pull" || a == "drag") {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 4, a == "drag" ? 5 : 4));
    std::array<double, 3> v{};
    VISVOL_RETURN_IF_ERROR(vector3(tok, v));
    double dur_s = 0.0;
    VISVOL_RETURN_IF_ERROR(seconds(tok[5], "duration", a == "move", dur_s));
    VISVOL_RETURN_IF_ERROR(start_motion(time_s_));
    if (a == "move") {
      VISVOL_RETURN_IF_ERROR(check_target(v));
      push_move(time_s_, v, dur_s);
      return Status::ok_status();
    }
    e.action = Action::grab;
    push(e);
    const std::array<double, 3> start = target_mm_;
    if (a == "pull") {
      const std::array<double, 3> to = {start[0] + v[0], start[1] + v[1], start[2] + v[2]};
      VISVOL_RETURN_IF_ERROR(check_target(to));
      push_move(time_s_, to, dur_s);
      return Status::ok_status();
    }
    return push_drag(start, v, dur_s, tok);
  }
  if (a == "drop") {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 1, 1));
    VISVOL_RETURN_IF_ERROR(number(tok[2], "fraction", e.fraction));
    if (e.fraction < 0.0 || e.fraction > 1.0) return error("drop fraction " + tok[2] + " must lie in [0, 1]");
    e.action = Action::drop;
    push(e);
    return Status::ok_status();
  }
  if (a == "silent") return timed(Action::silent);
  if (a == "wrong-length") return timed(Action::wrong_length);
  if (a == "freeze") return timed(Action::freeze);
  if (a == "bus-off") return timed(Action::bus_off);
  if (a == "reboot") {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 0, 1));
    e.duration_s = kDefaultRebootS;
    if (tok.size() == 3) VISVOL_RETURN_IF_ERROR(seconds(tok[2], "duration", true, e.duration_s));
    e.action = Action::reboot;
    push(e, e.duration_s);
    return Status::ok_status();
  }
  if (a == "garbage") {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 1, 1));
    double n = 0.0;
    VISVOL_RETURN_IF_ERROR(number(tok[2], "frame count", n));
    if (n < 1.0 || n > kMaxGarbage || n != std::floor(n)) {
      return error("garbage frame count " + tok[2] + " must be a whole number in 1..1000000");
    }
    e.action = Action::garbage;
    e.count = static_cast<std::uint32_t>(n);
    push(e, n * 1e-3);
    return Status::ok_status();
  }
  if (a == "emergency") {
    VISVOL_RETURN_IF_ERROR(expect_args(tok, 2, 2));
    const std::string& kind = tok[2];
    if (kind == "over-current") e.fault_bit = haptic::kFaultOverCurrent;
    else if (kind == "over-temperature") e.fault_bit = haptic::kFaultOverTemperature;
    else if (kind == "amplifier") e.fault_bit = haptic::kFaultAmplifier;
    else if (kind == "encoder") e.fault_bit = haptic::kFaultEncoder;
    else return error("unknown emergency '" + kind + "' (over-current, over-temperature, amplifier, encoder)");
    VISVOL_RETURN_IF_ERROR(seconds(tok[3], "duration", false, e.duration_s));
    e.action = Action::emergency;
    push(e, e.duration_s);
    return Status::ok_status();
  }
  return error("unknown action '" + a + "'");
}

}  // namespace

Result<Script> parse_script(const std::string& text, const std::string& source,
                            const std::array<double, 3>& workspace_half_mm) {
  Script script;
  LineParser parser(source, workspace_half_mm, script);
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::size_t hash = raw.find('#');
    if (hash != std::string::npos) raw.resize(hash);
    std::istringstream words(raw);
    std::vector<std::string> tok;
    for (std::string w; words >> w;) tok.push_back(w);
    if (tok.empty()) continue;
    VISVOL_RETURN_IF_ERROR(parser.parse(line, tok));
  }
  std::stable_sort(script.events.begin(), script.events.end(),
                   [](const ScriptEvent& a, const ScriptEvent& b) { return a.time_s < b.time_s; });
  return script;
}

Result<Script> load_script(const std::string& path, const std::array<double, 3>& workspace_half_mm) {
  // a script that cannot be read is bad input, whatever the reason
  Result<std::string> text = read_input_file(path, kMaxScriptBytes);
  if (!text.ok()) {
    const std::string& m = text.status().message();
    const std::string reason = m.rfind(path + ": ", 0) == 0 ? m.substr(path.size() + 2) : m;
    return invalid_argument(path + ": cannot open the script: " + reason);
  }
  return parse_script(*text, path, workspace_half_mm);
}

void Player::advance(double t_s, std::int64_t now_ns, SimDevice& device) {
  const std::vector<ScriptEvent>& events = script_->events;
  while (next_ < events.size() && events[next_].time_s <= t_s) apply(events[next_++], now_ns, device);
  if (t_s < t1_s_ && t1_s_ > t0_s_) {
    const double u = std::clamp((t_s - t0_s_) / (t1_s_ - t0_s_), 0.0, 1.0);
    for (std::size_t i = 0; i < 3; ++i) hand_.target_mm[i] = from_mm_[i] + u * (to_mm_[i] - from_mm_[i]);
  } else {
    hand_.target_mm = to_mm_;
  }
  device.set_hand(hand_);
}

void Player::apply(const ScriptEvent& e, std::int64_t now_ns, SimDevice& device) {
  const std::int64_t dur_ns = to_ns(e.duration_s);
  switch (e.action) {
    case Action::hold: hand_.holding = true; break;
    case Action::let_go: hand_.holding = false; break;
    case Action::move:
      from_mm_ = to_mm_;
      to_mm_ = e.target_mm;
      t0_s_ = e.time_s;
      t1_s_ = e.time_s + e.duration_s;
      break;
    case Action::grab: hand_.grasp = true; break;
    case Action::release: hand_.grasp = false; break;
    case Action::clutch_on: hand_.clutch = true; break;
    case Action::clutch_off: hand_.clutch = false; break;
    case Action::mode_on: hand_.mode = true; break;
    case Action::mode_off: hand_.mode = false; break;
    case Action::drop: device.inject_drop(e.fraction); break;
    case Action::silent: device.inject_silence(now_ns, dur_ns); break;
    case Action::garbage: device.inject_garbage(e.count); break;
    case Action::wrong_length: device.inject_wrong_length(now_ns, dur_ns); break;
    case Action::freeze: device.inject_freeze(now_ns, dur_ns); break;
    case Action::reboot: device.inject_reboot(now_ns, dur_ns); break;
    case Action::bus_off: device.inject_bus_off(now_ns, dur_ns); break;
    case Action::emergency: device.inject_emergency(now_ns, e.fault_bit, dur_ns); break;
    case Action::end: ended_ = true; break;
  }
}

}  // namespace visvol::hapticsim

#include "msg/samples.hpp"

#include <time.h>

namespace visvol::msg {

const char* to_string(Objective value) {
  switch (value) {
    case Objective::hide: return "hide";
    case Objective::show: return "show";
  }
  return nullptr;
}
const char* to_string(RopeModel value) {
  switch (value) {
    case RopeModel::spring_mass: return "spring";
    case RopeModel::articulated: return "articulated";
  }
  return nullptr;
}
const char* to_string(InteractionMode value) {
  switch (value) {
    case InteractionMode::pull: return "pull";
    case InteractionMode::spool: return "spool";
  }
  return nullptr;
}
const char* to_string(CatalogueState value) {
  switch (value) {
    case CatalogueState::verifying: return "verifying";
    case CatalogueState::verified: return "verified";
    case CatalogueState::refused: return "refused";
  }
  return nullptr;
}
const char* to_string(ConstraintKind value) {
  switch (value) {
    case ConstraintKind::hidden_from: return "hidden-from";
    case ConstraintKind::visible_to: return "visible-to";
    case ConstraintKind::clearance: return "clearance";
    case ConstraintKind::max_agl: return "max-agl";
    case ConstraintKind::max_altitude: return "max-altitude";
  }
  return nullptr;
}
const char* to_string(CommandKind value) {
  switch (value) {
    case CommandKind::set_endpoints: return "set-endpoints";
    case CommandKind::set_objective: return "set-objective";
    case CommandKind::set_weights: return "set-weights";
    case CommandKind::set_stiffness: return "set-stiffness";
    case CommandKind::set_model: return "set-model";
    case CommandKind::set_segment_count: return "set-segments";
    case CommandKind::set_constraints: return "set-constraints";
    case CommandKind::start: return "start";
    case CommandKind::stop: return "stop";
    case CommandKind::switch_terrain: return "switch-terrain";
    case CommandKind::set_mode: return "set-mode";
  }
  return nullptr;
}
const char* to_string(AckResult value) {
  switch (value) {
    case AckResult::accepted: return "accepted";
    case AckResult::rejected: return "rejected";
    case AckResult::applied: return "applied";
    case AckResult::failed: return "failed";
  }
  return nullptr;
}
const char* to_string(DeviceState value) {
  switch (value) {
    case DeviceState::unknown: return "unknown";
    case DeviceState::disconnected: return "disconnected";
    case DeviceState::idle: return "idle";
    case DeviceState::active: return "active";
    case DeviceState::fault: return "fault";
  }
  return nullptr;
}

std::int64_t now_stamp_ns() {
  constexpr std::int64_t kNsPerS = 1000000000;
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

}  // namespace visvol::msg

// The mission options `visvol plan`, `visvol check` and the console share: the vehicle's
// flight envelope and the observers a path must stay hidden from or visible to.
//
// --vehicle is a preset (fixed-wing, multirotor) or a small TOML file of the
// envelope's keys, spelled as the options are:
//   name = "survey plane"        # shown in reports
//   type = "fixed-wing"          # or "multirotor"
//   autopilot = "px4"            # or "ardupilot": the .plan's firmware
//   speed = 22.0                 # m/s
//   max-climb = 12.0             # deg
//   max-descent = 10.0           # deg
//   min-turn-radius = 120.0      # m
//   clearance = 50.0             # m above the terrain, at least
//   max-agl = 400.0              # m above the terrain, at most
//   max-altitude = 1500.0        # m above the datum, at most
//   acceptance-radius = 100.0    # m: where the autopilot takes the next waypoint
//   max-wind = 5.0               # m/s: the strongest wind the mission is flown in
// Keys left out keep the type's preset; an unknown key, a wrong type or a
// value out of range is an error naming the file and the key. The options
// (--max-climb ...) override the vehicle's values.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "rt/rope/path_check.hpp"
#include "rt/rope/vehicle.hpp"

namespace CLI {
class App;
}

namespace visvol::cli {

struct EnvelopeOptions {
  std::string vehicle = "fixed-wing";
  std::optional<double> speed_m_per_s, max_climb_deg, max_descent_deg, min_turn_radius_m, clearance_m, max_agl_m,
      acceptance_radius_m, max_altitude_m, max_wind_m_per_s;
  std::optional<std::string> autopilot;  // px4, ardupilot
};

struct ConstraintOptions {
  std::vector<std::vector<double>> hidden_from, visible_to;  // X Y Z each
  double eye_height_m = 2.0;
};

void add_envelope_options(CLI::App& command, EnvelopeOptions& options);
void add_constraint_options(CLI::App& command, ConstraintOptions& options);

// The preset or file, then the overrides; validated.
Result<rt::VehicleEnvelope> resolve_envelope(const EnvelopeOptions& options);
// The observers named, each checked (finite), with --eye-height (0..10000 m).
Result<std::vector<rt::ConstraintPoint>> constraint_points(const ConstraintOptions& options);

// A vehicle file (see above). Refuses anything but a regular file of at most 64 KiB.
Result<rt::VehicleEnvelope> read_vehicle_file(const std::string& path);

}  // namespace visvol::cli

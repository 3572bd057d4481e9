// The console's session state, shared by its parts: console.cpp (start-up
// and the session's run), console_catalogue.cpp (the packs a switch-terrain
// may take) and console_outputs.cpp (the final path, its check and the
// files written at the end). Private to the console: app/console.hpp is the
// interface.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/console.hpp"
#include "app/fault_injection.hpp"
#include "app/flyable_path.hpp"
#include "app/terrain_catalogue.hpp"
#include "app/thumbnail_thread.hpp"
#include "drivers/can/socketcan_bus.hpp"
#include "drivers/dds/catalogue_publisher.hpp"
#include "drivers/dds/command_intake.hpp"
#include "drivers/dds/live_publisher.hpp"
#include "drivers/dds/participant.hpp"
#include "drivers/haptic/can_device.hpp"
#include "drivers/hapticsim/simulated_device.hpp"
#include "rt/exec/executive.hpp"
#include "rt/exec/memory_budget.hpp"
#include "rt/exec/periodic_loop.hpp"
#include "rt/exec/realtime.hpp"
#include "rt/rope/path_check.hpp"
#include "storage/resident_pack.hpp"

namespace visvol::app {

inline constexpr std::uint64_t kMiB = 1024 * 1024;

// The haptic device's state for the summary and the status lines.
inline const char* device_text(const rt::ExecutiveCounters& c) {
  if (!c.haptics) return "none";
  return rt::to_string(c.device_state);
}

struct Console::Impl {
  ConsoleOptions o;
  std::shared_ptr<const storage::Pack> pack;
  std::string pack_id;
  fields::Bounds2D bounds;  // the pack's planning bounds: the ends and the flyable path stay inside
  std::vector<std::pair<std::string, std::string>> terrains;  // id, path: where switch-terrain may go
  std::unique_ptr<TerrainCatalogue> catalogue;                // --catalogue: more, verified off the loop
  std::uint64_t catalogue_seen = ~std::uint64_t{0};           // its version last acted on
  std::vector<CatalogueEntry> catalogue_entries;              // as last seen then
  bool catalogue_left_out_said = false;                       // more files than it keeps (said once)
  bool catalogue_full = false;                                // more verified than commands may name (said once)
  dds::CommandLimits limits;                                  // the intake's, but for the catalogue's packs
  std::string switch_to;    // the pack id a switch-terrain command asked for, once seen
  std::string switch_path;  // its file, found when the switch was seen
  double session_s = 0;     // how long the session ran
  rt::MemoryBudget budget{0};
  rt::RealtimeReport realtime;
  std::unique_ptr<storage::ResidentPack> field;
  std::unique_ptr<dds::Participant> participant;
  std::unique_ptr<dds::CataloguePublisher> catalogue_pub;  // with a catalogue (after the participant: deleted first)
  std::unique_ptr<msg::TerrainCatalogue> catalogue_msg;    // what it sends (80 KB: not on a stack)
  // Destroyed in reverse: the publisher before the intake it reads counters
  // from, the intake before the queues it fills (their documented lifetimes).
  msg::CommandQueue commands;
  msg::AckQueue acks;
  std::unique_ptr<dds::CommandIntake> intake;
  std::unique_ptr<dds::LivePublisher> publisher;
  std::unique_ptr<hapticsim::SimulatedDevice> sim;
  std::unique_ptr<can::SocketCanBus> socket_bus;
  std::optional<haptic::CanDevice> device;  // on sim's or socket_bus's bus (after them: destroyed first)
  std::unique_ptr<ThumbnailThread> thumbs;
  std::unique_ptr<rt::ConstraintHulls> hulls;  // with DDS or observers given: hidden-from / visible-to
  int observers = 0;                           // hulls reserved for (observers_reserved())
  rt::VehicleEnvelope vehicle;                 // --vehicle and the envelope options
  // The rope's path fitted into the envelope: a thread feeding the publisher
  // and the renderer (after them: destroyed before them), or the fitter alone
  // for the final path when nothing is sent.
  std::unique_ptr<FlyablePath> flyable;
  std::unique_ptr<PathFitter> fitter;
  std::vector<rt::Vec3> final_path;       // the flyable path at the end (write_outputs), thinned
  std::size_t final_fitted_vertices = 0;  // its vertices as fitted, before thinning
  bool final_flyable = false;
  std::unique_ptr<rt::Executive> exec;
  std::unique_ptr<StallingTask> stall;  // --inject-stall: between the loop and the executive
  std::unique_ptr<rt::PeriodicLoop> loop;
  rt::LoopConfig loop_config;
  // health.csv's lines, the last kHealthLines of them: a console run as a
  // service (--seconds 0) would otherwise grow them for ever
  static constexpr std::size_t kHealthLines = 3600;
  std::deque<std::string> health_lines;
  rt::ExecutiveCounters counters_at_start;  // before the loop started (then: snapshot())
  double fc_start = 0;
  std::uint64_t rss_peak = 0;
  bool over_budget_said = false;  // the first time the process's memory went over --budget-mib

  Status start();
  Status open_pack();
  Status reserve_and_open_tiles(const fields::VolumeGeometry& g, const rt::RealtimeConfig& rtc);
  Status start_device();
  Status start_executive();
  Status open_terrains();
  Status start_catalogue();
  void poll_catalogue();
  std::string path_of_pack(const std::string& id) const;
  void publish_catalogue();
  nlohmann::json catalogue_json() const;
  std::string out_dir() const;
  Status start_dds(const fields::VolumeGeometry& g);
  Status start_thumbnails();
  int observers_reserved(const fields::VolumeGeometry& g) const;
  Status start_hulls();
  rt::ExecutiveConfig executive_config() const;
  Status start_fitter();
  const PathFitter& path_fitter() const { return flyable ? flyable->fitter() : *fitter; }
  void fit_final_path();
  Result<rt::PathChecker> final_checker() const;
  rt::PathCheck judge_final_path(const rt::PathChecker& checker);
  nlohmann::json check_path(const Result<rt::PathChecker>& checker, const std::optional<rt::PathCheck>& judged,
                            std::string& line) const;
  Status check_outputs() const;
  Status write_outputs(const rt::LoopRun& run, double wall_s);
  Status make_output_dirs(const std::string& out) const;
  std::string path_csv(const msg::PathSample& fp, const nlohmann::json& check) const;
  nlohmann::json summary_json(const rt::LoopRun& run, double wall_s, const msg::PathSample& fp,
                              const nlohmann::json& check) const;
  void print_summary(const rt::LoopRun& run, double wall_s, const msg::PathSample& fp, const std::string& verdict,
                     const std::string& out) const;
  msg::HealthSample health(const rt::LoopReport& r, const rt::ExecutiveCounters& c, std::uint64_t seq) const;
};

}  // namespace visvol::app

// The console's start-up and the run of its session (the state its parts
// share: console_impl.hpp).
#include "app/console.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <thread>

#include "app/console_impl.hpp"
#include "app/log.hpp"
#include "app/supervisor.hpp"
#include "io/atomic_file.hpp"
#include "storage/pack_identity.hpp"

namespace visvol::app {

static_assert(app::kMaxObserversPerKind == rt::kMaxObserversPerKind &&
                  app::kMaxObservers == rt::ConstraintHulls::kMaxObservers,
              "the console's options take what its hull builder folds");

namespace {

// The simulated operator of the demo, pull mode (A): settles, grabs the rope
// in the middle of the workspace, pulls it north and up, lets go, and does it
// again later.
constexpr const char* kBuiltinPullScript =
    "2.0 move 0 0 0 0.5\n"
    "4.0 pull 0 40 -40 1.5\n"
    "7.0 release\n"
    "7.5 move 0 0 0 0.5\n"
    "12.0 pull 30 -30 0 1.0\n"
    "14.0 release\n"
    "14.5 move 0 0 0 0.5\n";

// Then spool mode (B): presses the mode button at 15.5 s (the handle, at the
// workspace's centre, then holds the lead's free end), drags that end from 16
// to 21 s in strokes of at most 60 mm re-centred with the clutch, to a tenth of
// the way past the far end (the free end trails the hand), and lets go at
// 21.5 s. The drag in device millimetres comes from the scene.
std::string builtin_script(const rt::ExecutiveConfig& ec, double spacing_m) {
  const Eigen::Vector3d by = rt::spool_drag_mm(ec, spacing_m, 0.1);
  char spool[256];
  std::snprintf(spool, sizeof spool, "15.5 mode on\n15.6 mode off\n16.0 drag %.1f %.1f %.1f 5.0 60\n21.5 release\n",
                by.x(), by.y(), by.z());
  return std::string(kBuiltinPullScript) + spool;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

msg::TimingSummary summary_of(const rt::DurationHistogram& h) {
  return {h.min_us(), h.mean_us(), h.percentile_us(0.99), h.max_us(), static_cast<std::uint32_t>(h.count())};
}

}  // namespace

Console::Console(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Console::~Console() {
  if (impl_ && impl_->loop && impl_->loop->running()) impl_->loop->stop();
  if (impl_ && impl_->field) impl_->field->stop_pager();
}

Result<std::unique_ptr<Console>> Console::start(const ConsoleOptions& options) {
  VISVOL_RETURN_IF_ERROR(validate(options));
  auto impl = std::make_unique<Impl>();
  impl->o = options;
  VISVOL_RETURN_IF_ERROR(impl->start());
  return std::unique_ptr<Console>(new Console(std::move(impl)));
}

std::optional<ConsoleOptions> Console::next_session() const {
  const Impl& m = *impl_;
  if (m.switch_to.empty()) return std::nullopt;
  ConsoleOptions next = m.o;
  next.pack = m.switch_path;  // found when the switch was seen
  if (next.pack.empty() || next.pack == m.o.pack) return std::nullopt;
  // the old pack becomes one to switch back to, unless the catalogue has it
  // (it verifies it again) or it is one already
  const bool listed =
      std::any_of(m.terrains.begin(), m.terrains.end(), [&](const auto& t) { return t.first == m.pack_id; }) ||
      (m.catalogue && m.catalogue->has(m.pack_id));
  if (!listed) next.terrains.push_back(m.o.pack);
  // the new pack is this session's, not another one to switch to
  next.terrains.erase(
      std::remove_if(next.terrains.begin(), next.terrains.end(),
                     [&](const std::string& t) { return storage::pack_id_from_path(t) == m.switch_to; }),
      next.terrains.end());
  if (m.o.seconds > 0) {
    const double left = m.o.seconds - m.session_s;
    if (left < 1.0) return std::nullopt;  // the time is up
    next.seconds = left;
  }
  // the endpoints and observers were in the old pack's area: the new one's
  // default endpoints, no observers (commands may set them there)
  next.from.clear();
  next.to.clear();
  next.hidden_from.clear();
  next.visible_to.clear();
  next.session = m.o.session + 1;
  next.switched_from = m.pack_id;
  next.switched_from_path = m.o.pack;
  return next;
}

ConsoleOptions session_after_failed_switch(const ConsoleOptions& failed, const std::string& error) {
  ConsoleOptions back = failed;
  const std::string failed_id = storage::pack_id_from_path(failed.pack);
  back.terrains.clear();
  for (const std::string& path : failed.terrains) {
    const std::string id = storage::pack_id_from_path(path);
    if (id == failed.switched_from) back.pack = path;  // next_session() put the pack it left here
    if (id != failed.switched_from && id != failed_id) back.terrains.push_back(path);
  }
  // a catalogue's pack is in no list: back to its file all the same (the
  // console went back to the broken pack, failed again and ended)
  if (!failed.switched_from_path.empty()) back.pack = failed.switched_from_path;
  back.switched_from.clear();
  back.switched_from_path.clear();
  back.switch_failed = failed_id + ": " + error;
  return back;
}

Status Console::Impl::start_dds(const fields::VolumeGeometry& g) {
  dds::ParticipantConfig pc;
  pc.domain_id = o.domain;
  pc.topic_namespace = o.dds_namespace;
  if (o.dds_config.empty()) {
    pc.cyclone_xml = std::string(dds::loopback_config());
  } else {
    Result<std::string> xml = dds::read_cyclone_config(o.dds_config);
    if (!xml.ok()) return xml.status();
    pc.cyclone_xml = std::move(*xml);
  }
  auto p = dds::Participant::create(pc);
  if (!p.ok()) return p.status();
  participant = std::move(*p);
  dds::IntakeConfig ic;
  ic.limits.min = {g.origin_x, g.origin_y - (g.ny - 1) * g.spacing_m, g.z0_m};
  ic.limits.max = {g.origin_x + (g.nx - 1) * g.spacing_m, g.origin_y, g.top_m() + 10000.0};
  // endpoints from commands inside the planning bounds, as on the command line
  ic.limits.plan_min = {bounds.xmin_m, bounds.ymin_m, 0.0};
  ic.limits.plan_max = {bounds.xmax_m, bounds.ymax_m, 0.0};
  ic.limits.max_segments = static_cast<std::uint32_t>(o.max_segments);
  ic.limits.max_observers = static_cast<std::uint32_t>(observers);
  VISVOL_RETURN_IF_ERROR(dds::add_known_pack(ic.limits, pack_id));
  for (const auto& t : terrains) VISVOL_RETURN_IF_ERROR(dds::add_known_pack(ic.limits, t.first));
  limits = ic.limits;          // poll_catalogue() adds the catalogue's verified packs to these
  if (!o.catalogue.empty()) {  // made here: counted in the budget with the rest of DDS
    auto cp = dds::CataloguePublisher::create(*participant);
    if (!cp.ok()) return cp.status();
    catalogue_pub = std::move(*cp);
    catalogue_msg = std::make_unique<msg::TerrainCatalogue>();
  }
  auto in = dds::CommandIntake::start(*participant, ic, commands, &acks);
  if (!in.ok()) return in.status();
  intake = std::move(*in);
  auto pub = dds::LivePublisher::start(*participant, dds::PublisherConfig(), intake.get());
  if (!pub.ok()) return pub.status();
  publisher = std::move(*pub);
  msg::TerrainInfo& t = publisher->terrain().back();
  t = msg::TerrainInfo{};
  t.stamp_ns = msg::now_stamp_ns();
  msg::copy_text(t.pack_id, pack_id);
  msg::copy_text(t.crs, storage::epsg_from_wkt(pack->metadata().crs_wkt));
  if (!msg::copy_text(t.crs_wkt, pack->metadata().crs_wkt)) t.crs_wkt[0] = '\0';
  t.min = ic.limits.min;
  t.max = {ic.limits.max.x_m, ic.limits.max.y_m, g.top_m()};
  t.post_spacing_m = g.spacing_m;
  t.planning_min = ic.limits.plan_min;
  t.planning_max = ic.limits.plan_max;
  publisher->terrain().publish();
  return {};
}

namespace {

// A --terrain pack as a switch would find it: its structure and contents
// (Pack::open), every tile's checksum, and the --level the session runs on.
// Read with pread, never mapped: a file changed meanwhile is an error, not SIGBUS.
Status check_terrain(const std::string& path, int level) {
  auto p = storage::Pack::open(path, storage::PackAccess::inspect);
  if (!p.ok()) return p.status();
  VISVOL_RETURN_IF_ERROR((*p)->verify());
  VISVOL_RETURN_IF_ERROR(storage::check_planning_bounds(**p));
  if (level >= (*p)->level_count()) {
    return invalid_argument(path + ": " + std::to_string((*p)->level_count()) + " levels of detail, --level " +
                            std::to_string(level) + " is not among them");
  }
  return {};
}

// --from and --to inside the pack's planning bounds, as `visvol plan` asks.
Status check_ends_inside(const ConsoleOptions& o, const fields::Bounds2D& b) {
  for (const auto& [name, p] : {std::pair{"--from", &o.from}, std::pair{"--to", &o.to}}) {
    // to a centimetre, as plan and check judge it
    const fields::Bounds2D near{b.xmin_m - kBoundsTolM, b.ymin_m - kBoundsTolM, b.xmax_m + kBoundsTolM,
                                b.ymax_m + kBoundsTolM};
    if (p->size() == 3 && !near.contains((*p)[0], (*p)[1])) {
      char at[96];
      std::snprintf(at, sizeof at, "(%.1f, %.1f)", (*p)[0], (*p)[1]);
      return invalid_argument(std::string(name) + " " + at + " is outside " + o.pack + "'s planning bounds (" +
                              storage::describe(b) + "), where F_p undercounts observers beyond the DEM");
    }
  }
  return {};
}

}  // namespace

// The other packs, ids unique. At start-up each is checked whole, tiles
// included, so that a switch never lands on a bad file: a bad one refuses the
// start. After a switch (the packs checked then, or run on), one that no
// longer opens is dropped from those a switch may name, with a warning.
Status Console::Impl::open_terrains() {
  for (const std::string& path : o.terrains) {
    const std::string id = storage::pack_id_from_path(path);
    if (id == pack_id) continue;  // the pack of this session
    for (const auto& t : terrains) {
      if (t.first == id) return invalid_argument("--terrain " + path + ": pack id '" + id + "' is also " + t.second);
    }
    if (terrains.size() + 1 >= dds::kMaxKnownPacks) {
      return invalid_argument("--terrain: at most " + std::to_string(dds::kMaxKnownPacks - 1) + " other packs");
    }
    const Status st = o.session == 1 ? check_terrain(path, o.level)
                                     : storage::Pack::open(path, storage::PackAccess::inspect).status();
    if (!st.ok() && o.session == 1) return Status(st.code(), "--terrain " + path + ": " + st.message());
    if (!st.ok()) {
      log_printf(LogLevel::warning, "visvol-console: warning: switch-terrain %s is no longer possible: %s\n",
                 id.c_str(), st.message().c_str());
      continue;
    }
    terrains.emplace_back(id, path);
  }
  return {};
}

// The outputs' folder and names, checked before the session: they are
// written at its end, and a bad --out found then lost the whole record.
Status Console::Impl::check_outputs() const {
  if (Status s = make_output_dirs(o.out); !s.ok()) return invalid_argument("--out: " + s.message());
  for (const char* name : {"path.csv", "health.csv", "summary.json", "thumbnail.png"}) {
    if (o.thumbnail_view == "none" && std::strcmp(name, "thumbnail.png") == 0) continue;  // not written
    if (Status s = check_output_path(o.out + "/" + name); !s.ok()) return invalid_argument("--out: " + s.message());
  }
  return {};
}

Status Console::Impl::start() {
  VISVOL_RETURN_IF_ERROR(open_pack());
  VISVOL_RETURN_IF_ERROR(check_outputs());  // (after the pack: a bad pack leaves no folder behind)
  const fields::VolumeGeometry g = pack->geometry(o.level);
  rt::RealtimeConfig rtc;
  rtc.priority = o.priority;
  rtc.cpu = o.cpu;
  rtc.lock_memory = o.lock_memory;
  rt::lock_process_memory(rtc, realtime);
  observers = observers_reserved(g);
  if (o.dds) VISVOL_RETURN_IF_ERROR(start_dds(pack->geometry(0)));
  VISVOL_RETURN_IF_ERROR(reserve_and_open_tiles(g, rtc));
  // after the memory lock and the budget: its reads are neither locked nor counted
  VISVOL_RETURN_IF_ERROR(start_catalogue());
  VISVOL_RETURN_IF_ERROR(start_device());
  VISVOL_RETURN_IF_ERROR(start_executive());

  // the loop and the pager
  loop_config.period_ns = static_cast<std::int64_t>(std::llround(o.period_us * 1000));
  loop_config.overrun_limit = o.overrun_limit;
  loop_config.report_ticks = static_cast<std::uint32_t>(std::max(1.0, std::round(100000.0 / o.period_us)));
  loop_config.realtime = rtc;
  field->set_reader_active(true);
  field->start_pager();
  if (!o.inject_stall.empty()) {
    stall = std::make_unique<StallingTask>(*exec, o.inject_stall[0], o.inject_stall[1]);
    log_printf(LogLevel::warning,
               "visvol-console: fault injection: the loop stalls %.3g s after it starts, for %.3g s\n",
               o.inject_stall[0], o.inject_stall[1]);
  }
  loop = std::make_unique<rt::PeriodicLoop>(stall ? static_cast<rt::PeriodicTask&>(*stall) : *exec);
  return loop->start(loop_config);
}

// The pack (not mapped: whatever reads its tiles reads checked copies, so a
// pack file cut short or rewritten under the session cannot fault it), the
// other terrains, the level and the ends checked against them.
Status Console::Impl::open_pack() {
  auto p = storage::Pack::open(o.pack, storage::PackAccess::inspect);
  if (!p.ok()) return p.status();
  pack = *p;
  pack_id = storage::pack_id_from_path(o.pack);
  VISVOL_RETURN_IF_ERROR(open_terrains());
  if (o.level < 0 || o.level >= pack->level_count()) {
    return invalid_argument("--level: " + std::to_string(o.level) + " is not in " + o.pack + " (0.." +
                            std::to_string(pack->level_count() - 1) + ")");
  }
  VISVOL_RETURN_IF_ERROR(storage::check_planning_bounds(*pack));
  bounds = storage::planning_bounds(*pack);
  VISVOL_RETURN_IF_ERROR(check_ends_inside(o, bounds));
  return {};
}

// The budget: what runs already, what the loop reserves; the tiles get the rest.
Status Console::Impl::reserve_and_open_tiles(const fields::VolumeGeometry& g, const rt::RealtimeConfig& rtc) {
  budget = rt::MemoryBudget(static_cast<std::uint64_t>(o.budget_mib * kMiB));
  budget.reserve(o.dds ? "process (code, libraries, DDS)" : "process (code, libraries)", rt::resident_bytes());
  if (o.thumbnail_view != "none") {
    const std::uint64_t before = rt::resident_bytes();
    VISVOL_RETURN_IF_ERROR(start_thumbnails());
    const std::uint64_t after = rt::resident_bytes();
    budget.reserve("renderer (GL context, mesh, F_p texture, PNG)", after > before ? after - before : 0);
  }
  VISVOL_RETURN_IF_ERROR(start_fitter());
  budget.reserve("flyable path (finest terrain, two folded hulls of it, fit)",
                 PathFitter::bytes(*pack, observers) + 8 * sizeof(msg::PathSample) + 1024 * 1024 +
                     (observers > 0 ? rt::ConstraintHulls::build_bytes(pack->geometry(0)) : 0));
  const std::uint64_t segments = static_cast<std::uint64_t>(o.max_segments) + 1;
  budget.reserve("ropes (both models, max segments)", 2 * segments * 1024);
  budget.reserve("executive (samples, scratch)", sizeof(msg::PathSample) * 2 + segments * 64 + 64 * 1024);
  budget.reserve("loop (histograms, reports)", sizeof(rt::LoopReport) * 3 + sizeof(rt::LoopRun) * 2);
  budget.reserve("loop stack (prefaulted)", rtc.stack_prefault_bytes);
  if (o.device == "sim") budget.reserve("simulated device and bus", 2 * 4096 * sizeof(can::CanFrame) + 64 * 1024);
  if (observers > 0) {
    budget.reserve("constraint hulls (3 sets of 2 folded hulls, one build)",
                   rt::ConstraintHulls::reserved_bytes(g, observers) + rt::ConstraintHulls::build_bytes(g));
  }
  VISVOL_RETURN_IF_ERROR(budget.check(1, "tiles"));
  storage::ResidentConfig rc;
  rc.budget_bytes = budget.remaining_bytes();
  rc.margin_m = o.tile_margin_m;
  auto f = storage::ResidentPack::create(pack, rc);
  if (!f.ok()) return Status(f.status().code(), f.status().message() + "\n" + budget.table());
  field = std::move(*f);
  budget.reserve("tiles (heights, coarsest level, around the rope)", rc.budget_bytes);
  return {};
}

// The haptic device: the simulated one on its in-process bus, or SocketCAN;
// the CAN driver on either.
Status Console::Impl::start_device() {
  can::CanBus* bus = nullptr;
  if (o.device == "sim") {
    hapticsim::SimConfig sc;
    sc.node_id = static_cast<std::uint8_t>(o.node);
    hapticsim::Script script;
    if (o.script == "builtin") {
      const std::string text = builtin_script(executive_config(), field->level(o.level).geometry().spacing_m);
      auto s = hapticsim::parse_script(text, "built-in script", sc.workspace_half_mm);
      if (!s.ok()) return s.status();
      script = std::move(*s);
    } else if (o.script != "none") {
      auto s = hapticsim::load_script(o.script, sc.workspace_half_mm);
      if (!s.ok()) return s.status();
      script = std::move(*s);
    }
    auto s = hapticsim::SimulatedDevice::create(sc, std::move(script), rt::monotonic_ns());
    if (!s.ok()) return s.status();
    sim = std::move(*s);
    bus = &sim->console_bus();
  } else if (o.device == "socketcan") {
    can::SocketCanConfig cc;
    cc.interface = o.can_interface;
    cc.filters = haptic::DeviceDriver::receive_filters(static_cast<std::uint8_t>(o.node));
    auto b = can::SocketCanBus::open(cc);
    if (!b.ok()) return b.status();
    socket_bus = std::move(*b);
    bus = socket_bus.get();
  }
  if (bus != nullptr) {
    haptic::DriverConfig dc;
    dc.node_id = static_cast<std::uint8_t>(o.node);
    auto d = haptic::CanDevice::create(dc, *bus);
    if (!d.ok()) return d.status();  // names the configuration's bad field
    device.emplace(std::move(*d));
  }
  return {};
}

Status Console::Impl::start_executive() {
  const rt::ExecutiveConfig ec = executive_config();
  rt::ExecutiveOutputs out;
  if (publisher) {
    out.device = &publisher->device_status();
    out.acks = &acks;
  }
  if (flyable) {
    out.limited_path = &flyable->rope_paths();
  }
  auto e = rt::Executive::create(ec, *field, device ? &*device : nullptr, sim.get(), &commands, out);
  if (!e.ok()) return e.status();
  exec = std::move(*e);
  // Copied here, before the loop thread starts: from then on only that
  // thread may read counters(); others take snapshot()s.
  counters_at_start = exec->counters();
  fc_start = counters_at_start.fc;
  VISVOL_RETURN_IF_ERROR(start_hulls());
  return {};
}

// Observers a set may name (each kind is folded into one hull, so the
// number costs build time, not memory): --max-observers; else, with DDS, all
// a command may send where three sets of two hulls take at most a quarter of
// the budget, and otherwise (or without DDS) those given.
int Console::Impl::observers_reserved(const fields::VolumeGeometry& g) const {
  const int given = static_cast<int>(o.hidden_from.size() + o.visible_to.size());
  if (o.max_observers >= 0) return o.max_observers;
  if (!o.dds) return given;
  const auto quarter = static_cast<std::uint64_t>(o.budget_mib * kMiB / 4);
  return std::max(given, rt::ConstraintHulls::observers_within(g, quarter));
}

// The hull builder beside the loop, with the observers given in force first.
Status Console::Impl::start_hulls() {
  if (!o.dds && observers == 0) return {};
  auto h = rt::ConstraintHulls::create(field->level(o.level), observers);
  if (!h.ok()) return h.status();
  hulls = std::move(*h);
  VISVOL_RETURN_IF_ERROR(exec->set_constraint_hulls(hulls.get()));
  hulls->start();
  return {};
}

// The planning problem of the options; endpoints by default a tenth inside
// the west and east edges of the planning bounds, 150 m up, or half way
// between the clearance and a lower ceiling.
rt::ExecutiveConfig Console::Impl::executive_config() const {
  rt::ExecutiveConfig ec;
  ec.gains.clearance_m = vehicle.clearance_m;
  ec.gains.max_agl_m = vehicle.max_agl_m;  // infinite: none
  ec.gains.max_altitude_m = vehicle.max_altitude_m;
  const fields::FieldSampler<storage::ResidentLevel> ground(field->level(o.level));
  auto end_at = [&](double x, double y) {
    const double z0 = ground.height(x, y);
    const double top = std::min({z0 + ec.gains.max_agl_m, ec.gains.max_altitude_m, ground.level().geometry().top_m()});
    // no room under the ceiling: left above it, for the executive to refuse naming it
    const bool lower = z0 + 150 > top && top > z0 + vehicle.clearance_m;
    return rt::Vec3(x, y, lower ? 0.5 * (z0 + vehicle.clearance_m + top) : z0 + 150);
  };
  const double ymid = 0.5 * (bounds.ymin_m + bounds.ymax_m);
  const double xw = bounds.xmin_m + 0.1 * (bounds.xmax_m - bounds.xmin_m);
  const double xe = bounds.xmin_m + 0.9 * (bounds.xmax_m - bounds.xmin_m);
  ec.start_m = o.from.empty() ? end_at(xw, ymid) : rt::Vec3(o.from[0], o.from[1], o.from[2]);
  ec.end_m = o.to.empty() ? end_at(xe, ymid) : rt::Vec3(o.to[0], o.to[1], o.to[2]);
  ec.objective = o.objective == "show" ? rt::Objective::show : rt::Objective::hide;
  ec.model = o.model == "spring" ? rt::RopeModel::spring : rt::RopeModel::articulated;
  ec.segments = o.segments;
  ec.max_segments = o.max_segments;
  ec.gains.k1_visibility = o.k1;
  ec.gains.k2_terrain = o.k2;
  ec.k3_user = o.k3;
  ec.level = o.level;
  ec.period_s = o.period_us * 1e-6;
  ec.eye_height_m = o.eye_height_m;
  ec.planning_bounds = bounds;
  for (const std::vector<double>& p : o.hidden_from) ec.observers.add_hidden_from(rt::Vec3(p[0], p[1], p[2]));
  for (const std::vector<double>& p : o.visible_to) ec.observers.add_visible_to(rt::Vec3(p[0], p[1], p[2]));
  msg::copy_text(ec.pack_id, pack_id);
  return ec;
}

// The fitter, and its thread when paths are sent (DDS or thumbnails).
Status Console::Impl::start_fitter() {
  Result<rt::VehicleEnvelope> v = resolve_vehicle(o);
  if (!v.ok()) return v.status();
  vehicle = *v;
  auto f = PathFitter::create(pack, vehicle, rt::ExecutiveConfig().fc_samples, observers);
  if (!f.ok()) return f.status();
  if (!publisher && !thumbs) {
    fitter = std::move(*f);
    return {};
  }
  auto t =
      FlyablePath::start(std::move(*f), publisher ? &publisher->path() : nullptr, thumbs ? &thumbs->paths() : nullptr);
  if (!t.ok()) return t.status();
  flyable = std::move(*t);
  return {};
}

Status Console::Impl::start_thumbnails() {
  ThumbnailConfig tc;
  auto view = render::parse_view(o.thumbnail_view);
  if (!view.ok()) return view.status();
  tc.view = *view;
  auto size = parse_thumbnail_size(o.thumbnail_size);
  if (!size.ok()) return size.status();
  tc.width_px = size->first;
  tc.height_px = size->second;
  tc.max_hz = o.thumbnail_max_hz;
  auto t = ThumbnailThread::start(pack, tc, publisher ? &publisher->thumbnail() : nullptr);
  if (!t.ok()) return Status(t.status().code(), "thumbnails: " + t.status().message());
  thumbs = std::move(*t);
  return {};
}

msg::HealthSample Console::Impl::health(const rt::LoopReport& r, const rt::ExecutiveCounters& c,
                                        std::uint64_t seq) const {
  msg::HealthSample h{};
  h.sequence = seq;
  h.stamp_ns = msg::now_stamp_ns();
  h.period_us = o.period_us;
  h.wakeup_latency = summary_of(r.wake_latency);
  h.compute_time = summary_of(r.compute);
  h.overruns = r.totals.overruns;
  h.misses = r.totals.misses;
  h.safe_state = c.servo_reason != servo::SafeReason::none;
  msg::copy_text(h.safe_state_reason, h.safe_state ? servo::safe_reason_name(c.servo_reason) : "");
  return h;
}

Status Console::run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  const auto t0 = std::chrono::steady_clock::now();
  for (const std::string& w : m.realtime.warnings)
    log_printf(LogLevel::warning, "visvol-console: warning: %s\n", w.c_str());
  if (!m.o.quiet)
    log_printf(LogLevel::info, "visvol-console: %s, rope of %d segments, %s, device %s, DDS %s; memory budget:\n%s",
               m.pack_id.c_str(), m.o.segments, m.o.objective.c_str(), m.o.device.c_str(),
               m.o.dds ? ("domain " + std::to_string(m.o.domain)).c_str() : "off", m.budget.table().c_str());
  rt::LoopReport last{};
  rt::ExecutiveCounters counters = m.counters_at_start;
  std::uint64_t health_seq = 0;
  double next_line_s = 1.0;
  Supervisor supervisor;  // systemd, when the console runs as its unit
  supervisor.ready(m.pack_id + ": rope of " + std::to_string(m.o.segments) + " segments, " + m.o.objective);
  while (!stop.load() && (m.o.seconds <= 0 || seconds_since(t0) < m.o.seconds)) {
    std::this_thread::sleep_for(std::chrono::duration<double>(supervisor.monitor_period_s()));
    if (const rt::LoopReport* r = m.loop->reports().take()) last = *r;
    if (const rt::ExecutiveCounters* c = m.exec->snapshot().take()) counters = *c;
    supervisor.monitor(seconds_since(t0), m.loop->ticks(), m.publisher != nullptr,
                       m.publisher ? m.publisher->passes() : 0);
    m.poll_catalogue();
    char next[msg::kPackIdCapacity];
    if (m.exec->terrain_switch(next)) {
      m.switch_path = m.path_of_pack(next);
      if (m.switch_path.empty()) {
        log_printf(LogLevel::warning,
                   "visvol-console: switch-terrain %s: no longer a verified pack of this console; staying on %s\n",
                   printable(next).c_str(), m.pack_id.c_str());
        m.exec->cancel_terrain_switch();
        continue;
      }
      m.switch_to = next;
      log_printf(LogLevel::info, "visvol-console: switch-terrain: ending this session to start one on %s\n", next);
      // the next session's start (pack, tiles, DDS) sends no pings: room for it
      supervisor.extend_watchdog(120.0, std::string("switching terrain to ") + next);
      break;
    }
    if (m.publisher && last.sequence > 0) m.publisher->health().write(m.health(last, counters, ++health_seq));
    const double t = seconds_since(t0);
    if (t >= next_line_s) {
      next_line_s += 1.0;
      const std::uint64_t rss = rt::resident_bytes();
      m.rss_peak = std::max(m.rss_peak, rss);
      if (!m.over_budget_said && static_cast<double>(rss) > m.o.budget_mib * kMiB) {
        m.over_budget_said = true;
        log_printf(LogLevel::warning, "visvol-console: memory: %.0f MiB resident, over the %.0f MiB budget\n",
                   static_cast<double>(rss) / kMiB, m.o.budget_mib);
      }
      const storage::ResidentStats ts = m.field->stats();
      char line[512];
      std::snprintf(line, sizeof line, "%.1f,%.1f,%.1f,%.1f,%.1f,%llu,%llu,%.6f,%d,%s,%.1f,%.1f,%llu\n", t,
                    last.wake_latency.percentile_us(0.99), last.wake_latency.max_us(), last.compute.percentile_us(0.99),
                    last.compute.max_us(), static_cast<unsigned long long>(last.totals.overruns),
                    static_cast<unsigned long long>(last.totals.misses), counters.fc, counters.converged ? 1 : 0,
                    device_text(counters), static_cast<double>(ts.resident_bytes) / kMiB,
                    static_cast<double>(rss) / kMiB, static_cast<unsigned long long>(m.field->fallbacks()));
      if (m.health_lines.size() == Impl::kHealthLines) m.health_lines.pop_front();
      m.health_lines.emplace_back(line);
      if (!m.o.quiet)
        log_printf(LogLevel::info,
                   "%6.1f s  F_c %.4f%s  wake p99 %.0f us  compute p99 %.0f us  overruns %llu  device %s  "
                   "grasps %llu  memory %.0f/%.0f MiB\n",
                   t, counters.fc, counters.converged ? " (at rest)" : "", last.wake_latency.percentile_us(0.99),
                   last.compute.percentile_us(0.99), static_cast<unsigned long long>(last.totals.overruns),
                   device_text(counters), static_cast<unsigned long long>(counters.grasps),
                   static_cast<double>(rss) / kMiB, m.o.budget_mib);
      char status[160];
      std::snprintf(status, sizeof status, "%s: F_c %.4f%s, device %s, overruns %llu", m.pack_id.c_str(), counters.fc,
                    counters.converged ? " (at rest)" : "", device_text(counters),
                    static_cast<unsigned long long>(last.totals.overruns));
      supervisor.status(status);
    }
  }
  const double wall_s = seconds_since(t0);
  m.session_s = wall_s;
  const rt::LoopRun run = m.loop->stop();  // its last act: zero force, disabled
  // then STOPPING=1, when the console ends for good (not on a terrain switch)
  if (m.switch_to.empty()) supervisor.stopping(m.pack_id + ": stopping, writing the outputs");
  if (m.flyable) m.flyable->stop();  // before the publisher and the renderer it feeds
  m.field->set_reader_active(false);
  m.field->stop_pager();
  if (m.hulls) m.hulls->stop();
  if (m.thumbs) m.thumbs->stop();  // after one last thumbnail, which the publisher still sends
  Status delivered;
  if (m.publisher) delivered = m.publisher->stop();
  if (m.intake) m.intake->stop();
  VISVOL_RETURN_IF_ERROR(m.write_outputs(run, wall_s));
  if (!delivered.ok()) log_printf(LogLevel::warning, "visvol-console: warning: %s\n", delivered.message().c_str());
  return {};
}

}  // namespace visvol::app

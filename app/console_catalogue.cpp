// The packs a switch-terrain command may take: --terrain packs and the
// catalogue folder's verified ones, published and handed to the command
// intake as they change.
#include <cstdio>
#include <cstring>

#include "app/console_impl.hpp"
#include "app/log.hpp"

namespace visvol::app {

Status Console::Impl::start_catalogue() {
  if (o.catalogue.empty()) return {};
  auto c = TerrainCatalogue::start(o.catalogue, o.level, static_cast<std::uint64_t>(o.budget_mib * kMiB));
  if (!c.ok()) return c.status();
  catalogue = std::move(*c);
  log_printf(LogLevel::info, "visvol-console: catalogue %s: %zu packs (ID.vvp), verifying them\n",
             printable(o.catalogue).c_str(), catalogue->entries().size());
  return {};
}

// From the monitor: the catalogue's changes said, and its verified packs
// made names a switch-terrain may use.
void Console::Impl::poll_catalogue() {
  if (!catalogue || catalogue->version() == catalogue_seen) return;
  catalogue_seen = catalogue->version();
  std::vector<CatalogueEntry> now = catalogue->entries();
  // both lists sorted by id: one pass says what was added, changed or removed
  auto old = catalogue_entries.cbegin();
  for (const CatalogueEntry& e : now) {
    for (; old != catalogue_entries.cend() && old->id < e.id; ++old) {
      log_printf(LogLevel::info, "visvol-console: catalogue: %s removed\n", printable(old->id).c_str());
    }
    const bool known = old != catalogue_entries.cend() && old->id == e.id;
    const bool changed = !known || old->state != e.state || old->reason != e.reason;
    if (known) ++old;
    if (!changed || e.state == CatalogueState::verifying) continue;
    if (e.state == CatalogueState::verified) {
      log_printf(LogLevel::info, "visvol-console: catalogue: %s verified (%s, %d levels of detail)\n",
                 printable(e.id).c_str(), e.crs.empty() ? "no CRS" : printable(e.crs).c_str(), e.levels);
    } else {
      log_printf(LogLevel::warning, "visvol-console: catalogue: %s refused: %s\n", printable(e.id).c_str(),
                 printable(e.reason).c_str());
    }
  }
  for (; old != catalogue_entries.cend(); ++old) {
    log_printf(LogLevel::info, "visvol-console: catalogue: %s removed\n", printable(old->id).c_str());
  }
  if (catalogue->left_out() > 0 && !catalogue_left_out_said) {
    log_printf(LogLevel::warning, "visvol-console: catalogue: more than %zu packs in %s: the others are left out\n",
               TerrainCatalogue::kMaxPacks, printable(catalogue->folder()).c_str());
    catalogue_left_out_said = true;
  }
  catalogue_entries = std::move(now);
  publish_catalogue();
  if (!intake) return;
  dds::CommandLimits l = limits;
  for (const CatalogueEntry& e : catalogue_entries) {
    if (e.state != CatalogueState::verified) continue;
    bool known = false;
    for (std::uint32_t i = 0; i < l.pack_count; ++i) known = known || msg::text_of(l.packs[i]) == e.id;
    if (known) continue;
    if (l.pack_count >= dds::kMaxKnownPacks) {
      if (!catalogue_full) {
        log_printf(LogLevel::warning,
                   "visvol-console: catalogue: more than %zu packs: switch-terrain takes the first\n",
                   dds::kMaxKnownPacks);
      }
      catalogue_full = true;
      break;
    }
    (void)dds::add_known_pack(l, e.id);  // its id was checked when it was verified
  }
  if (Status s = intake->set_limits(l); !s.ok()) {
    log_printf(LogLevel::warning, "visvol-console: catalogue: %s\n", s.message().c_str());
  }
}

// The file of pack `id`: a --terrain pack, else a verified catalogue pack
// (still the file that was verified); empty when neither.
std::string Console::Impl::path_of_pack(const std::string& id) const {
  for (const auto& t : terrains) {
    if (t.first == id) return t.second;
  }
  return catalogue ? catalogue->verified_path(id) : std::string();
}

// The catalogue as last seen, on rt/visvol/terrain_catalogue.
void Console::Impl::publish_catalogue() {
  if (!catalogue_pub) return;
  msg::TerrainCatalogue& m = *catalogue_msg;
  m.stamp_ns = msg::now_stamp_ns();
  m.count = 0;
  for (const CatalogueEntry& e : catalogue_entries) {
    if (m.count == msg::kMaxCatalogueEntries) break;
    msg::CatalogueEntry& w = m.entries[m.count++];
    w = msg::CatalogueEntry{};
    // printable ASCII: valid UTF-8 for every reader, cut anywhere
    msg::copy_text(w.pack_id, printable(e.id));
    msg::copy_text(w.name, printable(e.name));
    msg::copy_text(w.crs, printable(e.crs));
    msg::copy_text(w.reason, printable(e.reason));
    if (!msg::copy_text(w.build, printable(e.build_json))) w.build[0] = '\0';  // JSON cut short is no JSON
    w.min = {e.bounds.xmin_m, e.bounds.ymin_m, 0.0};
    w.max = {e.bounds.xmax_m, e.bounds.ymax_m, 0.0};
    w.planning_min = {e.planning.xmin_m, e.planning.ymin_m, 0.0};
    w.planning_max = {e.planning.xmax_m, e.planning.ymax_m, 0.0};
    w.post_spacing_m = e.post_spacing_m;
    w.levels = static_cast<std::uint32_t>(e.levels);
    w.state = e.state;
  }
  if (Status s = catalogue_pub->publish(m); !s.ok()) {
    log_printf(LogLevel::warning, "visvol-console: catalogue: %s\n", s.message().c_str());
  }
}

nlohmann::json Console::Impl::catalogue_json() const {
  if (!catalogue) return nullptr;
  nlohmann::json entries = nlohmann::json::array();
  for (const CatalogueEntry& e : catalogue->entries()) {
    nlohmann::json j = {{"id", printable(e.id)}, {"state", msg::to_string(e.state)}, {"path", printable(e.path)}};
    if (e.state == CatalogueState::refused) j["reason"] = e.reason;
    if (e.levels > 0) {
      j["name"] = e.name;
      j["crs"] = e.crs;
      j["levels"] = e.levels;
      j["post_spacing_m"] = e.post_spacing_m;
    }
    entries.push_back(std::move(j));
  }
  return {{"folder", catalogue->folder()}, {"entries", std::move(entries)}};
}

}  // namespace visvol::app

// libFuzzer target: the files `visvol plan` and `visvol check` read from a
// user. The first byte picks one: a path file (QGroundControl .plan, GeoJSON,
// the plan CSV or 'x y z' text: read_path_file tells them apart by content)
// or a vehicle file (TOML, --vehicle FILE). A path file read is flown as
// check flies it (its loiters as circles). Any bytes must give a result that
// holds what the planner relies on, or an error naming the file: never a
// crash, a hang or an exception.
#include <sys/mman.h>
#include <unistd.h>

#include <ogr_spatialref.h>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "app/mission_options.hpp"
#include "flown_path.hpp"
#include "path_io.hpp"

namespace {

// The pack CRS of the bundled terrain (NAD27 / UTM 10N): GeoJSON and .plan
// positions go through the WGS84 transformation with it.
const std::string& pack_wkt() {
  static const std::string wkt = [] {
    OGRSpatialReference srs;
    std::string out;
    if (srs.importFromEPSG(26710) != OGRERR_NONE) return out;
    char* text = nullptr;
    if (srs.exportToWkt(&text) == OGRERR_NONE && text != nullptr) out = text;
    CPLFree(text);
    return out;
  }();
  return wkt;
}

// A failed expectation is a finding: abort, so that libFuzzer keeps the input.
void expect(bool holds) {
  if (!holds) std::abort();
}

void check_path(const std::string& path) {
  visvol::Result<visvol::cli::PathFile> f = visvol::cli::read_path_file(path, pack_wkt());
  if (!f.ok()) {
    expect(!f.status().message().empty());
    return;
  }
  expect(f->points.size() >= 2);
  for (const visvol::rt::Vec3& p : f->points) expect(p.allFinite());
  expect(f->fp.empty() || f->fp.size() == f->points.size());
  // flown by either preset, as check does: finite points, one turn radius each
  for (const char* preset : {"fixed-wing", "multirotor"}) {
    visvol::Result<visvol::cli::FlownPath> flown = visvol::cli::fly_path(*f, *visvol::rt::vehicle_preset(preset));
    if (!flown.ok()) {
      expect(!flown.status().message().empty());
      continue;
    }
    expect(flown->points.size() == flown->turn_radius_m.size());
    for (const visvol::rt::Vec3& p : flown->points) expect(p.allFinite());
  }
}

void check_vehicle(const std::string& path) {
  visvol::Result<visvol::rt::VehicleEnvelope> v = visvol::cli::read_vehicle_file(path);
  if (!v.ok()) {
    expect(!v.status().message().empty());
    return;
  }
  expect(visvol::rt::validate(*v).ok());  // what the planner and the fit rely on
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool vehicle = data[0] % 4 == 0;
  const int fd = memfd_create("plan_input", MFD_CLOEXEC);
  if (fd < 0) return 0;
  const std::size_t n = size - 1;
  if (write(fd, data + 1, n) != static_cast<ssize_t>(n)) {
    close(fd);
    return 0;
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  if (vehicle) {
    check_vehicle(path);
  } else {
    check_path(path);
  }
  close(fd);
  return 0;
}

#include "import_cli.hpp"

#include <openssl/evp.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "io/input_file.hpp"
#include "io/json_text.hpp"

namespace visvol::cli {

void add_import_options(CLI::App* app, ImportCli& o) {
  app->add_flag("--fill-nodata", o.fill_nodata,
                "Fill nodata holes (up to 128 posts from data) instead of refusing the DEM");
  app->add_option("--t-srs", o.t_srs,
                  "Output CRS (EPSG:<code>, WKT or PROJ), metric; default: keep a projected CRS, "
                  "the UTM zone of the centre for a geographic DEM");
  app->add_option("--assume-srs", o.assume_srs,
                  "CRS of a DEM that carries none (e.g. EPSG:4326 for an ESRI grid without .prj)");
  app->add_option("--spacing", o.spacing_m, "Resample to this post spacing, m (0: keep)")->capture_default_str();
  app->add_option("--crop", o.crop, "Keep the box XMIN YMIN XMAX YMAX (output CRS, m)")->expected(4);
  app->add_option("--resampling", o.resampling, "near, bilinear, cubic, cubicspline, lanczos or average")
      ->capture_default_str();
}

fields::ImportOptions import_options(const ImportCli& o) {
  fields::ImportOptions options;
  options.nodata = o.fill_nodata ? fields::NodataPolicy::fill : fields::NodataPolicy::refuse;
  options.target_srs = o.t_srs;
  options.assume_srs = o.assume_srs;
  options.spacing_m = o.spacing_m;
  options.resampling = o.resampling;
  if (!o.crop.empty()) options.crop = fields::BoundingBox{o.crop[0], o.crop[1], o.crop[2], o.crop[3]};
  if (o.max_posts > 0 && o.max_posts < options.max_posts) {
    options.max_posts = o.max_posts;
    options.max_posts_reason = o.max_posts_reason;
  }
  return options;
}

Result<fields::Heightfield> import(const std::string& path, const ImportCli& o, fields::ImportReport* report) {
  return fields::import_dem(path, import_options(o), report);
}

Result<std::string> sha256_file(const std::string& path) {
  Result<InputFile> in = InputFile::open(path);
  if (!in.ok()) return in.status();
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  if (!ctx || EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr) != 1) {
    return Status(Errc::unsupported, "SHA-256 is not available from OpenSSL");
  }
  std::vector<char> buf(1 << 20);
  while (true) {
    const ssize_t n = ::read(in->fd(), buf.data(), buf.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return io_error(path + ": read failed: " + std::strerror(errno));
    if (n == 0) break;
    EVP_DigestUpdate(ctx.get(), buf.data(), static_cast<std::size_t>(n));
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  EVP_DigestFinal_ex(ctx.get(), digest, &len);
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned int n = 0; n < len; ++n) {
    out += hex[digest[n] >> 4];
    out += hex[digest[n] & 15];
  }
  return out;
}

std::string source_json(const std::string& path, const ImportCli& o, const fields::ImportReport& report) {
  nlohmann::json j;
  j["path"] = path;
  const Result<std::string> sha = sha256_file(path);
  j["sha256"] = sha.ok() ? *sha : std::string();
  j["driver"] = report.source.driver;
  j["size"] = {report.source.nx, report.source.ny};
  j["crs"] = report.source.crs_name;
  j["vertical_unit"] = report.source.vertical_unit.empty() ? "m" : report.source.vertical_unit;
  j["import"] = {{"fill_nodata", o.fill_nodata}, {"t_srs", o.t_srs}, {"assume_srs", o.assume_srs},
                 {"spacing_m", o.spacing_m},     {"crop", o.crop},   {"resampling", o.resampling},
                 {"steps", report.steps}};
  return json_text(j);
}

}  // namespace visvol::cli

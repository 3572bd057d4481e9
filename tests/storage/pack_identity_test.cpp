#include "storage/pack_identity.hpp"

#include <gtest/gtest.h>
#include <ogr_spatialref.h>

namespace visvol::storage {
namespace {

TEST(PackIdentity, PackIdIsTheFileStemInSafeCharacters) {
  EXPECT_EQ(pack_id_from_path("/srv/packs/sf_north.vvp"), "sf_north");
  EXPECT_EQ(pack_id_from_path("taunus 90m+v2.vvp"), "taunus_90m_v2");
  EXPECT_EQ(pack_id_from_path("/srv/packs/.vvp"), ".vvp");
  EXPECT_EQ(pack_id_from_path(std::string(100, 'a') + ".vvp").size(), 63u);
  EXPECT_EQ(pack_id_from_path("dir/"), "pack");
}

// WKT as GDAL writes it, in both generations of the format.
std::string wkt_of(int epsg, const char* const* options) {
  OGRSpatialReference srs;
  EXPECT_EQ(srs.importFromEPSG(epsg), OGRERR_NONE);
  char* text = nullptr;
  EXPECT_EQ(srs.exportToWkt(&text, options), OGRERR_NONE);
  std::string s(text);
  CPLFree(text);
  return s;
}

TEST(PackIdentity, EpsgCodeOfTheWholeCrs) {
  const char* wkt1[] = {"FORMAT=WKT1", nullptr};
  const char* wkt2[] = {"FORMAT=WKT2_2018", nullptr};
  for (int code : {26710, 32632, 32610, 4326}) {
    EXPECT_EQ(epsg_from_wkt(wkt_of(code, wkt1)), "EPSG:" + std::to_string(code));
    EXPECT_EQ(epsg_from_wkt(wkt_of(code, wkt2)), "EPSG:" + std::to_string(code));
  }
  EXPECT_EQ(epsg_from_wkt(""), "");
  EXPECT_EQ(epsg_from_wkt("not a crs"), "");
  // a CRS without its own identifier does not borrow its datum's
  EXPECT_EQ(epsg_from_wkt(R"(PROJCS["local",GEOGCS["NAD27",AUTHORITY["EPSG","4267"]],UNIT["metre",1]])"), "");
}

}  // namespace
}  // namespace visvol::storage

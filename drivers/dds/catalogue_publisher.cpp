#include "drivers/dds/catalogue_publisher.hpp"

#include <utility>

namespace visvol::dds {

Result<std::unique_ptr<CataloguePublisher>> CataloguePublisher::create(const Participant& participant,
                                                                       const std::string& frame_id) {
  if (frame_id.empty()) return invalid_argument("catalogue publisher: empty frame id");
  Result<Writer> w = Writer::create(participant, Topic::terrain_catalogue);
  if (!w.ok()) return w.status();
  return std::unique_ptr<CataloguePublisher>(new CataloguePublisher(std::move(*w), frame_id));
}

CataloguePublisher::CataloguePublisher(Writer writer, const std::string& frame_id)
    : writer_(std::move(writer)), message_(frame_id) {}

Status CataloguePublisher::publish(const msg::TerrainCatalogue& catalogue) {
  VISVOL_RETURN_IF_ERROR(message_.fill(catalogue));
  const dds_return_t rc = writer_.write(&message_.message());
  if (rc < 0) return dds_error(std::string("writing ") + relative_name(writer_.topic()), rc);
  ++published_;
  return Status();
}

}  // namespace visvol::dds

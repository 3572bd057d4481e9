// Publishes the console's terrain catalogue on rt/visvol/terrain_catalogue
// (reliable, transient-local: a late joiner gets the latest), from the
// console's main thread when an entry changes.
//
// Thread-safety: one thread (never the real-time one: writing allocates).
#pragma once

#include <memory>
#include <string>

#include "base/status.hpp"
#include "drivers/dds/message_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "msg/samples.hpp"

namespace visvol::dds {

class CataloguePublisher {
 public:
  static Result<std::unique_ptr<CataloguePublisher>> create(const Participant& participant,
                                                            const std::string& frame_id = kDefaultFrameId);
  Status publish(const msg::TerrainCatalogue& catalogue);
  std::uint64_t published() const { return published_; }

 private:
  CataloguePublisher(Writer writer, const std::string& frame_id);
  Writer writer_;
  CatalogueMessage message_;
  std::uint64_t published_ = 0;
};

}  // namespace visvol::dds

#include "drivers/dds/path_publisher.hpp"

#include <chrono>
#include <cstdio>
#include <thread>
#include <utility>

namespace visvol::dds {
namespace {

Status write_status(const Writer& writer, const void* sample) {
  const dds_return_t rc = writer.write(sample);
  if (rc < 0) return dds_error(std::string("writing ") + relative_name(writer.topic()), rc);
  return Status();
}

}  // namespace

Result<std::unique_ptr<PathPublisher>> PathPublisher::create(const Participant& participant,
                                                             const std::string& frame_id) {
  if (frame_id.empty()) return invalid_argument("path publisher: empty frame id");
  Result<Writer> path = Writer::create(participant, Topic::path);
  if (!path.ok()) return path.status();
  Result<Writer> update = Writer::create(participant, Topic::path_update);
  if (!update.ok()) return update.status();
  Result<Writer> thumbnail = Writer::create(participant, Topic::thumbnail);
  if (!thumbnail.ok()) return thumbnail.status();
  Result<Writer> terrain = Writer::create(participant, Topic::terrain);
  if (!terrain.ok()) return terrain.status();
  return std::unique_ptr<PathPublisher>(
      new PathPublisher(frame_id, std::move(*path), std::move(*update), std::move(*thumbnail), std::move(*terrain)));
}

PathPublisher::PathPublisher(const std::string& frame_id, Writer path, Writer update, Writer thumbnail, Writer terrain)
    : path_writer_(std::move(path)),
      update_writer_(std::move(update)),
      thumbnail_writer_(std::move(thumbnail)),
      terrain_writer_(std::move(terrain)),
      path_(frame_id),
      thumbnail_(frame_id),
      terrain_(frame_id) {}

Status PathPublisher::publish(const msg::PathSample& path) {
  VISVOL_RETURN_IF_ERROR(path_.fill(path));
  // The update first: a subscriber of both sees the measure no later than
  // the geometry.
  VISVOL_RETURN_IF_ERROR(write_status(update_writer_, &path_.update()));
  return write_status(path_writer_, &path_.path());
}

Status PathPublisher::publish(const msg::ThumbnailSample& thumbnail) {
  VISVOL_RETURN_IF_ERROR(thumbnail_.fill(thumbnail));
  return write_status(thumbnail_writer_, &thumbnail_.message());
}

Status PathPublisher::publish(const msg::TerrainInfo& terrain) {
  VISVOL_RETURN_IF_ERROR(terrain_.fill(terrain));
  return write_status(terrain_writer_, &terrain_.message());
}

Status PathPublisher::wait_for_delivery(double timeout_s) const {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::nanoseconds(to_duration(timeout_s));
  for (const Writer* w : {&update_writer_, &path_writer_, &thumbnail_writer_, &terrain_writer_}) {
    const double left_s = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    const dds_return_t rc = w->wait_for_acks(left_s > 0.0 ? left_s : 0.0);
    if (rc == DDS_RETCODE_TIMEOUT) {
      char text[256];
      std::snprintf(text, sizeof text,
                    "%s: not every subscriber (%u matched) acknowledged within %.1f s; "
                    "some may have missed the last sample",
                    relative_name(w->topic()), w->matched_readers(), timeout_s);
      return Status(Errc::timeout, text);
    }
    if (rc < 0) {
      return dds_error(std::string("waiting for delivery of ") + relative_name(w->topic()), rc);
    }
  }
  return Status();
}

Status PathPublisher::wait_for_subscribers(std::uint32_t count, double timeout_s) const {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::nanoseconds(to_duration(timeout_s));
  while (subscribers() < count) {
    if (std::chrono::steady_clock::now() >= deadline) {
      char text[200];
      std::snprintf(text, sizeof text, "path publisher: %u of %u subscribers (%s and %s readers) after %.1f s",
                    subscribers(), count, relative_name(Topic::path_update), relative_name(Topic::path), timeout_s);
      return Status(Errc::timeout, text);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // discovery on loopback takes milliseconds
  }
  return Status();
}

std::uint32_t PathPublisher::path_subscribers() const { return path_writer_.matched_readers(); }
std::uint32_t PathPublisher::path_update_subscribers() const { return update_writer_.matched_readers(); }

}  // namespace visvol::dds

// The console's publisher thread: it takes the newest samples from wait-free
// hand-offs and publishes them on DDS, so that dds_write (which allocates and
// may block) never runs on the real-time thread.
//
//   real-time thread                       publisher thread
//   PathSample& p = pub.path().back();     take() the newest of each hand-off
//   ... fill p ...;  pub.path().publish();  when its rate allows, convert, write
//
// Each hand-off is a LatestValue (base/handoff.hpp): the producer never
// waits and never fails, newer values replace older ones, and nothing is
// allocated after start. Each has exactly one producer thread:
//
//   hand-off         producer                published at most       topic
//   path()           executive (1 kHz)       path_hz (50)            path, path_update
//   health()         executive               health_hz (10)          health
//   device_status()  device thread           device_status_hz (10)   device_status
//   thumbnail()      renderer (on converge)  thumbnail_max_hz (1)    thumbnail/compressed
//   terrain()        console (pack loaded)   on change               terrain
//
// A rate is a minimum spacing: a sample is published as soon as it is seen
// once its topic's interval since the last publication has passed; samples in
// between are superseded, never queued. The thread sees fresh data within
// poll_interval_s while data flows and within idle_poll_interval_s after
// idle_after_s without any (it polls: the producer makes no system call).
//
// Paths go out fresh: when the newest path at its turn is older than
// poll_interval_s (by its stamp_ns, which the producer sets at hand-off), the
// thread keeps it and waits up to path_refresh_wait_s for a newer one (a
// 1 kHz executive hands one off within a millisecond), then publishes the
// newer one or, failing that, the one it kept. So what a subscriber receives
// is about as old as the poll interval plus delivery, not up to one producer
// period older. It waits only for a producer that hands off at least once per
// path_refresh_wait_s (its period estimated from the sequence numbers and
// stamps of the paths it took; unknown at first): waiting for one that hands
// off less often only delays the path. 0 turns this off.
//
// Thread-safety: the hand-offs as above; stop() and stats() from any one
// other thread. Cost: one thread; hand-offs and messages reserved at start
// (about 1 MiB, mostly the thumbnail's triple buffer).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "base/handoff.hpp"
#include "base/status.hpp"
#include "drivers/dds/message_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "drivers/dds/path_publisher.hpp"
#include "msg/samples.hpp"

namespace visvol::dds {

class CommandIntake;

struct PublisherConfig {
  double path_hz = 50.0;
  double health_hz = 10.0;
  double device_status_hz = 10.0;
  double thumbnail_max_hz = 1.0;
  double poll_interval_s = 0.00025;
  double idle_poll_interval_s = 0.005;
  double idle_after_s = 0.5;
  double path_refresh_wait_s = 0.0015;
  // On stop: how long to wait for reliable delivery of the last samples.
  double linger_s = 1.0;
  std::string frame_id = kDefaultFrameId;
};
// Rates in (0, 1000] Hz, polls in [10 us, 100 ms] (idle >= active),
// idle_after_s in (0, 3600], path_refresh_wait_s in [0, 0.1],
// linger_s in [0, 60], a frame id.
Status validate(const PublisherConfig& config);

struct PublisherStats {
  std::uint64_t paths = 0;  // published samples per hand-off
  std::uint64_t health = 0;
  std::uint64_t device_status = 0;
  std::uint64_t thumbnails = 0;
  std::uint64_t terrain = 0;
  std::uint64_t paths_held = 0;  // stale paths kept back for a newer one
  std::uint64_t errors = 0;      // samples not published (bad sample or DDS error)
  std::string last_error;
};

class LivePublisher {
 public:
  // Creates the writers and starts the thread. `intake` (may be null, must
  // outlive the publisher) supplies the command counters of health reports.
  static Result<std::unique_ptr<LivePublisher>> start(const Participant& participant, const PublisherConfig& config,
                                                      const CommandIntake* intake = nullptr);
  ~LivePublisher();  // stop()
  LivePublisher(const LivePublisher&) = delete;
  LivePublisher& operator=(const LivePublisher&) = delete;

  // The hand-offs (see the table above). Real-time safe for their producer.
  LatestValue<msg::PathSample>& path() { return path_; }
  LatestValue<msg::HealthSample>& health() { return health_; }
  LatestValue<msg::DeviceStatusSample>& device_status() { return device_; }
  LatestValue<msg::ThumbnailSample>& thumbnail() { return thumbnail_; }
  LatestValue<msg::TerrainInfo>& terrain() { return terrain_; }

  // Stops the thread after a last pass that publishes every fresh sample
  // regardless of rates, then waits up to linger_s for reliable delivery.
  // Returns the delivery status (a timeout names the topic); later calls
  // return ok at once.
  Status stop();
  PublisherStats stats() const;
  // The thread's passes so far: advancing while it lives (a supervisor's
  // watchdog asks for it; at least one every idle_poll_interval_s).
  std::uint64_t passes() const { return passes_.load(std::memory_order_relaxed); }
  // Readers matched on the path update topic.
  std::uint32_t path_subscribers() const { return paths_->path_update_subscribers(); }

 private:
  struct Stream {
    std::int64_t min_interval_ns = 0;
    std::int64_t next_allowed_ns = 0;
    std::int64_t last_fresh_ns = 0;
    std::atomic<std::uint64_t> published{0};
  };

  LivePublisher(const PublisherConfig& config, const CommandIntake* intake, std::unique_ptr<PathPublisher> paths,
                Writer health, Writer device);
  void run();
  void pass(std::int64_t now_ns, bool final);
  void service_path(std::int64_t now_ns, bool final);
  void publish_path(const msg::PathSample& sample, std::int64_t now_ns);
  std::int64_t next_wake_ns(std::int64_t now_ns) const;
  template <typename T, typename Publish>
  void service(Stream& stream, LatestValue<T>& handoff, std::int64_t now_ns, bool final, Publish&& publish);
  void count_error(const Status& status);

  const PublisherConfig config_;
  const CommandIntake* const intake_;

  LatestValue<msg::PathSample> path_;
  LatestValue<msg::HealthSample> health_;
  LatestValue<msg::DeviceStatusSample> device_;
  LatestValue<msg::ThumbnailSample> thumbnail_;
  LatestValue<msg::TerrainInfo> terrain_;

  // Publisher thread only.
  std::unique_ptr<PathPublisher> paths_;
  Writer health_writer_;
  Writer device_writer_;
  HealthMessage health_msg_;
  DeviceStatusMessage device_msg_;
  Stream path_stream_, health_stream_, device_stream_, thumbnail_stream_, terrain_stream_;
  std::unique_ptr<msg::PathSample> held_path_;  // a stale path kept while a newer one may come
  bool holding_path_ = false;
  // the path producer's hand-off period, from the paths taken (-1: unknown)
  std::uint64_t last_path_sequence_ = 0;
  std::int64_t last_path_stamp_ns_ = 0;
  std::int64_t path_period_ns_ = -1;
  void note_path_producer(const msg::PathSample& sample);
  std::int64_t hold_until_ns_ = 0;

  std::atomic<std::uint64_t> errors_{0};
  std::atomic<std::uint64_t> paths_held_{0};
  std::atomic<std::uint64_t> passes_{0};
  mutable std::mutex mutex_;  // guards last_error_, stopping_, stopped_
  std::condition_variable wake_;
  std::string last_error_;
  bool stopping_ = false;
  bool stopped_ = false;
  std::thread thread_;
};

}  // namespace visvol::dds

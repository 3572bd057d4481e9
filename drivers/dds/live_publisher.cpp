#include "drivers/dds/live_publisher.hpp"

#include <pthread.h>
#include <sys/prctl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "drivers/dds/command_intake.hpp"

namespace visvol::dds {
namespace {

using Clock = std::chrono::steady_clock;

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

std::int64_t to_ns(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e9)); }

Status check_range(const char* name, double v, double lo, double hi, const char* unit) {
  if (!std::isfinite(v) || v < lo || v > hi) {
    return invalid_argument(std::string("publisher: ") + name + " = " + std::to_string(v) + " outside [" +
                            std::to_string(lo) + ", " + std::to_string(hi) + "] " + unit);
  }
  return Status();
}

}  // namespace

Status validate(const PublisherConfig& c) {
  constexpr double kMinHz = 1e-3;
  VISVOL_RETURN_IF_ERROR(check_range("path_hz", c.path_hz, kMinHz, 1000.0, "Hz"));
  VISVOL_RETURN_IF_ERROR(check_range("health_hz", c.health_hz, kMinHz, 1000.0, "Hz"));
  VISVOL_RETURN_IF_ERROR(check_range("device_status_hz", c.device_status_hz, kMinHz, 1000.0, "Hz"));
  VISVOL_RETURN_IF_ERROR(check_range("thumbnail_max_hz", c.thumbnail_max_hz, kMinHz, 1000.0, "Hz"));
  VISVOL_RETURN_IF_ERROR(check_range("poll_interval_s", c.poll_interval_s, 1e-5, 0.1, "s"));
  VISVOL_RETURN_IF_ERROR(check_range("idle_poll_interval_s", c.idle_poll_interval_s, c.poll_interval_s, 0.1, "s"));
  VISVOL_RETURN_IF_ERROR(check_range("idle_after_s", c.idle_after_s, 1e-3, 3600.0, "s"));
  VISVOL_RETURN_IF_ERROR(check_range("path_refresh_wait_s", c.path_refresh_wait_s, 0.0, 0.1, "s"));
  VISVOL_RETURN_IF_ERROR(check_range("linger_s", c.linger_s, 0.0, 60.0, "s"));
  if (c.frame_id.empty()) return invalid_argument("publisher: empty frame id");
  return Status();
}

Result<std::unique_ptr<LivePublisher>> LivePublisher::start(const Participant& participant,
                                                            const PublisherConfig& config,
                                                            const CommandIntake* intake) {
  VISVOL_RETURN_IF_ERROR(validate(config));
  Result<std::unique_ptr<PathPublisher>> paths = PathPublisher::create(participant, config.frame_id);
  if (!paths.ok()) return paths.status();
  Result<Writer> health = Writer::create(participant, Topic::health);
  if (!health.ok()) return health.status();
  Result<Writer> device = Writer::create(participant, Topic::device_status);
  if (!device.ok()) return device.status();
  std::unique_ptr<LivePublisher> publisher(
      new LivePublisher(config, intake, std::move(*paths), std::move(*health), std::move(*device)));
  publisher->thread_ = std::thread([raw = publisher.get()] { raw->run(); });
  return publisher;
}

LivePublisher::LivePublisher(const PublisherConfig& config, const CommandIntake* intake,
                             std::unique_ptr<PathPublisher> paths, Writer health, Writer device)
    : config_(config),
      intake_(intake),
      paths_(std::move(paths)),
      health_writer_(std::move(health)),
      device_writer_(std::move(device)),
      health_msg_(config.frame_id),
      device_msg_(config.frame_id),
      held_path_(std::make_unique<msg::PathSample>()) {
  path_stream_.min_interval_ns = to_ns(1.0 / config.path_hz);
  health_stream_.min_interval_ns = to_ns(1.0 / config.health_hz);
  device_stream_.min_interval_ns = to_ns(1.0 / config.device_status_hz);
  thumbnail_stream_.min_interval_ns = to_ns(1.0 / config.thumbnail_max_hz);
  terrain_stream_.min_interval_ns = 0;  // on change
}

LivePublisher::~LivePublisher() { (void)stop(); }

Status LivePublisher::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopped_) return Status();
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  // the thread's last pass has run: wait for its samples to be acknowledged,
  // all writers within one linger time
  const auto start = Clock::now();
  Status delivery = paths_->wait_for_delivery(config_.linger_s);
  const double left_s = config_.linger_s - std::chrono::duration<double>(Clock::now() - start).count();
  if (delivery.ok() && device_writer_.wait_for_acks(std::max(left_s, 0.0)) == DDS_RETCODE_TIMEOUT) {
    delivery = Status(Errc::timeout, "device_status: not every subscriber acknowledged within " +
                                         std::to_string(config_.linger_s) + " s");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  stopped_ = true;
  return delivery;
}

PublisherStats LivePublisher::stats() const {
  PublisherStats s;
  s.paths = path_stream_.published.load(std::memory_order_relaxed);
  s.health = health_stream_.published.load(std::memory_order_relaxed);
  s.device_status = device_stream_.published.load(std::memory_order_relaxed);
  s.thumbnails = thumbnail_stream_.published.load(std::memory_order_relaxed);
  s.terrain = terrain_stream_.published.load(std::memory_order_relaxed);
  s.paths_held = paths_held_.load(std::memory_order_relaxed);
  s.errors = errors_.load(std::memory_order_relaxed);
  std::lock_guard<std::mutex> lock(mutex_);
  s.last_error = last_error_;
  return s;
}

void LivePublisher::count_error(const Status& status) {
  errors_.fetch_add(1, std::memory_order_relaxed);
  std::lock_guard<std::mutex> lock(mutex_);
  last_error_ = status.message();
}

void LivePublisher::run() {
  pthread_setname_np(pthread_self(), "visvol-dds-pub");
  // Wake-ups close to the requested time: the poll interval is the latency.
  prctl(PR_SET_TIMERSLACK, 10000UL, 0UL, 0UL, 0UL);
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_) {
    lock.unlock();
    const std::int64_t now = now_ns();
    pass(now, false);
    const std::int64_t wake = next_wake_ns(now_ns());
    lock.lock();
    wake_.wait_until(lock, Clock::time_point(std::chrono::nanoseconds(wake)), [this] { return stopping_; });
  }
  lock.unlock();
  pass(now_ns(), true);
}

template <typename T, typename Publish>
void LivePublisher::service(Stream& stream, LatestValue<T>& handoff, std::int64_t now, bool final, Publish&& publish) {
  if (!final && now < stream.next_allowed_ns) return;
  const T* sample = handoff.take();
  if (!sample) return;
  stream.last_fresh_ns = now;
  stream.next_allowed_ns = now + stream.min_interval_ns;
  const Status status = publish(*sample);
  if (status.ok()) {
    stream.published.fetch_add(1, std::memory_order_relaxed);
  } else {
    count_error(status);
  }
}

void LivePublisher::pass(std::int64_t now, bool final) {
  passes_.fetch_add(1, std::memory_order_relaxed);
  // terrain first: a subscriber learns the CRS before the first path in it
  service(terrain_stream_, terrain_, now, final, [this](const msg::TerrainInfo& t) { return paths_->publish(t); });
  service_path(now, final);
  service(health_stream_, health_, now, final, [this](const msg::HealthSample& h) {
    LayerCounters counters;
    if (intake_) {
      const IntakeStats s = intake_->stats();
      counters.commands_accepted = s.commands.accepted;
      counters.commands_rejected = s.commands.rejected;
    }
    counters.publish_errors = errors_.load(std::memory_order_relaxed);
    VISVOL_RETURN_IF_ERROR(health_msg_.fill(h, counters));
    const dds_return_t rc = health_writer_.write(&health_msg_.message());
    return rc < 0 ? dds_error("writing health", rc) : Status();
  });
  service(device_stream_, device_, now, final, [this](const msg::DeviceStatusSample& d) {
    VISVOL_RETURN_IF_ERROR(device_msg_.fill(d));
    const dds_return_t rc = device_writer_.write(&device_msg_.message());
    return rc < 0 ? dds_error("writing device status", rc) : Status();
  });
  service(thumbnail_stream_, thumbnail_, now, final,
          [this](const msg::ThumbnailSample& t) { return paths_->publish(t); });
}

void LivePublisher::publish_path(const msg::PathSample& sample, std::int64_t now) {
  path_stream_.next_allowed_ns = now + path_stream_.min_interval_ns;
  holding_path_ = false;
  const Status status = paths_->publish(sample);
  if (status.ok()) {
    path_stream_.published.fetch_add(1, std::memory_order_relaxed);
  } else {
    count_error(status);
  }
}

void LivePublisher::note_path_producer(const msg::PathSample& sample) {
  if (last_path_sequence_ != 0 && sample.sequence > last_path_sequence_ && sample.stamp_ns > last_path_stamp_ns_) {
    path_period_ns_ =
        (sample.stamp_ns - last_path_stamp_ns_) / static_cast<std::int64_t>(sample.sequence - last_path_sequence_);
  } else if (sample.sequence <= last_path_sequence_) {
    path_period_ns_ = -1;  // a new planning run numbers from the start
  }
  last_path_sequence_ = sample.sequence;
  last_path_stamp_ns_ = sample.stamp_ns;
}

void LivePublisher::service_path(std::int64_t now, bool final) {
  if (!final && now < path_stream_.next_allowed_ns) return;
  if (const msg::PathSample* sample = path_.take()) {
    path_stream_.last_fresh_ns = now;
    note_path_producer(*sample);
    const std::int64_t age_ns = msg::now_stamp_ns() - sample->stamp_ns;
    const bool fresh = age_ns <= to_ns(config_.poll_interval_s);
    const std::int64_t wait_ns = to_ns(config_.path_refresh_wait_s);
    const bool newer_soon = path_period_ns_ < 0 || path_period_ns_ <= wait_ns;
    // the newest path goes out when it is fresh, when it replaces one kept
    // back, when no newer one is due within the wait, or when there is no
    // time to wait
    if (fresh || holding_path_ || final || wait_ns <= 0 || !newer_soon) {
      publish_path(*sample, now);
      return;
    }
    *held_path_ = *sample;
    holding_path_ = true;
    paths_held_.fetch_add(1, std::memory_order_relaxed);
    hold_until_ns_ = now + to_ns(config_.path_refresh_wait_s);
    return;
  }
  if (holding_path_ && (final || now >= hold_until_ns_)) publish_path(*held_path_, now);
}

std::int64_t LivePublisher::next_wake_ns(std::int64_t now) const {
  const std::int64_t poll = to_ns(config_.poll_interval_s);
  const std::int64_t idle_poll = to_ns(config_.idle_poll_interval_s);
  const std::int64_t idle_after = to_ns(config_.idle_after_s);
  std::int64_t wake = now + idle_poll;
  for (const Stream* s : {&path_stream_, &health_stream_, &device_stream_, &thumbnail_stream_, &terrain_stream_}) {
    if (now < s->next_allowed_ns) {
      wake = std::min(wake, s->next_allowed_ns);
    } else {
      // allowed and waiting for data: poll fast while it flows
      const bool active = s->last_fresh_ns != 0 && now - s->last_fresh_ns < idle_after;
      wake = std::min(wake, now + (active ? poll : idle_poll));
    }
  }
  if (holding_path_) wake = std::min(wake, std::min(now + poll, hold_until_ns_));
  return wake;
}

}  // namespace visvol::dds

// A Cyclone DDS participant on an explicit domain with an explicit
// configuration, and the typed writers and readers built on it.
//
// The configuration always comes from the caller (the console's own
// configuration, a command-line option, or the shipped loopback file), never
// from the CYCLONEDDS_URI environment variable.
//
// Ownership: Participant owns its Cyclone participant, and a reference on the
// process-wide Cyclone domain of its id (Cyclone allows one configuration per
// domain id per process; participants of one id in one process share it).
// Writers and readers own their entities; the Participant must outlive them.
//
// Thread-safety: creating and destroying participants is thread-safe.
// Writer::write and Reader::take may run on different threads, one thread per
// Writer or Reader at a time. None of this is real-time safe: it allocates,
// takes locks and makes system calls.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "base/status.hpp"
#include "drivers/dds/topics.hpp"

namespace visvol::dds {

// Highest domain id whose ports fit the default Cyclone port mapping with up
// to 32 participants per domain and host.
inline constexpr std::uint32_t kMaxDomainId = 232;

// The loopback-only configuration shipped in drivers/dds/cyclone_loopback.xml,
// compiled in so that installed binaries do not need the source tree.
std::string_view loopback_config();

// Reads a Cyclone XML configuration file (at most 1 MiB). Errors name the
// file and the problem.
Result<std::string> read_cyclone_config(const std::string& path);

// The largest serialised sample a participant sends or takes, bytes:
// Cyclone drops a larger one as it arrives (with a line on stderr), before
// reassembling or decoding it. Every domain visvol creates has it (merged in
// after the configuration given), unless that configuration sets
// Internal/MaxSampleSize itself: a set-constraints command
// of 25 million observers took a console from 67 to 950 MiB of locked memory
// before its own limit (msg::kMaxConstraints) could refuse it. visvol's
// largest samples, a thumbnail's PNG (msg::kMaxThumbnailBytes) and a path of
// msg::kMaxPathVertices, are a quarter of it at most.
inline constexpr std::uint32_t kMaxSampleBytes = 1024 * 1024;

// Whether a Cyclone configuration sets Internal/MaxSampleSize itself: an
// element of that name outside comments (one that named it in a comment
// switched visvol's limit off), in any of its <Domain> entries (one set for
// another domain id keeps visvol's limit off for this one too).
bool sets_max_sample_size(const std::string& xml);

struct ParticipantConfig {
  std::uint32_t domain_id = 0;  // 0..kMaxDomainId
  // The Cyclone configuration XML itself (not a file name): see
  // loopback_config() and read_cyclone_config(). Its <Domain Id> must be
  // "any" or domain_id; Cyclone would silently ignore it otherwise.
  std::string cyclone_xml;
  // ROS-style namespace of every topic (topics.hpp); empty for none.
  std::string topic_namespace;
};

// Checks a configuration before use: domain range, a non-empty XML whose
// <Domain> entries apply to the domain, a valid namespace.
Status validate(const ParticipantConfig& config);

class Participant {
 public:
  // Creates the participant (and the domain when this process has none of
  // that id yet). Fails with the reason: a bad configuration, a domain of that
  // id already created in this process with another configuration, or
  // Cyclone's own error. Cost: tens of milliseconds (sockets, threads).
  static Result<std::unique_ptr<Participant>> create(const ParticipantConfig& config);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  dds_entity_t handle() const { return participant_; }
  std::uint32_t domain_id() const { return domain_id_; }
  const std::string& topic_namespace() const { return namespace_; }
  // The DDS name of a topic in this participant's namespace.
  std::string topic_name(Topic topic) const;

 private:
  Participant(dds_entity_t participant, std::uint32_t domain_id, std::string ns);
  dds_entity_t participant_;
  std::uint32_t domain_id_;
  std::string namespace_;
};

// A Cyclone error code as a Status: "<what>: <Cyclone's text>".
Status dds_error(std::string_view what, dds_return_t rc);

// A writer of one topic with the QoS of topics.hpp.
class Writer {
 public:
  static Result<Writer> create(const Participant& participant, Topic topic);
  Writer() = default;
  ~Writer();
  Writer(Writer&& other) noexcept;
  Writer& operator=(Writer&& other) noexcept;
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Serialises and sends one sample of the topic's generated type. Allocates
  // and may block up to 50 ms when reliable history is full: never call it
  // from the real-time thread.
  dds_return_t write(const void* sample) const;
  // Readers currently matched.
  std::uint32_t matched_readers() const;
  // Waits until `count` readers are matched or the timeout passes.
  Status wait_for_readers(std::uint32_t count, double timeout_s) const;
  // Waits until every matched reliable reader has acknowledged everything
  // written; DDS_RETCODE_TIMEOUT when the time passes first.
  dds_return_t wait_for_acks(double timeout_s) const;
  dds_entity_t handle() const { return writer_; }
  Topic topic() const { return topic_; }

 private:
  Writer(dds_entity_t writer, dds_entity_t topic_entity, Topic topic)
      : writer_(writer), topic_entity_(topic_entity), topic_(topic) {}
  void reset();
  dds_entity_t writer_ = 0;
  dds_entity_t topic_entity_ = 0;
  Topic topic_ = Topic::path;
};

// A reader of one topic with the QoS of topics.hpp (or the caller's).
class Reader {
 public:
  static Result<Reader> create(const Participant& participant, Topic topic);
  // With the caller's QoS (e.g. a volatile path reader, as RViz uses).
  static Result<Reader> create(const Participant& participant, Topic topic, const dds_qos_t* qos);
  Reader() = default;
  ~Reader();
  Reader(Reader&& other) noexcept;
  Reader& operator=(Reader&& other) noexcept;
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  // Waits until data is available or the timeout passes; true when some is.
  Result<bool> wait(double timeout_s) const;
  // Takes up to `max` samples and calls fn(const Msg&, const dds_sample_info_t&)
  // for each valid one; Msg is the topic's generated C type. Returns the
  // number taken (valid or not) or an error. The references live until fn
  // returns.
  template <typename Msg, typename Fn>
  Result<int> take(Fn&& fn, std::uint32_t max = 16) const;
  // Takes one sample in serialised form: the CDR bytes as they travel, with
  // the 4-byte encapsulation header. Empty vector when none is waiting.
  Result<std::vector<std::uint8_t>> take_serialized() const;
  // Writers currently matched.
  std::uint32_t matched_writers() const;
  Status wait_for_writers(std::uint32_t count, double timeout_s) const;
  dds_entity_t handle() const { return reader_; }

 private:
  static constexpr std::uint32_t kMaxTake = 64;
  Reader(dds_entity_t reader, dds_entity_t topic_entity, dds_entity_t waitset)
      : reader_(reader), topic_entity_(topic_entity), waitset_(waitset) {}
  void reset();
  dds_return_t take_loaned(void** samples, dds_sample_info_t* infos, std::uint32_t max) const;
  void return_loan(void** samples, int count) const;
  dds_entity_t reader_ = 0;
  dds_entity_t topic_entity_ = 0;
  dds_entity_t waitset_ = 0;
};

template <typename Msg, typename Fn>
Result<int> Reader::take(Fn&& fn, std::uint32_t max) const {
  if (max == 0 || max > kMaxTake) max = kMaxTake;
  void* samples[kMaxTake] = {};
  dds_sample_info_t infos[kMaxTake];
  const dds_return_t n = take_loaned(samples, infos, max);
  if (n < 0) return dds_error("take", n);
  for (int i = 0; i < n; ++i) {
    if (infos[i].valid_data) fn(*static_cast<const Msg*>(samples[i]), infos[i]);
  }
  return_loan(samples, n);
  return static_cast<int>(n);
}

}  // namespace visvol::dds

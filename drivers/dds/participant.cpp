#include "drivers/dds/participant.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>
#include <utility>

#include <dds/ddsi/ddsi_serdata.h>

#include "drivers/dds/log_limit.hpp"
#include "io/input_file.hpp"
#include "msg/samples.hpp"

namespace visvol::dds {
namespace {

constexpr std::size_t kMaxConfigBytes = 1u << 20;

// Cyclone keeps one configuration per domain id per process; so do we, with
// a count of the participants that use it. Guarded by registry_mutex().
struct DomainUse {
  dds_entity_t domain;
  std::string xml;
  int participants;
};
std::mutex& registry_mutex() {
  static std::mutex m;
  return m;
}
std::map<std::uint32_t, DomainUse>& registry() {
  static std::map<std::uint32_t, DomainUse> r;
  return r;
}

std::string strip_comments(std::string_view xml) {
  std::string out;
  out.reserve(xml.size());
  std::size_t pos = 0;
  while (pos < xml.size()) {
    const std::size_t open = xml.find("<!--", pos);
    if (open == std::string_view::npos) {
      out.append(xml.substr(pos));
      break;
    }
    out.append(xml.substr(pos, open - pos));
    const std::size_t close = xml.find("-->", open + 4);
    if (close == std::string_view::npos) break;
    pos = close + 3;
  }
  return out;
}

std::string trim(std::string_view s) {
  const std::size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return std::string();
  const std::size_t e = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(b, e - b + 1));
}

// The id a <Domain> element applies to: its Id attribute, the legacy <Id>
// child, or "any" when it has neither.
std::string domain_element_id(std::string_view tag, std::string_view body) {
  for (const char* attr : {"Id=", "id=", "ID="}) {
    const std::size_t at = tag.find(attr);
    if (at == std::string_view::npos) continue;
    const std::size_t q = at + std::strlen(attr);
    if (q >= tag.size() || (tag[q] != '"' && tag[q] != '\'')) continue;
    const std::size_t end = tag.find(tag[q], q + 1);
    if (end == std::string_view::npos) continue;
    return trim(tag.substr(q + 1, end - q - 1));
  }
  const std::size_t id_open = body.find("<Id>");
  if (id_open != std::string_view::npos) {
    const std::size_t id_close = body.find("</Id>", id_open);
    if (id_close != std::string_view::npos) {
      return trim(body.substr(id_open + 4, id_close - id_open - 4));
    }
  }
  return "any";
}

// Cyclone applies a <Domain> whose id differs from the domain being created
// by ignoring it silently and using its defaults (multicast on every
// interface). Refuse such a configuration instead.
Status check_domain_entries(const std::string& xml, std::uint32_t domain_id) {
  const std::string text = strip_comments(xml);
  std::vector<std::string> ids;
  std::size_t pos = 0;
  while ((pos = text.find("<Domain", pos)) != std::string::npos) {
    const std::size_t after = pos + 7;
    if (after < text.size() && text[after] != ' ' && text[after] != '>' && text[after] != '\t' && text[after] != '\n' &&
        text[after] != '\r' && text[after] != '/') {
      pos = after;  // <DomainTag> and the like
      continue;
    }
    const std::size_t tag_end = text.find('>', after);
    if (tag_end == std::string::npos) break;
    const std::size_t close = text.find("</Domain>", tag_end);
    const std::string_view tag(text.data() + pos, tag_end - pos);
    const std::string_view body(text.data() + tag_end, (close == std::string::npos ? text.size() : close) - tag_end);
    ids.push_back(domain_element_id(tag, body));
    pos = tag_end;
  }
  if (ids.empty()) return Status();
  std::string list;
  for (const std::string& id : ids) {
    if (id == "any" || id == std::to_string(domain_id)) return Status();
    list += (list.empty() ? "" : ", ") + id;
  }
  return invalid_argument("cyclone configuration: no <Domain> applies to domain " + std::to_string(domain_id) +
                          " (ids: " + list + "); Cyclone would ignore it and use its defaults");
}

}  // namespace

Result<std::string> read_cyclone_config(const std::string& path) {
  if (path.empty()) return invalid_argument("cyclone configuration: empty file name");
  Result<std::string> read = read_input_file(path, kMaxConfigBytes);
  if (!read.ok()) return Status(read.status().code(), "cyclone configuration " + read.status().message());
  std::string text = std::move(read).value();
  if (trim(text).empty()) return invalid_argument("cyclone configuration " + path + ": empty");
  if (trim(text).front() != '<') {
    return invalid_argument("cyclone configuration " + path + ": not XML (must start with '<')");
  }
  return text;
}

Status validate(const ParticipantConfig& config) {
  if (config.domain_id > kMaxDomainId) {
    return invalid_argument("domain id " + std::to_string(config.domain_id) + ": above " +
                            std::to_string(kMaxDomainId) + " (Cyclone's port mapping)");
  }
  const std::string xml = trim(config.cyclone_xml);
  if (xml.empty()) {
    return invalid_argument("cyclone configuration: empty (pass the XML itself, e.g. loopback_config())");
  }
  if (xml.front() != '<') {
    return invalid_argument("cyclone configuration: not XML (must start with '<')");
  }
  VISVOL_RETURN_IF_ERROR(check_domain_entries(config.cyclone_xml, config.domain_id));
  return validate_namespace(config.topic_namespace);
}

Status dds_error(std::string_view what, dds_return_t rc) {
  const Errc code = rc == DDS_RETCODE_TIMEOUT            ? Errc::timeout
                    : rc == DDS_RETCODE_BAD_PARAMETER    ? Errc::invalid_argument
                    : rc == DDS_RETCODE_OUT_OF_RESOURCES ? Errc::resource
                                                         : Errc::io;
  return Status(code, std::string(what) + ": " + dds_strretcode(rc));
}

bool sets_max_sample_size(const std::string& xml) {
  std::string text = xml;
  for (std::size_t open = text.find("<!--"); open != std::string::npos; open = text.find("<!--", open)) {
    const std::size_t close = text.find("-->", open + 4);
    text.erase(open, close == std::string::npos ? std::string::npos : close + 3 - open);
  }
  return text.find("<MaxSampleSize") != std::string::npos;
}

// visvol's own samples stay well under the limit (a PathVertex is under
// 64 bytes serialised)
static_assert(4 * msg::kMaxThumbnailBytes <= kMaxSampleBytes, "a thumbnail fits the sample limit");
static_assert(4 * 64 * msg::kMaxPathVertices <= kMaxSampleBytes, "a path fits the sample limit");

Result<std::unique_ptr<Participant>> Participant::create(const ParticipantConfig& config) {
  VISVOL_RETURN_IF_ERROR(validate(config));
  const std::uint32_t id = config.domain_id;
  std::lock_guard<std::mutex> lock(registry_mutex());
  auto& domains = registry();
  auto it = domains.find(id);
  bool created = false;
  if (it == domains.end()) {
    install_dds_log_limit();  // before the domain: its configuration problems come through it too
    // Cyclone merges a list of fragments in order; a configuration that sets
    // its own limit keeps it (the operator's choice, larger or smaller)
    const std::string merged = sets_max_sample_size(config.cyclone_xml)
                                   ? config.cyclone_xml
                                   : config.cyclone_xml + ",<CycloneDDS><Domain Id=\"any\"><Internal><MaxSampleSize>" +
                                         std::to_string(kMaxSampleBytes) +
                                         "B</MaxSampleSize></Internal></Domain></CycloneDDS>";
    const dds_entity_t domain = dds_create_domain(id, merged.c_str());
    if (domain == DDS_RETCODE_PRECONDITION_NOT_MET) {
      return Status(Errc::state, "DDS domain " + std::to_string(id) +
                                     " already exists in this process, created outside "
                                     "visvol (with a configuration visvol cannot check)");
    }
    if (domain < 0) {
      return dds_error(
          "creating DDS domain " + std::to_string(id) + " (Cyclone prints the configuration problem above)", domain);
    }
    it = domains.emplace(id, DomainUse{domain, config.cyclone_xml, 0}).first;
    created = true;
  } else if (it->second.xml != config.cyclone_xml) {
    return Status(Errc::state, "DDS domain " + std::to_string(id) +
                                   " already runs in this process with another "
                                   "Cyclone configuration");
  }
  const dds_entity_t participant = dds_create_participant(id, nullptr, nullptr);
  if (participant < 0) {
    if (created) {
      dds_delete(it->second.domain);
      domains.erase(it);
    }
    return dds_error("creating DDS participant on domain " + std::to_string(id), participant);
  }
  ++it->second.participants;
  std::string ns = config.topic_namespace;
  if (!ns.empty() && ns.front() == '/') ns.erase(0, 1);
  return std::unique_ptr<Participant>(new Participant(participant, id, std::move(ns)));
}

Participant::Participant(dds_entity_t participant, std::uint32_t domain_id, std::string ns)
    : participant_(participant), domain_id_(domain_id), namespace_(std::move(ns)) {}

Participant::~Participant() {
  std::lock_guard<std::mutex> lock(registry_mutex());
  dds_delete(participant_);
  auto& domains = registry();
  const auto it = domains.find(domain_id_);
  if (it != domains.end() && --it->second.participants == 0) {
    dds_delete(it->second.domain);
    domains.erase(it);
  }
}

std::string Participant::topic_name(Topic topic) const { return dds::topic_name(namespace_, topic); }

// Writer ---------------------------------------------------------------------

namespace {

Result<dds_entity_t> create_topic(const Participant& participant, Topic topic) {
  const std::string name = participant.topic_name(topic);
  const dds_entity_t t = dds_create_topic(participant.handle(), &descriptor(topic), name.c_str(), nullptr, nullptr);
  if (t < 0) return dds_error("creating topic " + name, t);
  return t;
}

// Polls a matched count until it reaches `count`; discovery on loopback takes
// milliseconds, so a 5 ms step costs little.
template <typename Count>
Status wait_for_count(Count&& current, std::uint32_t count, double timeout_s, const std::string& what) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::nanoseconds(to_duration(timeout_s));
  while (current() < count) {
    if (std::chrono::steady_clock::now() >= deadline) {
      return Status(Errc::timeout, what + ": " + std::to_string(current()) + " of " + std::to_string(count) +
                                       " matched after " + std::to_string(timeout_s) + " s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return Status();
}

}  // namespace

Result<Writer> Writer::create(const Participant& participant, Topic topic) {
  Result<dds_entity_t> t = create_topic(participant, topic);
  if (!t.ok()) return t.status();
  const QosPtr qos = writer_qos(topic);
  const dds_entity_t w = dds_create_writer(participant.handle(), *t, qos.get(), nullptr);
  if (w < 0) {
    dds_delete(*t);
    return dds_error("creating writer of " + participant.topic_name(topic), w);
  }
  return Writer(w, *t, topic);
}

void Writer::reset() {
  // The writer first: a topic cannot go while an endpoint uses it.
  if (writer_ > 0) dds_delete(writer_);
  if (topic_entity_ > 0) dds_delete(topic_entity_);
  writer_ = 0;
  topic_entity_ = 0;
}
Writer::~Writer() { reset(); }
Writer::Writer(Writer&& other) noexcept
    : writer_(std::exchange(other.writer_, 0)),
      topic_entity_(std::exchange(other.topic_entity_, 0)),
      topic_(other.topic_) {}
Writer& Writer::operator=(Writer&& other) noexcept {
  if (this != &other) {
    reset();
    writer_ = std::exchange(other.writer_, 0);
    topic_entity_ = std::exchange(other.topic_entity_, 0);
    topic_ = other.topic_;
  }
  return *this;
}

dds_return_t Writer::write(const void* sample) const { return dds_write(writer_, sample); }

std::uint32_t Writer::matched_readers() const {
  dds_publication_matched_status_t status{};
  if (dds_get_publication_matched_status(writer_, &status) < 0) return 0;
  return status.current_count;
}

Status Writer::wait_for_readers(std::uint32_t count, double timeout_s) const {
  return wait_for_count([this] { return matched_readers(); }, count, timeout_s, "waiting for subscribers");
}

dds_return_t Writer::wait_for_acks(double timeout_s) const {
  return dds_wait_for_acks(writer_, to_duration(timeout_s));
}

// Reader ---------------------------------------------------------------------

Result<Reader> Reader::create(const Participant& participant, Topic topic) {
  const QosPtr qos = reader_qos(topic);
  return create(participant, topic, qos.get());
}

Result<Reader> Reader::create(const Participant& participant, Topic topic, const dds_qos_t* qos) {
  Result<dds_entity_t> t = create_topic(participant, topic);
  if (!t.ok()) return t.status();
  const dds_entity_t r = dds_create_reader(participant.handle(), *t, qos, nullptr);
  if (r < 0) {
    dds_delete(*t);
    return dds_error("creating reader of " + participant.topic_name(topic), r);
  }
  Reader reader(r, *t, 0);
  // A read condition on any sample state: the waitset triggers while data waits.
  const dds_entity_t condition = dds_create_readcondition(r, DDS_ANY_STATE);
  if (condition < 0) return dds_error("creating read condition", condition);
  reader.waitset_ = dds_create_waitset(participant.handle());
  if (reader.waitset_ < 0) {
    const dds_return_t rc = reader.waitset_;
    reader.waitset_ = 0;
    return dds_error("creating waitset", rc);
  }
  const dds_return_t rc = dds_waitset_attach(reader.waitset_, condition, r);
  if (rc < 0) return dds_error("attaching waitset", rc);
  return reader;
}

void Reader::reset() {
  // Waitset, reader (with its read condition), then the topic.
  if (waitset_ > 0) dds_delete(waitset_);
  if (reader_ > 0) dds_delete(reader_);
  if (topic_entity_ > 0) dds_delete(topic_entity_);
  waitset_ = 0;
  reader_ = 0;
  topic_entity_ = 0;
}
Reader::~Reader() { reset(); }
Reader::Reader(Reader&& other) noexcept
    : reader_(std::exchange(other.reader_, 0)),
      topic_entity_(std::exchange(other.topic_entity_, 0)),
      waitset_(std::exchange(other.waitset_, 0)) {}
Reader& Reader::operator=(Reader&& other) noexcept {
  if (this != &other) {
    reset();
    reader_ = std::exchange(other.reader_, 0);
    topic_entity_ = std::exchange(other.topic_entity_, 0);
    waitset_ = std::exchange(other.waitset_, 0);
  }
  return *this;
}

Result<bool> Reader::wait(double timeout_s) const {
  const dds_return_t n = dds_waitset_wait(waitset_, nullptr, 0, to_duration(timeout_s));
  if (n < 0) return dds_error("waiting for data", n);
  return n > 0;
}

dds_return_t Reader::take_loaned(void** samples, dds_sample_info_t* infos, std::uint32_t max) const {
  return dds_take(reader_, samples, infos, max, max);
}

void Reader::return_loan(void** samples, int count) const {
  if (count > 0) dds_return_loan(reader_, samples, count);
}

Result<std::vector<std::uint8_t>> Reader::take_serialized() const {
  struct ddsi_serdata* data = nullptr;
  dds_sample_info_t info;
  const dds_return_t n = dds_takecdr(reader_, &data, 1, &info, DDS_ANY_STATE);
  if (n < 0) return dds_error("take (serialised)", n);
  std::vector<std::uint8_t> bytes;
  if (n == 0) return bytes;
  if (info.valid_data) {
    bytes.resize(ddsi_serdata_size(data));
    ddsi_serdata_to_ser(data, 0, bytes.size(), bytes.data());
  }
  ddsi_serdata_unref(data);
  return bytes;
}

std::uint32_t Reader::matched_writers() const {
  dds_subscription_matched_status_t status{};
  if (dds_get_subscription_matched_status(reader_, &status) < 0) return 0;
  return status.current_count;
}

Status Reader::wait_for_writers(std::uint32_t count, double timeout_s) const {
  return wait_for_count([this] { return matched_writers(); }, count, timeout_s, "waiting for publishers");
}

}  // namespace visvol::dds

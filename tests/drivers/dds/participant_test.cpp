// Participants, configuration and topic names with real Cyclone participants
// (domain 211, loopback).
#include <unistd.h>

#include <dds/ddsrt/log.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "dds_test_support.hpp"
#include "drivers/dds/log_limit.hpp"
#include "drivers/dds/participant.hpp"
#include "drivers/dds/topics.hpp"
#include "test_domains.hpp"

namespace visvol::dds {
namespace {

using test::loopback;
using test::make_participant;
constexpr std::uint32_t kDomain = test::kDomainParticipant;

// Configuration ----------------------------------------------------------------

TEST(ParticipantConfig, ShippedFileIsTheCompiledInConfiguration) {
  Result<std::string> file = read_cyclone_config(VISVOL_DDS_LOOPBACK_XML);
  ASSERT_TRUE(file.ok()) << file.status().message();
  EXPECT_EQ(*file, std::string(loopback_config()));
  const std::string xml(loopback_config());
  EXPECT_NE(xml.find("<NetworkInterface name=\"lo\" multicast=\"false\"/>"), std::string::npos);
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(xml.find("<Peer address=\"127.0.0.1\"/>"), std::string::npos);
}

TEST(ParticipantConfig, RejectsBadValuesWithReasons) {
  ParticipantConfig c = loopback(kDomain);
  EXPECT_TRUE(validate(c).ok());

  c.domain_id = 233;
  Status s = validate(c);
  EXPECT_EQ(s.code(), Errc::invalid_argument);
  EXPECT_NE(s.message().find("domain id 233"), std::string::npos) << s.message();

  c = loopback(kDomain);
  c.cyclone_xml = "  ";
  EXPECT_NE(validate(c).message().find("empty"), std::string::npos);
  c.cyclone_xml = "file:///etc/cyclone.xml";
  EXPECT_NE(validate(c).message().find("not XML"), std::string::npos);

  // Cyclone would silently fall back to its defaults (multicast everywhere).
  c.cyclone_xml = "<CycloneDDS><Domain Id=\"7\"><General/></Domain></CycloneDDS>";
  s = validate(c);
  EXPECT_NE(s.message().find("no <Domain> applies to domain 211 (ids: 7)"), std::string::npos) << s.message();
  c.cyclone_xml = "<CycloneDDS><Domain><Id>7</Id></Domain></CycloneDDS>";
  EXPECT_FALSE(validate(c).ok());
  c.cyclone_xml = "<CycloneDDS><Domain Id=\"7\"/><Domain Id=\"211\"/></CycloneDDS>";
  EXPECT_TRUE(validate(c).ok());
  c.cyclone_xml = "<CycloneDDS><!-- <Domain Id=\"7\"> --><Domain><DomainTag/></Domain></CycloneDDS>";
  EXPECT_TRUE(validate(c).ok());

  c = loopback(kDomain, "bad//ns");
  EXPECT_NE(validate(c).message().find("empty segment"), std::string::npos);
  c = loopback(kDomain, "9lives");
  EXPECT_NE(validate(c).message().find("character 1"), std::string::npos);
  c = loopback(kDomain, "/console_a/left");
  EXPECT_TRUE(validate(c).ok());
}

// A configuration's own sample limit is kept; one that names it only in a
// comment gets visvol's (8 million constraints got through such a one).
TEST(ParticipantConfig, OnlyAnElementSetsTheSampleLimit) {
  EXPECT_FALSE(sets_max_sample_size(std::string(loopback_config())));
  EXPECT_TRUE(sets_max_sample_size("<CycloneDDS><Domain><Internal><MaxSampleSize>8MiB</MaxSampleSize></Internal>"));
  EXPECT_FALSE(sets_max_sample_size("<CycloneDDS><!-- Cyclone's default MaxSampleSize --><Domain/></CycloneDDS>"));
  EXPECT_FALSE(sets_max_sample_size("<CycloneDDS><!-- <MaxSampleSize>8MiB</MaxSampleSize> --></CycloneDDS>"));
  EXPECT_FALSE(sets_max_sample_size("<CycloneDDS><!-- never closed <MaxSampleSize>"));
}

TEST(ParticipantConfig, ReadErrorsNameTheFile) {
  Result<std::string> r = read_cyclone_config("/nonexistent/cyclone.xml");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("/nonexistent/cyclone.xml"), std::string::npos);
  // a device is refused without reading it (a FIFO would block for ever)
  r = read_cyclone_config("/dev/null");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("/dev/null: is a character device, not a regular file"), std::string::npos)
      << r.status().message();
  const std::string empty = ::testing::TempDir() + "/participant_test_empty.xml";
  std::ofstream{empty};
  r = read_cyclone_config(empty);
  std::remove(empty.c_str());
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("empty"), std::string::npos);
}

TEST(Topics, NamesFollowRos2) {
  EXPECT_EQ(topic_name("", Topic::path), "rt/visvol/path");
  EXPECT_EQ(topic_name("/console_a", Topic::thumbnail), "rt/console_a/visvol/thumbnail/compressed");
  EXPECT_STREQ(type_name(Topic::path), "nav_msgs::msg::dds_::Path_");
  EXPECT_STREQ(type_name(Topic::thumbnail), "sensor_msgs::msg::dds_::CompressedImage_");
  EXPECT_STREQ(type_name(Topic::command), "visvol_msgs::msg::dds_::Command_");
}

// Participants -----------------------------------------------------------------

TEST(Participant, IgnoresCycloneddsUriFromTheEnvironment) {
  // Were Cyclone to read this, creating the domain would fail.
  ASSERT_EQ(::setenv("CYCLONEDDS_URI", "<CycloneDDS><Broken", 1), 0);
  auto p = make_participant(loopback(kDomain));
  ::unsetenv("CYCLONEDDS_URI");
  ASSERT_NE(p, nullptr);
  EXPECT_GT(p->handle(), 0);
}

TEST(Participant, LoopbackConfigurationKeepsEveryAddressOn127) {
  // Cyclone's own account of what it chose, traced to a file of this test.
  char path[] = "/tmp/visvol_dds_trace_XXXXXX";
  const int fd = ::mkstemp(path);
  ASSERT_GE(fd, 0);
  ::close(fd);
  ParticipantConfig c = loopback(kDomain);
  c.cyclone_xml += std::string("<CycloneDDS><Domain Id=\"any\"><Tracing><Verbosity>config") +
                   "</Verbosity><OutputFile>" + path + "</OutputFile></Tracing></Domain>" + "</CycloneDDS>";
  {
    auto p = make_participant(c);
    ASSERT_NE(p, nullptr);
  }
  std::stringstream text;
  text << std::ifstream(path).rdbuf();
  const std::string trace = text.str();
  ::unlink(path);
  ASSERT_FALSE(trace.empty());
  EXPECT_NE(trace.find("selected interfaces: lo "), std::string::npos) << trace;
  EXPECT_NE(trace.find("AllowMulticast/#text: false"), std::string::npos);
  // every peer address Cyclone sends discovery to is 127.0.0.1
  std::size_t peers = 0;
  for (std::size_t at = trace.find("add_peer_addresses:"); at != std::string::npos;
       at = trace.find("add_peer_addresses:", at + 1)) {
    const std::string line = trace.substr(at, trace.find('\n', at) - at);
    for (std::size_t u = line.find("udp/"); u != std::string::npos; u = line.find("udp/", u + 1)) {
      EXPECT_EQ(line.compare(u, 14, "udp/127.0.0.1:"), 0) << line;
      ++peers;
    }
  }
  EXPECT_GT(peers, 0u) << trace;
}

TEST(Participant, OneConfigurationPerDomainPerProcess) {
  auto a = make_participant(loopback(kDomain));
  ASSERT_NE(a, nullptr);
  auto b = make_participant(loopback(kDomain));  // same configuration: shares it
  ASSERT_NE(b, nullptr);
  ParticipantConfig other = loopback(kDomain);
  other.cyclone_xml += "<!-- another -->";
  Result<std::unique_ptr<Participant>> c = Participant::create(other);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.status().code(), Errc::state);
  EXPECT_NE(c.status().message().find("another Cyclone configuration"), std::string::npos);
}

TEST(Participant, BadXmlFailsCleanly) {
  ParticipantConfig c = loopback(kDomain);
  c.cyclone_xml =
      "<CycloneDDS><Domain Id=\"any\"><General><NoSuchSetting>1</NoSuchSetting>"
      "</General></Domain></CycloneDDS>";
  const DdsLogCounts before = dds_log_counts();
  ::testing::internal::CaptureStderr();
  Result<std::unique_ptr<Participant>> p = Participant::create(c);
  const std::string said = ::testing::internal::GetCapturedStderr();
  ASSERT_FALSE(p.ok());
  // Cyclone names the problem on stderr, through visvol's limiter
  EXPECT_NE(said.find("NoSuchSetting"), std::string::npos) << said;
  EXPECT_GT(dds_log_counts().shown, before.shown);
  EXPECT_NE(p.status().message().find("creating DDS domain 211"), std::string::npos) << p.status().message();
  // The failure leaves nothing behind: a good configuration works afterwards.
  EXPECT_NE(make_participant(loopback(kDomain)), nullptr);
}

// Cyclone's warnings pass 20 at once, then one each 10 s (the burst
// refilling at that rate), each after a gap saying how many were left out (a
// peer's oversize samples are a warning each: a flood filled the log).
TEST(DdsLog, WarningsPassABurstThenOneEachQuietPeriod) {
  LogLimiter limit(3, 10.0);
  std::uint64_t left_out = 99;
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(limit.admit(0.001 * k, left_out)) << k;
    EXPECT_EQ(left_out, 0u);
  }
  for (int k = 0; k < 500; ++k) EXPECT_FALSE(limit.admit(0.01 + 0.01 * k, left_out)) << k;
  EXPECT_EQ(limit.pending(), 500u);
  EXPECT_FALSE(limit.admit(9.9, left_out));  // a line's worth refills 10 s after the burst went
  EXPECT_TRUE(limit.admit(10.01, left_out));
  EXPECT_EQ(left_out, 501u);
  EXPECT_EQ(limit.pending(), 0u);
  EXPECT_FALSE(limit.admit(15.0, left_out));
  EXPECT_TRUE(limit.admit(20.5, left_out));
  EXPECT_EQ(left_out, 1u);
  // a quiet spell refills the burst, no more
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(limit.admit(1000.0 + 0.001 * k, left_out)) << k;
  EXPECT_FALSE(limit.admit(1000.1, left_out));
}

// Errors pass whatever warnings came before: a configuration problem is said
// after a flood of warnings, of which the sink showed a burst at most (with
// errors limited as warnings, the 21st run of Participant.BadXmlFailsCleanly
// in one process said nothing).
TEST(DdsLog, ErrorsPassAfterAFloodOfWarnings) {
  ASSERT_NE(make_participant(loopback(kDomain)), nullptr);  // the limiter in place
  const DdsLogCounts before = dds_log_counts();
  ::testing::internal::CaptureStderr();
  for (int k = 0; k < 3 * kLogBurst; ++k) {
    dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "visvol test: flood line %d\n", k);
  }
  const std::string flood = ::testing::internal::GetCapturedStderr();
  int shown = 0;
  for (std::size_t at = flood.find("flood line"); at != std::string::npos; at = flood.find("flood line", at + 1)) {
    ++shown;
  }
  EXPECT_GE(shown, 1);
  EXPECT_LE(shown, kLogBurst);
  EXPECT_GE(dds_log_counts().left_out - before.left_out, static_cast<std::uint64_t>(2 * kLogBurst));
  ParticipantConfig c = loopback(kDomain);
  c.cyclone_xml =
      "<CycloneDDS><Domain Id=\"any\"><General><AlsoNoSuchSetting>1</AlsoNoSuchSetting>"
      "</General></Domain></CycloneDDS>";
  ::testing::internal::CaptureStderr();
  const Result<std::unique_ptr<Participant>> bad = Participant::create(c);
  const std::string said = ::testing::internal::GetCapturedStderr();
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(said.find("Cyclone DDS: "), std::string::npos) << said;
  EXPECT_NE(said.find("AlsoNoSuchSetting"), std::string::npos) << said;
}

}  // namespace
}  // namespace visvol::dds

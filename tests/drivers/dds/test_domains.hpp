// DDS domain ids of the test binaries: one per binary, so that binaries run
// at once (ctest -j, another suite) never see each other's traffic. Every
// test also puts its topics under a namespace of its own process
// ("t<pid>", see dds_test_support.hpp), which keeps two runs of one binary
// (two build trees at once) apart as well. All of them use the loopback
// configuration: no packet leaves 127.0.0.1.
//
//   211  dds_participant_test     participants, configuration
//   212  dds_path_publisher_test  path publisher, the bytes on the wire
//   213  dds_live_publisher_test  the publisher thread
//   214  dds_command_intake_test  command intake in one process
//   215  dds_interprocess_test    a second process (dds_test_peer) on each side
//   216  dds_echo_test            visvol-echo against this process
//   219  visvol-dds-bench         tools/bench/dds (its default; --domain to change)
//
//   223, 224  app_console_dds_test    a console per case (one case at a time)
//   225, 226, 229  app_console_terrain_test  the same
//   227  app_console_threads_test a console under ThreadSanitizer
//   228  app_console_test         the console under a socket that plays systemd
//
// Other suites that use DDS: take ids outside 211..219 and 223..229.
#pragma once

#include <cstdint>

namespace visvol::dds::test {

inline constexpr std::uint32_t kDomainParticipant = 211;
inline constexpr std::uint32_t kDomainPathPublisher = 212;
inline constexpr std::uint32_t kDomainLivePublisher = 213;
inline constexpr std::uint32_t kDomainCommandIntake = 214;
inline constexpr std::uint32_t kDomainInterprocess = 215;
inline constexpr std::uint32_t kDomainEcho = 216;

}  // namespace visvol::dds::test

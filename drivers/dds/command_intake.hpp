// Command intake: a thread that takes commands from rt/visvol/command,
// validates them in full (command_processor.hpp), pushes the accepted ones
// into the real-time thread's CommandQueue and acknowledges every one on
// rt/visvol/command_ack: accepted, or rejected with a reason naming the field
// and the problem. A flood is rate-limited (rejected without decoding); a
// bad command never stops anything.
//
// The executive may report what became of a command by pushing
// CommandAck{applied or failed, reason} into the AckQueue (real-time safe);
// intake publishes those too, within ack_poll_interval_s.
//
// A sample that is not even valid CDR for Command_ is dropped by Cyclone
// before intake sees it, so it cannot be acknowledged.
//
// Ownership: the queues belong to the caller and must outlive the intake;
// intake is their producer (commands) and consumer (acks).
// Thread-safety: set_limits() and stats() from any thread; stop() from one.
// Cost: one thread; per command O(constraints), one dds_take share and one
// dds_write.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "base/status.hpp"
#include "drivers/dds/command_codec.hpp"
#include "drivers/dds/command_processor.hpp"
#include "drivers/dds/participant.hpp"

namespace visvol::dds {

struct IntakeConfig {
  CommandLimits limits;
  RateLimit rate;
  double ack_poll_interval_s = 0.01;  // how often the executive's acks are looked at
  std::string frame_id = kDefaultFrameId;
};

struct IntakeStats {
  CommandCounts commands;
  std::uint64_t executive_acks = 0;  // applied/failed acks published for the executive
  std::uint64_t ack_errors = 0;      // acknowledgements that could not be written
  std::uint64_t take_errors = 0;
};

class CommandIntake {
 public:
  // Validates the configuration, creates the reader and the ack writer, and
  // starts the thread. `executive_acks` may be null.
  static Result<std::unique_ptr<CommandIntake>> start(const Participant& participant, const IntakeConfig& config,
                                                      msg::CommandQueue& commands,
                                                      msg::AckQueue* executive_acks = nullptr);
  ~CommandIntake();  // stop()
  CommandIntake(const CommandIntake&) = delete;
  CommandIntake& operator=(const CommandIntake&) = delete;

  // New limits (after a terrain switch): commands from now on are validated
  // against them. Keeps the old ones and says why when they are not valid.
  Status set_limits(const CommandLimits& limits);
  IntakeStats stats() const;
  // Command writers matched (senders the console can hear).
  std::uint32_t matched_senders() const { return reader_.matched_writers(); }
  void stop();

 private:
  CommandIntake(const IntakeConfig& config, const CommandProcessor& processor, Reader reader, Writer ack_writer,
                msg::CommandQueue& commands, msg::AckQueue* executive_acks);
  void run();
  void handle_commands();
  void publish_executive_acks();
  void write_ack(const msg::CommandAck& ack);

  const IntakeConfig config_;
  msg::CommandQueue& commands_;
  msg::AckQueue* const executive_acks_;
  Reader reader_;
  Writer ack_writer_;
  AckMessage ack_msg_;  // intake thread only

  mutable std::mutex mutex_;  // guards processor_ and the counters below
  CommandProcessor processor_;
  std::uint64_t executive_ack_count_ = 0;
  std::uint64_t ack_errors_ = 0;
  std::uint64_t take_errors_ = 0;

  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace visvol::dds

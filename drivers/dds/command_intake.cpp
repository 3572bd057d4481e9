#include "drivers/dds/command_intake.hpp"

#include <pthread.h>

#include <chrono>
#include <cmath>
#include <utility>

namespace visvol::dds {
namespace {

double monotonic_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

Result<std::unique_ptr<CommandIntake>> CommandIntake::start(const Participant& participant, const IntakeConfig& config,
                                                            msg::CommandQueue& commands,
                                                            msg::AckQueue* executive_acks) {
  if (!std::isfinite(config.ack_poll_interval_s) || config.ack_poll_interval_s < 0.001 ||
      config.ack_poll_interval_s > 1.0) {
    return invalid_argument("command intake: ack_poll_interval_s must lie in [0.001, 1] s");
  }
  if (config.frame_id.empty()) return invalid_argument("command intake: empty frame id");
  Result<CommandProcessor> processor = CommandProcessor::create(config.limits, config.rate);
  if (!processor.ok()) return processor.status();
  Result<Reader> reader = Reader::create(participant, Topic::command);
  if (!reader.ok()) return reader.status();
  Result<Writer> writer = Writer::create(participant, Topic::command_ack);
  if (!writer.ok()) return writer.status();
  std::unique_ptr<CommandIntake> intake(
      new CommandIntake(config, *processor, std::move(*reader), std::move(*writer), commands, executive_acks));
  intake->thread_ = std::thread([raw = intake.get()] { raw->run(); });
  return intake;
}

CommandIntake::CommandIntake(const IntakeConfig& config, const CommandProcessor& processor, Reader reader,
                             Writer ack_writer, msg::CommandQueue& commands, msg::AckQueue* executive_acks)
    : config_(config),
      commands_(commands),
      executive_acks_(executive_acks),
      reader_(std::move(reader)),
      ack_writer_(std::move(ack_writer)),
      ack_msg_(config.frame_id),
      processor_(processor) {}

CommandIntake::~CommandIntake() { stop(); }

void CommandIntake::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

Status CommandIntake::set_limits(const CommandLimits& limits) {
  std::lock_guard<std::mutex> lock(mutex_);
  return processor_.set_limits(limits).with_context("command intake");
}

IntakeStats CommandIntake::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  IntakeStats s;
  s.commands = processor_.counts();
  s.executive_acks = executive_ack_count_;
  s.ack_errors = ack_errors_;
  s.take_errors = take_errors_;
  return s;
}

void CommandIntake::run() {
  pthread_setname_np(pthread_self(), "visvol-dds-cmd");
  while (!stop_.load(std::memory_order_acquire)) {
    // wait for commands, but no longer than the executive's acks may wait
    const Result<bool> ready = reader_.wait(config_.ack_poll_interval_s);
    if (!ready.ok()) {
      // never spin on a failing waitset
      std::this_thread::sleep_for(std::chrono::duration<double>(config_.ack_poll_interval_s));
    } else if (*ready) {
      handle_commands();
    }
    publish_executive_acks();
  }
  // what arrived before stop still gets its answer
  handle_commands();
  publish_executive_acks();
}

void CommandIntake::handle_commands() {
  for (;;) {
    const Result<int> taken = reader_.take<visvol_msgs_msg_dds__Command_>(
        [this](const visvol_msgs_msg_dds__Command_& wire, const dds_sample_info_t&) {
          msg::CommandAck ack;
          {
            std::lock_guard<std::mutex> lock(mutex_);
            processor_.process(wire, monotonic_s(), commands_, ack);
          }
          write_ack(ack);
        });
    if (!taken.ok()) {
      std::lock_guard<std::mutex> lock(mutex_);
      ++take_errors_;
      return;
    }
    if (*taken == 0) return;
  }
}

void CommandIntake::publish_executive_acks() {
  if (!executive_acks_) return;
  msg::CommandAck ack;
  while (executive_acks_->try_pop(ack)) {
    write_ack(ack);
    std::lock_guard<std::mutex> lock(mutex_);
    ++executive_ack_count_;
  }
}

void CommandIntake::write_ack(const msg::CommandAck& ack) {
  const dds_return_t rc = ack_writer_.write(&ack_msg_.fill(ack));
  if (rc < 0) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++ack_errors_;
  }
}

}  // namespace visvol::dds

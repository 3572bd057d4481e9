#include "msg/samples.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <initializer_list>
#include <memory>
#include <set>
#include <string>

namespace visvol::msg {
namespace {

TEST(CopyText, FitsAndIsAlwaysTerminated) {
  char reason[8];
  EXPECT_TRUE(copy_text(reason, "applied"));  // 7 characters and the NUL
  EXPECT_EQ(text_of(reason), "applied");
  EXPECT_FALSE(copy_text(reason, "rejected: too long"));  // truncated, and says so
  EXPECT_EQ(text_of(reason), "rejecte");
  EXPECT_TRUE(copy_text(reason, ""));
  EXPECT_EQ(text_of(reason), "");
}

TEST(TextOf, StopsAtTheFirstNulOrTheArraysEnd) {
  const char unterminated[4] = {'a', 'b', 'c', 'd'};  // as a hostile sample may hold
  EXPECT_EQ(text_of(unterminated), "abcd");
  const char early[6] = {'p', 'k', '\0', 'x', 'y', 'z'};
  EXPECT_EQ(text_of(early), "pk");
}

// Every value of an enum named, and no two alike.
template <typename E>
void expect_named_once(std::initializer_list<E> values) {
  std::set<std::string> names;
  for (E v : values) {
    ASSERT_NE(to_string(v), nullptr) << static_cast<int>(v);
    EXPECT_TRUE(names.insert(to_string(v)).second) << to_string(v) << " names two values";
  }
}

// The names the command line, the echo tool and the logs use: one per value,
// none missing, none shared.
TEST(ToString, NamesEveryValueOnce) {
  expect_named_once({CommandKind::set_endpoints, CommandKind::set_objective, CommandKind::set_weights,
                     CommandKind::set_stiffness, CommandKind::set_model, CommandKind::set_segment_count,
                     CommandKind::set_constraints, CommandKind::start, CommandKind::stop, CommandKind::switch_terrain,
                     CommandKind::set_mode});
  expect_named_once({InteractionMode::pull, InteractionMode::spool});
  EXPECT_STREQ(to_string(CommandKind::set_mode), "set-mode");
  EXPECT_STREQ(to_string(InteractionMode::spool), "spool");
  expect_named_once({Objective::hide, Objective::show});
  expect_named_once({RopeModel::spring_mass, RopeModel::articulated});
  expect_named_once({ConstraintKind::hidden_from, ConstraintKind::visible_to, ConstraintKind::clearance,
                     ConstraintKind::max_agl, ConstraintKind::max_altitude});
  expect_named_once({AckResult::accepted, AckResult::rejected, AckResult::applied, AckResult::failed});
  expect_named_once(
      {DeviceState::unknown, DeviceState::disconnected, DeviceState::idle, DeviceState::active, DeviceState::fault});
  EXPECT_STREQ(to_string(CommandKind::set_segment_count), "set-segments");
  EXPECT_STREQ(to_string(CommandKind::switch_terrain), "switch-terrain");
  EXPECT_STREQ(to_string(Objective::show), "show");
  EXPECT_STREQ(to_string(RopeModel::spring_mass), "spring");
  EXPECT_STREQ(to_string(ConstraintKind::hidden_from), "hidden-from");
  EXPECT_STREQ(to_string(ConstraintKind::visible_to), "visible-to");
  EXPECT_STREQ(to_string(AckResult::failed), "failed");
  EXPECT_STREQ(to_string(DeviceState::fault), "fault");
  // a value off the wire that no enumerator names
  EXPECT_EQ(to_string(static_cast<CommandKind>(200)), nullptr);
}

TEST(NowStamp, IsUnixEpochNanoseconds) {
  const auto before =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  const std::int64_t stamp = now_stamp_ns();
  const auto after =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  EXPECT_GE(stamp, before - 1000000);  // the same clock, within a millisecond
  EXPECT_LE(stamp, after + 1000000);
}

// Commands travel to the real-time thread in a queue reserved once: it holds
// its capacity and refuses the next without blocking.
TEST(CommandQueue, HoldsItsCapacityAndRefusesMore) {
  auto queue = std::make_unique<CommandQueue>();
  Command c{};
  std::size_t pushed = 0;
  for (std::size_t i = 0; i < kCommandQueueCapacity + 4; ++i) {
    c.sequence = i;
    if (queue->try_push(c)) ++pushed;
  }
  EXPECT_EQ(pushed, kCommandQueueCapacity);
  Command out{};
  ASSERT_TRUE(queue->try_pop(out));
  EXPECT_EQ(out.sequence, 0u);  // first in, first out
}

}  // namespace
}  // namespace visvol::msg

// The console's log lines: sd-daemon priority prefixes on every line when
// standard error is the journal, plain lines otherwise.
#include "app/log.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace visvol::app {
namespace {

TEST(Log, JournalLinesCarryTheirPriorityOnEveryLine) {
  EXPECT_EQ(log_text(LogLevel::error, "visvol-console: no pack", true), "<3>visvol-console: no pack\n");
  EXPECT_EQ(log_text(LogLevel::warning, "w\n", true), "<4>w\n");
  EXPECT_EQ(log_text(LogLevel::info, "table:\n  a 1\n  b 2\n", true), "<6>table:\n<6>  a 1\n<6>  b 2\n");
  EXPECT_EQ(log_text(LogLevel::info, "table:\n  a 1\n", false), "table:\n  a 1\n") << "plain off the journal";
  EXPECT_EQ(log_text(LogLevel::info, "", true), "");
}

// JOURNAL_STREAM names standard error's device and inode when systemd
// connected it to the journal; anything else is not the journal.
TEST(Log, TheJournalIsRecognisedByStandardErrorsDeviceAndInode) {
  struct stat st {};
  ASSERT_EQ(::fstat(STDERR_FILENO, &st), 0);
  const std::string mine = std::to_string(static_cast<unsigned long long>(st.st_dev)) + ":" + std::to_string(st.st_ino);
  ::unsetenv("JOURNAL_STREAM");
  EXPECT_FALSE(stderr_is_journal());
  ::setenv("JOURNAL_STREAM", mine.c_str(), 1);
  EXPECT_TRUE(stderr_is_journal());
  ::setenv("JOURNAL_STREAM", (mine + "1").c_str(), 1);
  EXPECT_FALSE(stderr_is_journal()) << "another inode";
  ::setenv("JOURNAL_STREAM", "garbage", 1);
  EXPECT_FALSE(stderr_is_journal());
  ::unsetenv("JOURNAL_STREAM");
}

}  // namespace
}  // namespace visvol::app

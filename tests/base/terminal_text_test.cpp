#include "base/terminal_text.hpp"

#include <gtest/gtest.h>

namespace visvol {
namespace {

TEST(TerminalText, ControlCharactersAreShownNotSent) {
  // an OSC title sequence and a colour, as a crafted pack's CRS name held them
  EXPECT_EQ(terminal_safe("a\x1b]0;PWN\x07z\x1b[31m"), "a\\x1B]0;PWN\\x07z\\x1B[31m");
  EXPECT_EQ(terminal_safe(std::string("nul\0here", 8)), "nul\\x00here");
  EXPECT_EQ(terminal_safe("del\x7f"), "del\\x7F");
  // U+009B, CSI in C1, as UTF-8: a terminal acts on it
  EXPECT_EQ(terminal_safe("c1\xc2\x9b"
                          "31m"),
            "c1\\xC2\\x9B31m");
  // a lone byte of no character: 0x9B is CSI to an 8-bit terminal
  EXPECT_EQ(terminal_safe("lone\x9b"
                          "31m"),
            "lone\\x9B31m");
  EXPECT_EQ(terminal_safe("cut\xc3"), "cut\\xC3");
  // an overlong CSI (E0 82 9B) and a surrogate are no characters either
  EXPECT_EQ(terminal_safe("\xe0\x82\x9b"), "\\xE0\\x82\\x9B");
  EXPECT_EQ(terminal_safe("\xed\xa0\x80"), "\\xED\\xA0\\x80");
  EXPECT_EQ(terminal_safe("\xe2\x82\xac"), "\xe2\x82\xac");  // the euro sign stays
}

TEST(TerminalText, LinesAndOtherUtf8Stay) {
  EXPECT_EQ(terminal_safe("two\nlines"), "two\nlines");
  EXPECT_EQ(terminal_safe("Zürich \xc4\x89 \xc2\xa0"), "Zürich \xc4\x89 \xc2\xa0");  // 0x89 as a continuation byte
}

TEST(TerminalText, ALongTokenIsCutAndItsLengthSaid) {
  const std::string big(8 << 20, 'x');
  const std::string shown = terminal_safe(big, 100);
  EXPECT_EQ(shown, std::string(100, 'x') + "... (8388608 bytes)");
  EXPECT_EQ(terminal_safe("short", 100), "short");
  // not inside a character: "ü" is two bytes, the cut falls between them
  EXPECT_EQ(terminal_safe("aaü", 3), "aa... (4 bytes)");
}

}  // namespace
}  // namespace visvol

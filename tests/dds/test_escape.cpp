// escape_text: the one escaping function for peer-supplied strings (issue 15, Medium 9).
#include <gtest/gtest.h>

#include <string>

#include "usv_fdi/core/text.hpp"

namespace usvfdi {
namespace {

TEST(EscapeText, PlainTextAndUtf8PassUnchanged) {
  EXPECT_EQ(escape_text("alice (bridge) #3: J_N 14.08 > 12"), "alice (bridge) #3: J_N 14.08 > 12");
  EXPECT_EQ(escape_text("Ålesund skipper Øyvind, 10 °C, ∆t"), "Ålesund skipper Øyvind, 10 °C, ∆t");
  EXPECT_EQ(escape_text(""), "");
}

TEST(EscapeText, LineEndsControlsAndTheBackslashAreEscaped) {
  EXPECT_EQ(escape_text("a\nb"), "a\\nb");
  EXPECT_EQ(escape_text("a\rb\tc"), "a\\rb\\tc");
  EXPECT_EQ(escape_text("\x1b[2J"), "\\x1b[2J");
  EXPECT_EQ(escape_text(std::string("a\0b", 3)), "a\\x00b");
  EXPECT_EQ(escape_text("\x7f"), "\\x7f");
  // idempotent: the sidecar escapes an operator id, the monitor the message that quotes it
  EXPECT_EQ(escape_text(escape_text("a\nb\x1b\xc2\x9b")), escape_text("a\nb\x1b\xc2\x9b"));
  EXPECT_EQ(escape_text("a\\nb"), "a\\nb");
}

TEST(EscapeText, C1ControlsBidiOverridesAndInvalidUtf8AreEscaped) {
  EXPECT_EQ(escape_text("\xc2\x9b"
                        "2J"),
            "\\u{009b}2J");  // CSI as a C1 control
  EXPECT_EQ(escape_text("abc\xe2\x80\xae"
                        "cba"),
            "abc\\u{202e}cba");                           // right-to-left override
  EXPECT_EQ(escape_text("\xe2\x81\xa6x"), "\\u{2066}x");  // left-to-right isolate
  EXPECT_EQ(escape_text("\xff\xfe"), "\\xff\\xfe");
  EXPECT_EQ(escape_text("\xc3"), "\\xc3");                    // truncated sequence
  EXPECT_EQ(escape_text("\xc0\xaf"), "\\xc0\\xaf");           // overlong '/'
  EXPECT_EQ(escape_text("\xed\xa0\x80"), "\\xed\\xa0\\x80");  // a surrogate
}

TEST(EscapeText, NothingItReturnsContainsAControlByte) {
  std::string all;
  for (int c = 0; c < 256; ++c) all += static_cast<char>(c);
  const std::string e = escape_text(all);
  for (const char c : e) {
    const unsigned char u = static_cast<unsigned char>(c);
    EXPECT_TRUE(u >= 0x20 && u != 0x7f) << "byte " << static_cast<int>(u);
  }
}

}  // namespace
}  // namespace usvfdi

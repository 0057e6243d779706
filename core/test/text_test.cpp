#include "dreamsense/core/text.hpp"

#include <gtest/gtest.h>

namespace dreamsense {
namespace {

TEST(Utf8, AcceptsWellFormedText) {
  EXPECT_FALSE(find_invalid_utf8("plain ascii").has_value());
  EXPECT_FALSE(find_invalid_utf8("Zo\xC3\xAB, \xE2\x82\xAC 5, \xF0\x9F\x99\x82").has_value());
  EXPECT_FALSE(find_invalid_utf8("").has_value());
}

TEST(Utf8, FindsTheFirstMalformedByte) {
  EXPECT_EQ(find_invalid_utf8("ab\xFF"
                              "cd"),
            2u);                                         // never valid
  EXPECT_EQ(find_invalid_utf8("ab\xC3"), 2u);            // truncated sequence at the end
  EXPECT_EQ(find_invalid_utf8("\xC0\xAF"), 0u);          // overlong '/'
  EXPECT_EQ(find_invalid_utf8("x\xED\xA0\x80"), 1u);     // UTF-16 surrogate
  EXPECT_EQ(find_invalid_utf8("\xF4\x90\x80\x80"), 0u);  // above U+10FFFF
  EXPECT_EQ(find_invalid_utf8("ok\xE2\x82"
                              "A"),
            2u);  // bad continuation byte
}

TEST(Utf8, LineOfOffsetCountsNewlines) {
  const std::string_view t = "a\nb\nc";
  EXPECT_EQ(line_of_offset(t, 0), 1u);
  EXPECT_EQ(line_of_offset(t, 2), 2u);
  EXPECT_EQ(line_of_offset(t, 4), 3u);
  EXPECT_EQ(line_of_offset(t, 99), 3u);
}

}  // namespace
}  // namespace dreamsense

// Splitting test files into sections (TESTFORMAT.md §2).
#include "testing/sections.h"

#include <gtest/gtest.h>

namespace simit::tools {
namespace {

TEST(Sections, FileWithoutLeadingDelimiterIsOneSection) {
  auto s = split_sections("func f()\nend\n%%% not a split point here\n");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_FALSE(s[0].sectioned);
  EXPECT_EQ(s[0].name, "");
  EXPECT_EQ(s[0].line, 1);
  EXPECT_EQ(s[0].source, "func f()\nend\n%%% not a split point here\n");
}

TEST(Sections, LeadingBlankPreventsSplitting) {
  auto s = split_sections(" %%% a\n%%% b\n");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_FALSE(s[0].sectioned);
}

TEST(Sections, EmptyFileIsOneEmptySection) {
  auto s = split_sections("");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].source, "");
}

TEST(Sections, SplitsAtEveryDelimiterWithNamesAndLines) {
  auto s = split_sections("%%% first\na = 1;\n\n%%%second one  \nb\n%%%\nc\n");
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].name, "first");
  EXPECT_EQ(s[0].source, "%%% first\na = 1;\n\n");
  EXPECT_EQ(s[0].line, 1);
  EXPECT_EQ(s[1].name, "second one");
  EXPECT_EQ(s[1].line, 4);
  EXPECT_EQ(s[1].source, "%%%second one  \nb\n");
  EXPECT_EQ(s[2].name, "");
  EXPECT_EQ(s[2].line, 6);
  EXPECT_TRUE(s[2].sectioned);
}

TEST(Sections, NamesKeepSpacesAndPunctuation) {
  auto s = split_sections("%%%   empty loop (regression)\t\n");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "empty loop (regression)");
}

TEST(Sections, SplitsMidLineAndTracksTheColumn) {
  auto s = split_sections("%%% a\nx = 1; %%% b\ny\n");
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].source, "%%% a\nx = 1; ");
  EXPECT_EQ(s[1].name, "b");
  EXPECT_EQ(s[1].line, 2);
  EXPECT_EQ(s[1].column, 8);
  EXPECT_EQ(s[1].source, "%%% b\ny\n");
}

TEST(Sections, AdjacentDelimitersMakeNoEmptySection) {
  auto s = split_sections("%%%%%% name\nbody\n");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "name");
  EXPECT_EQ(s[0].source, "%%% name\nbody\n");
  EXPECT_EQ(s[0].column, 4);
}

TEST(Sections, DecorativeLineMakesExtraSections) {
  // Ten percent signs: delimiters at 0, 3 and 6 (the first two empty), then "%%%%".
  auto s = split_sections("%%%%%%%%%%\nx\n");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "%");
  EXPECT_EQ(s[0].source, "%%%%\nx\n");
}

TEST(Sections, TrailingDelimiterAloneIsDropped) {
  auto s = split_sections("%%% a\nx\n%%%");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "a");
}

TEST(Sections, DashRightAfterDelimiterDisables) {
  auto s = split_sections("%%%- off\nbroken(\n%%%-\n%%% -on\nok\n");
  ASSERT_EQ(s.size(), 3u);
  EXPECT_TRUE(s[0].disabled);
  EXPECT_TRUE(s[1].disabled);
  EXPECT_FALSE(s[2].disabled);
  EXPECT_EQ(s[2].name, "-on");
}

TEST(Sections, CommentOnlySectionsFromPrefixedBlock) {
  auto s = split_sections("%%% real\nf\n%%% %! twice(2) == 4;\n%%% func g()\n");
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[1].name, "%! twice(2) == 4;");
  EXPECT_EQ(s[1].source, "%%% %! twice(2) == 4;\n");
  EXPECT_EQ(s[1].line, 3);
  EXPECT_EQ(s[2].line, 4);
}

TEST(Sections, LineTrackingCountsCrLfAndLoneCr) {
  auto s = split_sections("%%% a\r\nx\r\n%%% b\ry\r%%% c\n");
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].line, 1);
  EXPECT_EQ(s[1].line, 3);
  EXPECT_EQ(s[1].name, "b");
  EXPECT_EQ(s[2].line, 5);
}

TEST(Sections, CountLineBreaks) {
  EXPECT_EQ(count_line_breaks(""), 0);
  EXPECT_EQ(count_line_breaks("a\nb\r\nc\rd"), 3);
  EXPECT_EQ(count_line_breaks("\n\n"), 2);
}

}  // namespace
}  // namespace simit::tools

// The tracers' abort reasons (jit/trace/abort_reasons.h): one list of texts, details filled
// into their placeholders, and give_up's located GiveUp.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "jit/ir_build.h"
#include "jit/trace/abort_reasons.h"

namespace simit::jit {
namespace {

TEST(AbortReasons, TextsAreDistinctWithAtMostTwoDetails) {
  std::set<std::string> texts;
  int entries = 0;
#define SIMIT_TEST_ABORT(name, text)                                                            \
  {                                                                                             \
    ++entries;                                                                                  \
    const std::string t = abort_text(AbortReason::name);                                        \
    EXPECT_FALSE(t.empty()) << #name;                                                           \
    EXPECT_TRUE(texts.insert(t).second) << "two entries read \"" << t << "\"";                  \
    size_t holes = 0;                                                                           \
    for (size_t at = t.find("{}"); at != std::string::npos; at = t.find("{}", at + 2)) ++holes; \
    EXPECT_LE(holes, 2u) << #name;                                                              \
  }
  SIMIT_TRACE_ABORTS(SIMIT_TEST_ABORT)
#undef SIMIT_TEST_ABORT
  EXPECT_EQ(static_cast<int>(texts.size()), entries);
  EXPECT_GT(entries, 100);
}

TEST(AbortReasons, DetailsFillThePlaceholdersInOrder) {
  EXPECT_EQ(abort_message(AbortReason::TensorTooLarge, "4096", "1024"),
            "a dense tensor of 4096 components (more than 1024) is not compiled");
  EXPECT_EQ(abort_message(AbortReason::ReadBeforeSet, "x"), "'x' is read before it is set");
  EXPECT_EQ(abort_message(AbortReason::StatementKind, "While"),
            "While statements are not compiled");
  EXPECT_EQ(abort_message(AbortReason::LoopBoundsNotConstant),
            "a loop whose bounds are not constants");
  // A missing detail leaves its placeholder empty rather than showing braces.
  EXPECT_EQ(abort_message(AbortReason::VariableTypeInLoop, "m"), "'m' of type  in a compiled loop");
}

TEST(AbortReasons, GiveUpThrowsTheMessage) {
  try {
    trace_detail::give_up({}, AbortReason::FieldNotBound, "x");
    FAIL() << "give_up returned";
  } catch (const GiveUp& g) {
    EXPECT_EQ(g.reason, "field 'x' is not bound");  // no line without a location
  }
}

}  // namespace
}  // namespace simit::jit

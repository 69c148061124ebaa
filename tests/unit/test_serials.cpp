// SerialTracker: each channel in serial order, repeats and gaps told apart,
// missing messages asked for in batches, a standing request not repeated
// until its time is up.
#include <gtest/gtest.h>

#include "afford/serials.hpp"

namespace afford {
namespace {

using V = SerialTracker::Verdict;
using namespace std::chrono_literals;

TEST(Serials, AcceptsInOrderAndDropsRepeats) {
  SerialTracker t;
  EXPECT_EQ(t.offer("FOCUS", 0), V::Accept);
  EXPECT_EQ(t.offer("FOCUS", 1), V::Accept);
  EXPECT_EQ(t.offer("FOCUS", 1), V::Repeat);
  EXPECT_EQ(t.offer("FOCUS", 0), V::Repeat);
  EXPECT_EQ(t.offer("DECISION", 0), V::Accept);  // channels are independent
  EXPECT_EQ(t.expected("FOCUS"), 2);
  EXPECT_EQ(t.missing(), 0);
}

TEST(Serials, AGapIsNotTakenAndIsAskedForThenFilled) {
  SerialTracker t;
  const auto now = SerialTracker::Clock::now();
  ASSERT_EQ(t.offer("FOCUS", 0), V::Accept);
  EXPECT_EQ(t.offer("FOCUS", 3), V::Gap);  // 1 and 2 lost
  EXPECT_EQ(t.expected("FOCUS"), 1);
  EXPECT_EQ(t.missing(), 3);  // 1, 2 and 3 itself
  const auto r = t.due(now);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].channel, "FOCUS");
  EXPECT_EQ(r[0].first, 1);
  EXPECT_EQ(r[0].last, 3);
  for (int s = 1; s <= 3; ++s) EXPECT_EQ(t.offer("FOCUS", s), V::Accept);
  EXPECT_EQ(t.missing(), 0);
  EXPECT_TRUE(t.due(now).empty());
}

TEST(Serials, AnnouncedCountsRevealALostLastMessageAndAskInBatches) {
  SerialTracker t(64, 300ms);
  const auto now = SerialTracker::Clock::now();
  t.announce("FOCUS", 200);  // a restarted receiver: everything is missing
  auto r = t.due(now);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, 0);
  EXPECT_EQ(r[0].last, 63);
  EXPECT_TRUE(t.due(now + 100ms).empty()) << "a standing request is not repeated";
  for (int s = 0; s < 64; ++s) ASSERT_EQ(t.offer("FOCUS", s), V::Accept);
  r = t.due(now + 100ms);  // that batch is in: the next one at once
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, 64);
  EXPECT_EQ(r[0].last, 127);
  r = t.due(now + 500ms);  // unanswered for longer than the retry time: asked again
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, 64);
}

TEST(Serials, ExpectResumesAChannelWhereAnEarlierSegmentEnded) {
  SerialTracker t;
  t.expect("SCENE", 10);
  EXPECT_EQ(t.offer("SCENE", 9), V::Repeat);
  EXPECT_EQ(t.offer("SCENE", 10), V::Accept);
  t.reset();
  EXPECT_EQ(t.offer("SCENE", 0), V::Accept);
}

}  // namespace
}  // namespace afford

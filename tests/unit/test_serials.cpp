// SerialTracker: each channel in serial order, repeats and gaps told apart,
// missing messages asked for in batches, a standing request not repeated
// until its time is up (then backing off), a publisher's claim replacing
// what was believed before, a refused message expected again. Replay's
// serials (SerialRuns, GapFinder): a set held as runs of consecutive serials,
// and the holes of a recording found event by event.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <set>

#include "afford/serials.hpp"
#include "experiment/replay/replay.hpp"
#include "tests/samples.hpp"

namespace afford {
namespace {

using V = SerialTracker::Verdict;
using namespace std::chrono_literals;

SerialTracker tracker() { return SerialTracker(64, 20ms, 500ms); }

TEST(Serials, AcceptsInOrderAndDropsRepeats) {
  SerialTracker t = tracker();
  EXPECT_EQ(t.offer("FOCUS", 0), V::Accept);
  EXPECT_EQ(t.offer("FOCUS", 1), V::Accept);
  EXPECT_EQ(t.offer("FOCUS", 1), V::Repeat);
  EXPECT_EQ(t.offer("FOCUS", 0), V::Repeat);
  EXPECT_EQ(t.offer("DECISION", 0), V::Accept);  // channels are independent
  EXPECT_EQ(t.expected("FOCUS"), 2);
  EXPECT_EQ(t.missing(), 0);
}

TEST(Serials, AGapIsNotTakenAndIsAskedForThenFilled) {
  SerialTracker t = tracker();
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

TEST(Serials, ClaimedCountsRevealALostLastMessageAndAskInBatches) {
  SerialTracker t = tracker();
  const auto now = SerialTracker::Clock::now();
  t.claim("FOCUS", 200);  // a restarted receiver: everything is missing
  auto r = t.due(now);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, 0);
  EXPECT_EQ(r[0].last, 63);
  EXPECT_TRUE(t.due(now + 10ms).empty()) << "a standing request is not repeated";
  for (int s = 0; s < 64; ++s) ASSERT_EQ(t.offer("FOCUS", s), V::Accept);
  r = t.due(now + 10ms);  // that batch is in: the next one at once
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, 64);
  EXPECT_EQ(r[0].last, 127);
  r = t.due(now + 35ms);  // unanswered for longer than the retry time: asked again
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, 64);
}

TEST(Serials, AnUnansweredRequestIsAskedAgainLessAndLessOften) {
  SerialTracker t = tracker();
  auto now = SerialTracker::Clock::now();
  t.claim("SCENE", 5);
  ASSERT_EQ(t.due(now).size(), 1u);
  std::vector<std::chrono::milliseconds> waits;
  auto asked = now;
  for (int k = 0; k < 8; ++k) {  // nothing ever comes: find when each request goes out again
    do now += 1ms;
    while (t.due(now).empty());
    waits.push_back(std::chrono::duration_cast<std::chrono::milliseconds>(now - asked));
    asked = now;
  }
  EXPECT_EQ(waits.front(), 20ms);
  for (std::size_t k = 1; k < waits.size(); ++k) EXPECT_GE(waits[k], waits[k - 1]);
  EXPECT_EQ(waits.back(), 500ms) << "the wait stops growing at the heartbeat";
  ASSERT_EQ(t.offer("SCENE", 0), V::Accept);  // an answer: the rest is asked for after the short wait again
  EXPECT_TRUE(t.due(now + 19ms).empty());
  const auto r = t.due(now + 21ms);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, 1);
}

TEST(Serials, ThePublishersClaimReplacesAForgedCountOrSerial) {
  SerialTracker t = tracker();
  ASSERT_EQ(t.offer("FOCUS", 0), V::Accept);
  EXPECT_EQ(t.offer("FOCUS", 1'000'000), V::Gap);  // a forged serial far ahead
  EXPECT_EQ(t.missing(), 1'000'000);
  t.claim("FOCUS", 1);  // the publisher: it has published one message
  EXPECT_EQ(t.missing(), 0);
  t.claim("FOCUS", 1'000'000'000);  // a forged claim ...
  EXPECT_GT(t.missing(), 0);
  t.claim("FOCUS", 1);  // ... until the publisher's next
  EXPECT_EQ(t.missing(), 0);
  EXPECT_EQ(t.offer("FOCUS", 1), V::Accept);
}

// After the publisher has left the run, nothing undoes a forged serial or
// count: its final count stands, later claims only lower it, and a serial at
// or beyond it is dropped, not waited for (the hostile flood found a forged
// serial arriving after the last STATUS of a run's publisher).
TEST(Serials, OnceThePublisherHasLeftItsFinalCountStands) {
  SerialTracker t = tracker();
  for (int s = 0; s < 3; ++s) ASSERT_EQ(t.offer("DECISION", s), V::Accept);
  EXPECT_EQ(t.finalCount("DECISION"), -1);
  t.claim("DECISION", 3, /*final=*/true);
  EXPECT_EQ(t.finalCount("DECISION"), 3);
  EXPECT_EQ(t.offer("DECISION", INT64_MAX), V::Beyond);
  EXPECT_EQ(t.offer("DECISION", 3), V::Beyond);
  EXPECT_EQ(t.offer("DECISION", 2), V::Repeat);
  EXPECT_EQ(t.missing(), 0);
  t.claim("DECISION", 3007);  // an in-run STATUS, late or forged
  EXPECT_EQ(t.missing(), 0);
  t.claim("DECISION", INT64_MAX / 2, /*final=*/true);  // a forged final one
  EXPECT_EQ(t.missing(), 0);
  EXPECT_EQ(t.finalCount("DECISION"), 3);
  // A final count above what was had: the last message was lost, and is asked for.
  t.claim("FOCUS", 0);
  t.claim("FOCUS", 2, /*final=*/true);
  EXPECT_EQ(t.missing(), 2);
  EXPECT_EQ(t.offer("FOCUS", 0), V::Accept);
  EXPECT_EQ(t.offer("FOCUS", 1), V::Accept);
  EXPECT_EQ(t.missing(), 0);
}

TEST(Serials, AChannelNotAllowedToAskWaits) {
  SerialTracker t = tracker();
  const auto now = SerialTracker::Clock::now();
  t.claim("EFFECT", 10);
  t.claim("FOCUS", 10);
  const auto r = t.due(now, [](const std::string& c) { return c != "EFFECT"; });
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].channel, "FOCUS");
  EXPECT_EQ(t.due(now, {}).size(), 1u) << "EFFECT, once allowed";
}

TEST(Serials, ARefusedMessageIsExpectedAgain) {
  SerialTracker t = tracker();
  for (int s = 0; s < 5; ++s) ASSERT_EQ(t.offer("LOOK", s), V::Accept);
  t.rewind("LOOK", 3);  // serial 3 was not the real one: 3 and 4 are not had
  EXPECT_EQ(t.expected("LOOK"), 3);
  EXPECT_EQ(t.offer("LOOK", 3), V::Accept);
  EXPECT_EQ(t.offer("LOOK", 2), V::Repeat);
}

TEST(Serials, ExpectResumesAChannelWhereAnEarlierSegmentEnded) {
  SerialTracker t = tracker();
  t.expect("SCENE", 10);
  EXPECT_EQ(t.offer("SCENE", 9), V::Repeat);
  EXPECT_EQ(t.offer("SCENE", 10), V::Accept);
  t.reset();
  EXPECT_EQ(t.offer("SCENE", 0), V::Accept);
}

TEST(Serials, TheLargestSerialClaimsNoMoreThanItself) {
  SerialTracker t = tracker();
  EXPECT_EQ(t.offer("FOCUS", INT64_MAX), V::Gap);  // 1 + it would overflow
  EXPECT_EQ(t.missing(), INT64_MAX);
  EXPECT_EQ(t.offer("FOCUS", INT64_MAX), V::Gap);
  t.claim("FOCUS", 1);  // the publisher's count replaces the forged evidence
  EXPECT_EQ(t.missing(), 1);
}

// Whatever the order serials come in, the runs hold exactly the serials given,
// each run maximal (no two touch), and a repeat is told.
TEST(ReplaySerials, RunsHoldTheSerialsGivenAndTellRepeats) {
  std::mt19937 gen(7);
  std::uniform_int_distribution<std::int64_t> pick(0, 300);
  SerialRuns runs;
  std::set<std::int64_t> plain;
  for (int i = 0; i < 2000; ++i) {
    const std::int64_t s = pick(gen);
    EXPECT_EQ(runs.insert(s), plain.insert(s).second) << s;
  }
  EXPECT_EQ(runs.size(), static_cast<std::int64_t>(plain.size()));
  std::set<std::int64_t> held;
  std::int64_t end = -2;
  for (const auto& [first, last] : runs.runs()) {
    EXPECT_GT(first, end + 1) << "runs " << end << " and " << first << " touch";
    for (std::int64_t s = first; s <= last; ++s) held.insert(s);
    end = last;
  }
  EXPECT_EQ(held, plain);
  for (std::int64_t s = 0; s <= 300; ++s) runs.insert(s);
  EXPECT_EQ(runs.runs().size(), 1u);  // all of them: one run, two numbers
}

LogEvent focusEvent(const std::string& run, std::int64_t serial) {
  focus_t m = test::sample(static_cast<const focus_t*>(nullptr));
  m.run_id = run;
  m.serial = serial;
  return LogEvent{ch::focus.name, sealed(m)};
}

// The holes of a recording, in any order and with repeats, and beyond the last
// recorded serial up to what its publisher said it published; other runs'
// events are not counted.
TEST(ReplaySerials, TheGapsOfARecordingAreFoundEventByEvent) {
  const ProtocolConfig protocol = test::shippedProtocol();
  GapFinder finder("r", Phase::Intrinsic, BoundsContext{&protocol, nullptr});
  for (std::int64_t s : {0, 1, 2, 5, 4, 9, 2, 10, 11})
    finder.add(focusEvent("r", s));
  finder.add(focusEvent("other", 3));
  process_status_t st = test::sample(static_cast<const process_status_t*>(nullptr));
  st.process = "eye";
  st.counts_run = "r";
  st.channels = {ch::focus.name};
  st.counts = {14};
  st.held_from = {0};
  st.n_channels = 1;
  finder.add(LogEvent{ch::status.name, sealed(st)});
  const std::vector<LogGap> gaps = finder.gaps();
  ASSERT_EQ(gaps.size(), 3u);
  EXPECT_EQ(gaps[0].channel, ch::focus.name);
  EXPECT_EQ(std::make_pair(gaps[0].first, gaps[0].last), std::make_pair(std::int64_t{3}, std::int64_t{3}));
  EXPECT_EQ(std::make_pair(gaps[1].first, gaps[1].last), std::make_pair(std::int64_t{6}, std::int64_t{8}));
  EXPECT_EQ(std::make_pair(gaps[2].first, gaps[2].last), std::make_pair(std::int64_t{12}, std::int64_t{13}));
}

}  // namespace
}  // namespace afford

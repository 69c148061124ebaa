// The edge's table of peers (afford/edge_peers.hpp): STATUS beats, and a keyed
// bus's freshness windows, each bounded; the copies of a process, and which
// of two refuses.
#include <gtest/gtest.h>

#include "afford/edge_peers.hpp"

#include <vector>

namespace afford {
namespace {

constexpr std::int64_t kNow = 1'764'000'000'000;  // a receiver's clock (ms)
constexpr int kFresh = 10'000, kLimit = 4;

std::string fresh(EdgePeers& p, std::uint64_t session, std::uint64_t counter, std::int64_t sent = kNow) {
  std::int64_t forgotten = 0;
  return p.fresh({session, counter, sent}, kNow, kFresh, kLimit, forgotten);
}

TEST(Freshness, EachCounterOfASessionIsTakenOnceInAnyOrderWithinTheWindow) {
  EdgePeers p;
  EXPECT_EQ(fresh(p, 1, 10), "");
  EXPECT_EQ(fresh(p, 1, 12), "");
  EXPECT_EQ(fresh(p, 1, 11), "");  // late, within the window
  EXPECT_NE(fresh(p, 1, 11).find("taken already"), std::string::npos);
  EXPECT_NE(fresh(p, 1, 12).find("taken already"), std::string::npos);
  EXPECT_NE(fresh(p, 1, 9).find("before this sender was first heard"), std::string::npos);
  EXPECT_EQ(fresh(p, 1, 12 + EdgePeers::kWindow), "");  // far ahead: the window moves
  // Now the highest is 12 + kWindow: 12 is just outside the window, 13 just inside it.
  EXPECT_NE(fresh(p, 1, 12).find("older than the window"), std::string::npos);
  EXPECT_EQ(fresh(p, 1, 13), "");
  EXPECT_NE(fresh(p, 1, 13).find("taken already"), std::string::npos);
}

TEST(Freshness, ASessionNotHeardYetIsTakenOnlyIfRecentByItsClock) {
  EdgePeers p;
  EXPECT_NE(fresh(p, 7, 0, kNow - kFresh - 1).find("s ago by its clock"), std::string::npos);
  EXPECT_NE(fresh(p, 7, 1, kNow + kFresh + 1).find("s ago by its clock"), std::string::npos);  // from the future
  EXPECT_EQ(fresh(p, 7, 2, kNow - kFresh + 1), "");
  // Once heard, its window decides, not its clock (a long-lived sender's messages stay welcome).
  EXPECT_EQ(fresh(p, 7, 3, kNow - 10 * kFresh), "");
  std::int64_t forgotten = 0;
  EXPECT_EQ(p.fresh({8, 0, 0}, kNow, 0, kLimit, forgotten), "") << "freshness_ms 0: any age";
}

TEST(Freshness, TheTableHoldsAtMostItsLimitAndAForgottenSessionMustBeRecentAgain) {
  EdgePeers p;
  std::int64_t forgotten = 0;
  for (std::uint64_t s = 1; s <= 6; ++s) EXPECT_EQ(p.fresh({s, 100, kNow}, kNow, kFresh, kLimit, forgotten), "");
  EXPECT_EQ(forgotten, 2);  // sessions 1 and 2, heard from longest ago
  // Session 1 forgotten: an old message of it is stale; a recent one starts its window anew.
  EXPECT_NE(p.fresh({1, 50, kNow - 2 * kFresh}, kNow, kFresh, kLimit, forgotten).find("ago"), std::string::npos);
  EXPECT_EQ(p.fresh({1, 101, kNow}, kNow, kFresh, kLimit, forgotten), "");
  // Session 6 is remembered: its counter 100 again is a repeat.
  EXPECT_NE(p.fresh({6, 100, kNow}, kNow, kFresh, kLimit, forgotten).find("taken already"), std::string::npos);
}

TEST(Peers, AStatusBeatIsTakenOnceAndTheTableIsBounded) {
  EdgePeers p;
  std::int64_t forgotten = 0;
  process_status_t st{};
  st.process = "eye";
  st.pid = 1;
  st.host = "lab-1";
  st.started = 100;
  st.beat = 5;
  EXPECT_TRUE(p.newerStatus(st, kLimit, forgotten));
  EXPECT_FALSE(p.newerStatus(st, kLimit, forgotten));
  st.beat = 6;
  EXPECT_TRUE(p.newerStatus(st, kLimit, forgotten));
  st.host = "lab-2";  // the same pid on another host: another process, whose beats count from its own
  st.beat = 0;
  EXPECT_TRUE(p.newerStatus(st, kLimit, forgotten));
  for (int pid = 2; pid <= 4; ++pid) {
    st.pid = pid;
    EXPECT_TRUE(p.newerStatus(st, kLimit, forgotten));
  }
  EXPECT_EQ(forgotten, 1);
}

// A STATUS of `who`, naming `copies`.
process_status_t statusOf(const Instance& who, std::vector<std::string> copies = {}) {
  process_status_t st{};
  st.process = who.process;
  st.pid = who.pid;
  st.host = who.host;
  st.started = who.started;
  st.state = process_status_t::WAITING;
  st.copies = std::move(copies);
  st.n_copies = static_cast<std::int32_t>(st.copies.size());
  return st;
}

TEST(Copies, OfTwoCopiesThatHearEachOtherTheLaterRefusesWhicheverHearsFirst) {
  const Instance early{"eye", "lab-1", 300, 1000}, late{"eye", "lab-1", 200, 2000};
  const auto now = Copies::Clock::now();
  for (bool early_hears_first : {true, false}) {
    Copies a(early), b(late);
    std::int64_t forgotten = 0;
    const auto live = std::chrono::seconds(2);
    if (early_hears_first) {
      EXPECT_EQ(a.heard(statusOf(late), now, kLimit, forgotten), Copies::Heard::New);
      EXPECT_EQ(a.named(now, live), std::vector<std::string>{late.id()});
    } else {
      EXPECT_EQ(b.heard(statusOf(early), now, kLimit, forgotten), Copies::Heard::New);  // named by b, then a hears it
      EXPECT_EQ(a.heard(statusOf(late, b.named(now, live)), now, kLimit, forgotten), Copies::Heard::New);
      EXPECT_EQ(a.refusal(), "");  // a later copy naming the earlier one changes nothing for the earlier
    }
    // The early one's STATUS names the late one: the late one refuses, naming the early one; the early one serves.
    EXPECT_EQ(b.heard(statusOf(early, a.named(now, live)), now, kLimit, forgotten), Copies::Heard::Refuse);
    EXPECT_NE(b.refusal().find("pid 300 on host lab-1, started earlier; this one (pid 200 on host lab-1)"),
              std::string::npos);
    EXPECT_EQ(a.refusal(), "");
    // Its last STATUS (FAILED, in no run, naming the early one): the early one names it no more.
    process_status_t last = statusOf(late, b.named(now, live));
    last.state = process_status_t::FAILED;
    EXPECT_EQ(a.heard(last, now, kLimit, forgotten), Copies::Heard::Nothing);
    EXPECT_TRUE(a.named(now, live).empty());
  }
}

TEST(Copies, ARecordingsStatusNeverMakesALiveProcessRefuse) {
  // A recording played onto the bus: an earlier eye's STATUS, naming whom it heard then, never this one.
  const Instance live_eye{"eye", "lab-1", 500, 5000}, recorded{"eye", "lab-1", 400, 1000};
  Copies c(live_eye);
  std::int64_t forgotten = 0;
  const auto now = Copies::Clock::now();
  EXPECT_EQ(c.heard(statusOf(recorded, {"401@lab-1/1001"}), now, kLimit, forgotten), Copies::Heard::New);
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(c.heard(statusOf(recorded, {"401@lab-1/1001"}), now, kLimit, forgotten), Copies::Heard::Nothing);
  EXPECT_EQ(c.refusal(), "");
  // Nor the same pid on the same host (this process itself, or a node of it made anew), nor a sender without a host.
  EXPECT_EQ(c.heard(statusOf({"eye", "lab-1", 500, 9000}, {live_eye.id()}), now, kLimit, forgotten),
            Copies::Heard::Nothing);
  EXPECT_EQ(c.heard(statusOf({"eye", "", 1, 1}, {live_eye.id()}), now, kLimit, forgotten), Copies::Heard::Nothing);
  EXPECT_EQ(c.heard(statusOf({"predictors", "lab-1", 9, 1}, {live_eye.id()}), now, kLimit, forgotten),
            Copies::Heard::Nothing);
  EXPECT_EQ(c.refusal(), "");
}

TEST(Copies, TheOrderIsTheStartThenTheHostThenThePid) {
  EXPECT_TRUE((Instance{"eye", "b", 1, 1}).before(Instance{"eye", "a", 1, 2}));
  EXPECT_TRUE((Instance{"eye", "a", 9, 1}).before(Instance{"eye", "b", 1, 1}));
  EXPECT_TRUE((Instance{"eye", "a", 1, 1}).before(Instance{"eye", "a", 2, 1}));
  EXPECT_FALSE((Instance{"eye", "a", 1, 1}).before(Instance{"eye", "a", 1, 1}));
  EXPECT_EQ(instanceText("4102@lab-1/17"), "pid 4102 on host lab-1");
}

TEST(Copies, TheRunnerTellsACopyThatRefusesFromOneRestartedAfterTheOther) {
  Instances seen;
  std::int64_t forgotten = 0;
  const auto t0 = Instances::Clock::now();
  const auto live = std::chrono::seconds(2);
  const Instance early{"eye", "lab-1", 300, 1000}, late{"eye", "lab-1", 200, 2000};
  seen.heard(statusOf(late), t0, kLimit, forgotten);
  EXPECT_FALSE(seen.refuses(late, t0, live));  // not yet named by the earlier one
  seen.heard(statusOf(early, {late.id()}), t0, kLimit, forgotten);
  EXPECT_TRUE(seen.refuses(late, t0, live));
  EXPECT_FALSE(seen.refuses(early, t0, live));
  EXPECT_FALSE(seen.refuses(late, t0 + 2 * live, live));  // the earlier one, not heard for long, names nobody
  ASSERT_EQ(seen.live("eye", t0, live).size(), 2u);
  EXPECT_EQ(seen.live("eye", t0, live).front()->who, early);
}

}  // namespace
}  // namespace afford

// The edge's table of peers (afford/edge_peers.hpp): STATUS beats, and a keyed
// bus's freshness windows, each bounded.
#include <gtest/gtest.h>

#include "afford/edge_peers.hpp"

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
  process_status_t st;
  st.process = "eye";
  st.pid = 1;
  st.beat = 5;
  EXPECT_TRUE(p.newerStatus(st, kLimit, forgotten));
  EXPECT_FALSE(p.newerStatus(st, kLimit, forgotten));
  st.beat = 6;
  EXPECT_TRUE(p.newerStatus(st, kLimit, forgotten));
  for (int pid = 2; pid <= 5; ++pid) {
    st.pid = pid;
    EXPECT_TRUE(p.newerStatus(st, kLimit, forgotten));
  }
  EXPECT_EQ(forgotten, 1);
}

}  // namespace
}  // namespace afford

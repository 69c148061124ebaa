// A run's log read in step order (processes/viewer/step_order.hpp): the
// logger records each channel in serial order, but not how the channels
// interleave, so a log shuffled as the protocol allows (tests/logorder/
// shuffle.hpp: each channel in its own order, the channels up to a window of
// steps apart, in one segment or two) gives the same messages in the same
// order as the log as recorded, and `afford watch --log` shows the same state
// at every step. The logs: a short intrinsic run of IMP and one of the GOALS
// agent, recorded when a test first needs them (memq), and a stored extrinsic
// test.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "afford/config.hpp"
#include "afford/logging.hpp"
#include "afford/process_main.hpp"
#include "afford/protocol.hpp"
#include "experiment/replay/replay.hpp"
#include "experiment/watch/player.hpp"
#include "experiment/watch/state.hpp"
#include "tests/logorder/shuffle.hpp"
#include "tests/support.hpp"
#include "viewer/step_order.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using Message = std::pair<std::string, std::vector<std::uint8_t>>;

spdlog::logger& quiet() {
  static auto log = makeLogger("log-order-test", "off");
  return *log;
}

fs::path dir() {
  static const fs::path d = test::tempDir("log-order");
  return d;
}

// A short run of `system`'s, recorded once for the program (memq).
fs::path recorded(const std::string& system, int steps) {
  const fs::path log = dir() / "logs" / ("lo-base-" + system + "-s1");
  if (fs::exists(log)) return log;
  const auto run = test::runAfford("experiment base --system " + system + " --reps 1 --steps " +
                                   std::to_string(steps) + " --transport memq --quiet --keep-logs all --run-prefix lo" +
                                   " --out " + (dir() / system).string() + " --log-root " + (dir() / "logs").string());
  EXPECT_EQ(run.exit_code, 0) << run.output;
  return log;
}
fs::path intrinsicLog() { return recorded("IMP", 300); }
fs::path goalsLog() { return recorded("GOALS", 100); }
// A stored extrinsic test (tests/data/explain), unzipped.
fs::path extrinsicLog() {
  const fs::path log = dir() / "multi-step-top-down-budget.lcm";
  if (fs::exists(log)) return log;
  const fs::path gz = fs::path(AFFORD_SOURCE_DIR) / "tests/data/explain/multi-step-top-down-budget.lcm.gz";
  const auto unzip = test::runCommand("gzip -dc '" + gz.string() + "' > '" + log.string() + "'");
  EXPECT_EQ(unzip.exit_code, 0) << unzip.output;
  return log;
}

// The log at `log` interleaved anew into a new folder.
fs::path shuffled(const fs::path& log, std::int64_t window, int segments, bool config_too = false) {
  static int made = 0;
  const fs::path out = dir() / ("shuffled-" + std::to_string(++made));
  const testing::ShuffleReport r = testing::shuffleLog(log, out, {window, 1, segments, config_too});
  EXPECT_GT(r.moved, r.events / 2) << log;  // most events moved
  EXPECT_GE(r.most_ahead, std::min<std::int64_t>(window / 2, 20)) << log;  // channels steps apart
  return out;
}

using OrderedLog = StepOrderedLog<RecordedLogStream, RunSelector>;
std::unique_ptr<OrderedLog> open(const fs::path& log) {
  return std::make_unique<OrderedLog>(
      [log](spdlog::logger& l) { return std::make_unique<RecordedLogStream>(log, l); },
      [log](spdlog::logger& l) { return std::make_unique<RunSelector>("", log.string(), l); },
      loadProtocol(defaultConfigDir()), quiet());
}

// The run's messages as the tools are given them.
std::vector<Message> inStepOrder(const fs::path& log, std::size_t* most_held = nullptr) {
  auto in = open(log);
  std::vector<Message> out;
  LogEvent e;
  StepKey key;
  while (in->next(e, key)) out.emplace_back(e.channel, e.data);
  if (most_held) *most_held = in->order().mostHeld();
  return out;
}

TEST(StepOrder, AShuffledLogGivesTheRunsMessagesInTheOrderOfTheLogAsRecorded) {
  for (const fs::path& log : {intrinsicLog(), goalsLog(), extrinsicLog()}) {
    SCOPED_TRACE(log.string());
    const std::vector<Message> recorded = inStepOrder(log);
    ASSERT_GT(recorded.size(), 300u);
    for (const auto& [window, segments] : {std::pair<std::int64_t, int>{20, 1}, {1000, 2}, {50, 3}}) {
      SCOPED_TRACE("window " + std::to_string(window) + ", segments " + std::to_string(segments));
      std::size_t held = 0;
      // The last: the RUN_CONFIG interleaved too, as a logger never writes it, but another tool might.
      const std::vector<Message> got = inStepOrder(shuffled(log, window, segments, segments == 3), &held);
      EXPECT_TRUE(got == recorded);
      EXPECT_GT(held, 0u);  // messages read ahead of their turn
    }
  }
}

// The ranks within a step are the intrinsic step's own order: its log as recorded is given as it is, with nothing
// read ahead.
TEST(StepOrder, AnIntrinsicRunRecordedInStepOrderIsGivenInItsOwnOrder) {
  std::vector<Message> recorded;
  for (LogEvent& e : readRecordedLog(intrinsicLog(), quiet()).events) recorded.emplace_back(e.channel, e.data);
  std::size_t held = 1;
  EXPECT_TRUE(inStepOrder(intrinsicLog(), &held) == recorded);
  EXPECT_EQ(held, 0u);
}

// A message whose digest does not match (its step cannot be trusted) goes with the one before it on its channel:
// it holds back no other message of its channel, and the rest come as they do from the log unchanged.
TEST(StepOrder, AMessageItsContentCannotPlaceGoesWithTheOneBeforeIt) {
  std::vector<LogEvent> events = readRecordedLog(intrinsicLog(), quiet()).events;
  Message changed, before;
  int focus = 0;
  for (LogEvent& e : events) {
    if (e.channel != ch::focus.name) continue;
    if (++focus == 99) before = {e.channel, e.data};
    if (focus != 100) continue;
    RunHeader h;
    ASSERT_TRUE(peekRunHeader(e.data.data(), e.data.size(), h));
    e.data[8 + 4 + h.run_id.size() + 1] = 0x10;  // (fingerprint, run id) its step: some 2^60; its digest fails
    changed = {e.channel, e.data};
  }
  const fs::path bad = dir() / "bad-focus";
  fs::create_directories(bad);
  {
    LogWriter w(bad / "log.00.lcm");
    for (const LogEvent& e : events) w.write(e.channel, e.data.data(), e.data.size(), e.utime);
  }
  // The rest in the order of the log unchanged; the one changed right after the FOCUS before it.
  std::vector<Message> clean, got = inStepOrder(bad);
  focus = 0;
  for (Message& m : inStepOrder(intrinsicLog()))
    if (m.first != ch::focus.name || ++focus != 100) clean.push_back(std::move(m));
  const auto at = std::find(got.begin(), got.end(), changed);
  ASSERT_TRUE(at != got.end() && at != got.begin());
  EXPECT_TRUE(*(at - 1) == before);
  std::vector<Message> rest = got;
  rest.erase(rest.begin() + (at - got.begin()));
  EXPECT_TRUE(rest == clean);
  EXPECT_TRUE(inStepOrder(shuffled(bad, 50, 2)) == got);
}

TEST(StepOrder, AChannelSaidEveryStepIsHeldAsOneRunWhateverItsLength) {
  StepTrail every, some;
  for (std::int64_t s = 0; s < 100000; ++s) every.add(s);
  EXPECT_EQ(every.runs(), 1u);
  const std::vector<std::int64_t> steps = {StepKey::kBefore, 0, 0, 1, 3, 5, 7, 8, StepKey::kAfter, -4};
  for (std::int64_t s : steps) some.add(s);
  StepTrail::At at;
  for (std::int64_t s : steps) {
    EXPECT_EQ(some.step(at), s);
    some.advance(at);
  }
}

// A log that lost messages of the run between its two readings is said to have changed; one that gained
// some (still being written) is given as first read.
TEST(StepOrder, ALogThatChangesBetweenItsReadingsIsSaidToHaveChanged) {
  std::vector<LogEvent> events = readRecordedLog(intrinsicLog(), quiet()).events;
  int readings = 0;
  auto passOf = [&](std::size_t lose_at, std::size_t n) {
    auto at = std::make_shared<std::size_t>(0);
    return StepOrdered::Pass{[&events, at, lose_at, n](LogEvent& e) {
                               if (*at == lose_at) ++*at;
                               if (*at >= n) return false;
                               e = events[(*at)++];
                               return true;
                             },
                             [](const LogEvent&) { return true; }};
  };
  // (The readings: up to the RUN_CONFIG, through for the keys, then as given.)
  StepOrdered lost([&](bool) { return passOf(++readings == 3 ? 500 : events.size(), events.size()); },
                   loadProtocol(defaultConfigDir()));
  LogEvent e;
  StepKey key;
  EXPECT_THROW(
      {
        while (lost.next(e, key)) {
        }
      },
      std::runtime_error);
  readings = 0;
  StepOrdered grew([&](bool) { return passOf(events.size(), ++readings <= 2 ? events.size() - 50 : events.size()); },
                   loadProtocol(defaultConfigDir()));
  std::size_t given = 0;
  while (grew.next(e, key)) ++given;
  EXPECT_EQ(given, events.size() - 50);
}

// ---- afford watch --log ---------------------------------------------------------------------

// What the page is sent, but for the counters of changes.
nlohmann::json shown(const WatchState& state) {
  nlohmann::json j = nlohmann::json::parse(state.snapshot(true));
  j.erase("version");
  j.erase("curves_version");
  return j;
}

TEST(LogPlayer, AShuffledLogShowsTheSameStateAtEveryStep) {
  const ProtocolConfig protocol = loadProtocol(defaultConfigDir());
  for (const fs::path& log : {intrinsicLog(), goalsLog(), extrinsicLog()}) {
    SCOPED_TRACE(log.string());
    WatchState a, b;
    PlayerOptions o;
    o.log = log;
    o.play = false;
    LogPlayer recorded(a, protocol, o, quiet());
    o.log = shuffled(log, 40, 2);
    LogPlayer played(b, protocol, o, quiet());
    ASSERT_EQ(recorded.firstStep(), played.firstStep());
    ASSERT_EQ(recorded.lastStep(), played.lastStep());
    std::vector<std::int64_t> steps;
    for (std::int64_t s = recorded.firstStep(); s <= recorded.lastStep(); s += 3) steps.push_back(s);
    steps.push_back(recorded.firstStep() + 7);  // back: read again from the start
    int differ = 0;
    for (std::int64_t s : steps) {
      recorded.seekTo(s);
      played.seekTo(s);
      if (shown(a) != shown(b) && differ++ < 3) ADD_FAILURE() << "step " << s << ": the pages differ";
    }
    EXPECT_EQ(differ, 0) << "of " << steps.size() << " steps";
  }
}

}  // namespace
}  // namespace afford

// The goals phase (docs/model.md#goals-of-its-own), hosted in one process over
// memq: the motivation sets goals, the planner pursues them one step at a time,
// every action is learned from as in Algorithm 1, and a run is a pure function
// of its configuration.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "afford/goal_result_t.hpp"
#include "afford/goal_t.hpp"
#include "tests/in_process.hpp"

namespace afford {
namespace {

using test::InProcessRun;

std::string goalsYaml(std::int64_t steps, std::int64_t seed, std::vector<std::string> settings = {}) {
  return test::shippedConfigYaml("base", System::GOALS, seed, steps, std::move(settings));
}

template <class T>
std::vector<T> decoded(const InProcessRun& run, const std::string& channel) {
  std::vector<T> out;
  for (const auto& e : run.events)
    if (e.channel == channel) {
      T m;
      m.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
      out.push_back(m);
    }
  return out;
}

// A channel's messages by serial, each once (a restarted process may say one again), without the bytes that name
// the run's request (two requests of one run are compared).
std::map<std::int64_t, std::vector<std::uint8_t>> bySerial(const InProcessRun& run, const std::string& channel) {
  std::map<std::int64_t, std::vector<std::uint8_t>> out;
  for (const auto& e : run.events)
    if (e.channel == channel) {
      RunHeader h;
      if (peekRunHeader(e.data.data(), e.data.size(), h)) out[h.serial] = test::withoutRequest(channel, e.data);
    }
  return out;
}

TEST(Goals, EachStepLooksAtOneObjectAndDecidesOnceAndEveryGoalEnds) {
  const std::int64_t steps = 300;
  InProcessRun run(goalsYaml(steps, 3), System::GOALS, 3, steps);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error << "\n" << run.log.str();
  // One DECISION and one object FOCUS (scan or attended object) per step, in step order.
  const auto decisions = decoded<decision_t>(run, ch::decision.name);
  ASSERT_EQ(decisions.size(), static_cast<std::size_t>(steps));
  for (std::size_t i = 0; i < decisions.size(); ++i) EXPECT_EQ(decisions[i].step, static_cast<std::int64_t>(i));
  std::map<std::int64_t, int> objects;
  for (const focus_t& f : decoded<focus_t>(run, ch::focus.name))
    if (f.kind == focus_t::SCENE_SCAN || f.kind == focus_t::SCENE_OBJECT) ++objects[f.step];
  ASSERT_EQ(objects.size(), static_cast<std::size_t>(steps));
  for (const auto& [step, n] : objects) EXPECT_EQ(n, 1) << "step " << step;
  // Every action learned from once, as in Algorithm 1.
  EXPECT_EQ(run.count(ch::effect.name), test::trainingReports(run.events));
  EXPECT_EQ(run.count(ch::result.name), 1);
  // Goals in order, each ended by its result; the last result ends the run.
  const auto goals = decoded<goal_t>(run, ch::goal.name);
  const auto results = decoded<goal_result_t>(run, ch::goalResult.name);
  ASSERT_FALSE(goals.empty());
  ASSERT_EQ(results.size(), goals.size());
  for (std::size_t i = 0; i < goals.size(); ++i) {
    EXPECT_EQ(goals[i].id, static_cast<std::int32_t>(i));
    EXPECT_EQ(results[i].id, goals[i].id);
    EXPECT_LE(results[i].actions, goals[i].budget);
  }
  EXPECT_EQ(results.back().step, steps);
  // The agent explores first, then sets goals of each one-action module, and reaches some of them.
  std::map<int, int> set, reached;
  for (const auto& r : results) {
    ++set[r.module];
    reached[r.module] += r.reached;
  }
  EXPECT_GT(set[goal_t::EXPLORE], 0);
  EXPECT_GT(set[goal_t::COLOUR], 0);
  EXPECT_GT(set[goal_t::MOVE], 0);
  EXPECT_GT(reached[goal_t::COLOUR] + reached[goal_t::MOVE], 0);
}

TEST(Goals, TheSameRunTwiceIsTheSameRun) {
  const std::int64_t steps = 250;
  InProcessRun a(goalsYaml(steps, 5), System::GOALS, 5, steps);
  InProcessRun b(goalsYaml(steps, 5), System::GOALS, 5, steps);
  ASSERT_TRUE(a.outcome.ok) << a.outcome.error;
  ASSERT_TRUE(b.outcome.ok) << b.outcome.error;
  EXPECT_EQ(a.outcome.weights_checksum, b.outcome.weights_checksum);
  const auto ga = bySerial(a, ch::goal.name), gb = bySerial(b, ch::goal.name);
  ASSERT_EQ(ga.size(), gb.size());
  EXPECT_GT(ga.size(), 1u);
  EXPECT_EQ(ga, gb);
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

// Any one process killed mid-goal and started again (from its snapshot: every 100 steps) leaves the run as it
// was: the same weights, the same goals, the same results.
TEST(Goals, AProcessKilledMidGoalAndStartedAgainLeavesTheRunUnchanged) {
  const std::int64_t steps = 240;
  InProcessRun plain(goalsYaml(steps, 3), System::GOALS, 3, steps);
  ASSERT_TRUE(plain.outcome.ok) << plain.outcome.error;
  const std::string yaml = goalsYaml(steps, 3, {"protocol.recovery.snapshot_steps=100"});
  for (const std::string& p : runProcesses(Phase::Goals, /*recorded=*/false)) {
    const std::string snapshots = test::tempDir("goals-snapshots-" + p);
    InProcessRun run(yaml, System::GOALS, 3, steps, {}, 50, false, test::Restart{p, 170, snapshots, false, false});
    ASSERT_TRUE(run.outcome.ok) << p << ": " << run.outcome.error;
    ASSERT_TRUE(run.restarted) << p;
    EXPECT_GE(run.restored_step, 100) << p << " went on from no snapshot";
    EXPECT_EQ(run.outcome.weights_checksum, plain.outcome.weights_checksum) << p;
    EXPECT_EQ(bySerial(plain, ch::goalResult.name), bySerial(run, ch::goalResult.name)) << p;
  }
}

}  // namespace
}  // namespace afford

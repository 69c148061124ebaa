// Issue 12: top-down attention and multi-step planning on generated
// scenarios, as a plain loop and as a choreography of the processes (with a
// process killed and restarted mid-test).
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "experiment/design/generate.hpp"
#include "tests/in_process.hpp"
#include "tests/reference_loops.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

const std::string kConfigDir = std::string(AFFORD_SOURCE_DIR) + "/config";
// Scenarios of these tests come from this seed; the experiments draw theirs from others.
constexpr std::int64_t kScenarioSeed = 901;

// An IMP agent of the base world, trained once for every test of this file.
struct Agent {
  std::string checkpoint;
  std::unique_ptr<Predictors> predictors;
  RunConfig world;
};
const Agent& agent() {
  static const Agent a = [] {
    Agent out;
    out.world = parseRunConfigText(test::baseYaml(System::IMP, 6000, 7));
    out.checkpoint = test::tempDir("attention") + "/predictors.ckpt";
    test::runIntrinsic(out.world).save(out.checkpoint);
    out.predictors = std::make_unique<Predictors>(out.world);
    out.predictors->load(out.checkpoint);
    return out;
  }();
  return a;
}

std::vector<std::string> settings(const char* attention, int depth) {
  return {std::string("eye.attention=") + attention, "planner.search.max_depth=" + std::to_string(depth),
          "planner.budget=300", "planner.max_attempts=100"};
}

std::string testYaml(const GeneratedScenario& g, std::int64_t seed, const std::vector<std::string>& s) {
  return emitYaml(extrinsicConfig(kConfigDir, RunRequest{"base", System::IMP, seed, std::nullopt, s}, agent().checkpoint,
                                  g.scenario));
}

test::GoalTestOutcome plain(const std::string& yaml) {
  const RunConfig c = parseRunConfigText(yaml);
  return test::runGoalTest(c, *c.scenario, *agent().predictors);
}

void expectSame(const ExtrinsicOutcome& got, const test::GoalTestOutcome& ref, const std::string& what) {
  EXPECT_EQ(got.success, ref.success) << what;
  EXPECT_EQ(got.completion, ref.completion) << what;
  EXPECT_EQ(got.attempts, ref.attempts) << what;
  ASSERT_EQ(got.sub_goals.size(), ref.sub_goals.size()) << what;
  for (std::size_t i = 0; i < ref.sub_goals.size(); ++i) {
    EXPECT_EQ(got.sub_goals[i].iterations, ref.sub_goals[i].iterations) << what << " sub-goal " << i;
    EXPECT_EQ(got.sub_goals[i].actions_checked, ref.sub_goals[i].actions_checked) << what << " sub-goal " << i;
    EXPECT_EQ(got.sub_goals[i].reached, ref.sub_goals[i].reached) << what << " sub-goal " << i;
  }
}

// Top-down attention goes from one sub-goal to the next: on generated
// scenarios of 1 to 8 sub-goals it needs about one iteration per sub-goal,
// where the bottom-up scan needs many more as sub-goals grow.
TEST(Attention, TopDownNeedsAboutOneIterationPerSubGoal) {
  for (int k : {1, 4, 8}) {
    double top_down = 0, bottom_up = 0;
    int solved_top = 0, solved_bottom = 0;
    for (int i = 0; i < 3; ++i) {
      const GeneratedScenario g = generateScenario(agent().world, ScenarioSpec{k, k, 0}, kScenarioSeed, i);
      const test::GoalTestOutcome t = plain(testYaml(g, 40 + i, settings("top_down", 1)));
      const test::GoalTestOutcome b = plain(testYaml(g, 40 + i, settings("bottom_up", 1)));
      solved_top += t.success;
      solved_bottom += b.success;
      top_down += t.completion;
      bottom_up += b.completion;
    }
    EXPECT_EQ(solved_top, 3) << k << " sub-goals";
    EXPECT_GE(solved_top, solved_bottom) << k << " sub-goals";
    EXPECT_LE(top_down / 3, 1.5 * k) << k << " sub-goals: mean iterations";
    if (k == 8) {
      EXPECT_GT(bottom_up / solved_bottom, 2.0 * top_down / 3) << "bottom-up should need far more";
    }
  }
}

// A sub-goal that changes an object's colour and place needs two actions:
// the one-step planner finds no action for it, the multi-step one a plan of
// two, whose first action it takes, then the second on the same object.
TEST(Attention, MultiStepPlansSolveTwoActionSubGoals) {
  for (const char* attention : {"bottom_up", "top_down"})
    for (int i = 0; i < 3; ++i) {
      const GeneratedScenario g = generateScenario(agent().world, ScenarioSpec{2, 2, 2}, kScenarioSeed, i);
      const test::GoalTestOutcome one = plain(testYaml(g, 60 + i, settings(attention, 1)));
      const test::GoalTestOutcome two = plain(testYaml(g, 60 + i, settings(attention, 2)));
      EXPECT_FALSE(one.success) << attention << " " << g.scenario.name;
      EXPECT_TRUE(two.success) << attention << " " << g.scenario.name;
      EXPECT_GE(two.attempts, 4) << attention << " " << g.scenario.name << ": two actions per sub-goal";
    }
}

// The search is bounded: with one query per iteration, depth 2 is depth 1.
TEST(Attention, TheQueryBoundStopsTheSearch) {
  const GeneratedScenario g = generateScenario(agent().world, ScenarioSpec{1, 1, 1}, kScenarioSeed, 0);
  std::vector<std::string> s = settings("top_down", 2);
  s.push_back("planner.search.max_queries=1");
  const test::GoalTestOutcome bounded = plain(testYaml(g, 70, s));
  EXPECT_FALSE(bounded.success);
  EXPECT_EQ(bounded.attempts, 0);
}

// The choreography computes what the plain loop computes, with top-down
// attention and with multi-step plans, also when the planner or the eye is
// killed and restarted in the middle of a test: their memory of objects and
// plans is rebuilt from the run's messages.
TEST(Attention, TheProcessesComputeThePlainLoopAlsoAfterARestart) {
  struct Case {
    ScenarioSpec spec;
    const char* attention;
    int depth;
    const char* restart;
  };
  for (const Case& c : {Case{{6, 6, 0}, "top_down", 1, ""}, Case{{3, 3, 2}, "top_down", 2, ""},
                        Case{{2, 2, 1}, "bottom_up", 2, ""}, Case{{6, 6, 0}, "top_down", 1, "planner"},
                        Case{{3, 3, 2}, "top_down", 2, "eye"}, Case{{3, 3, 2}, "top_down", 2, "planner"}}) {
    const GeneratedScenario g = generateScenario(agent().world, c.spec, kScenarioSeed, 1);
    const std::string yaml = testYaml(g, 80, settings(c.attention, c.depth));
    const std::string what = g.scenario.name + " " + c.attention + " depth " + std::to_string(c.depth) +
                             (*c.restart ? std::string(" restarting the ") + c.restart : std::string());
    const test::InProcessRun run(yaml, System::IMP, 80, parseRunConfigText(yaml).planner.budget, {}, 50, false,
                                 test::Restart{c.restart, 2, ""});
    ASSERT_TRUE(run.outcome.ok) << what << ": " << run.outcome.error << "\n" << run.log.str().substr(0, 3000);
    if (*c.restart) {
      EXPECT_TRUE(run.restarted) << what;
    }
    const test::GoalTestOutcome ref = plain(yaml);
    EXPECT_TRUE(ref.success) << what;
    expectSame(run.outcome.extrinsic, ref, what);
  }
}

}  // namespace
}  // namespace afford

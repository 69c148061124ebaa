#include <gtest/gtest.h>

#include <cmath>

#include "planner/planner.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

using Kind = PlannerRequest::Kind;
using A = std::array<double, kNumActions>;

View view(std::uint8_t fill, double x, double y) { return {std::vector<std::uint8_t>(1323, fill), x, y}; }
ForwardPrediction prediction(int action, double fill, double x, double y) {
  return {action, std::vector<double>(1323, fill), x, y};
}

struct PlannerTest : ::testing::Test {
  PlannerConfig config = test::shippedConfig().planner;
  Planner planner{config};
  const View goal = view(255, 0.2, 0.5);  // the sub-goal as the goal image shows it
  const View scene_differs = view(0, 0.2, 0.5);

  // Start an iteration and get to the scene scan of an active sub-goal.
  void reachScan() {
    ASSERT_EQ(planner.startIteration().kind, Kind::LookAtGoal);
    const PlannerRequest r = planner.onView(goal);
    ASSERT_EQ(r.kind, Kind::LookAtSceneAt);
    EXPECT_DOUBLE_EQ(r.x, 0.2);
    EXPECT_DOUBLE_EQ(r.y, 0.5);
    ASSERT_EQ(planner.onView(scene_differs).kind, Kind::ScanScene);
  }
};

TEST(PlannerDistances, ImagesAndPositions) {
  const std::vector<std::uint8_t> a(1323, 0), b(1323, 255);
  EXPECT_DOUBLE_EQ(imageDistance(a, a), 0.0);
  EXPECT_NEAR(imageDistance(a, b), std::sqrt(1323.0) / 1323.0, 1e-12);
  EXPECT_NEAR(imageDistance(std::vector<double>(1323, 0.9), b), 0.1 / std::sqrt(1323.0), 1e-12);
  EXPECT_DOUBLE_EQ(positionDistance(0.2, 0.2, 0.2, 0.2, PositionMetric::Euclidean), 0.0);
  EXPECT_NEAR(positionDistance(0.0, 0.0, 0.03, 0.04, PositionMetric::Euclidean), 0.05, 1e-12);
  EXPECT_NEAR(positionDistance(0.0, 0.0, 0.03, 0.04, PositionMetric::HalfEuclidean), 0.025, 1e-12);
}

TEST_F(PlannerTest, ASubGoalAlreadyReachedEndsTheIteration) {
  ASSERT_EQ(planner.startIteration().kind, Kind::LookAtGoal);
  planner.onView(goal);
  EXPECT_EQ(planner.onView(goal).kind, Kind::IterationDone);
  EXPECT_FALSE(planner.subGoalActive());
  ASSERT_EQ(planner.subGoals().size(), 1u);
  EXPECT_TRUE(planner.subGoals()[0].reached);
  EXPECT_EQ(planner.startIteration().kind, Kind::LookAtGoal);  // next iteration: a new sub-goal
}

TEST_F(PlannerTest, AnAffordedActionWhosePredictedEffectIsTheSubGoalIsTaken) {
  reachScan();
  PlannerRequest r = planner.onObject(view(0, 0.2, 0.5), A{0.1, 0.9, 0.2, 0.1});
  ASSERT_EQ(r.kind, Kind::Forward);
  EXPECT_EQ(r.actions, std::vector<int>{kTurnGreen});  // only what the object affords
  r = planner.onForward({prediction(kTurnGreen, 0.999, 0.2, 0.5)});
  ASSERT_EQ(r.kind, Kind::Act);
  EXPECT_EQ(r.action, kTurnGreen);
  EXPECT_DOUBLE_EQ(r.object_x, 0.2);
  EXPECT_EQ(planner.attempts(), 1);
  r = planner.onActed();
  ASSERT_EQ(r.kind, Kind::LookAtSceneAt);  // check the sub-goal again
  EXPECT_EQ(planner.onView(goal).kind, Kind::IterationDone);
  EXPECT_TRUE(planner.subGoals()[0].reached);
  EXPECT_EQ(planner.subGoals()[0].actions_checked, 1);
}

TEST_F(PlannerTest, WithoutRestrictionEveryActionIsChecked) {
  config.restrict_by_affordance = false;
  Planner all(config);
  ASSERT_EQ(all.startIteration().kind, Kind::LookAtGoal);
  all.onView(goal);
  all.onView(scene_differs);
  const PlannerRequest r = all.onObject(view(0, 0.2, 0.5), A{0.1, 0.9, 0.2, 0.1});
  EXPECT_EQ(r.actions, (std::vector<int>{0, 1, 2, 3}));
}

TEST_F(PlannerTest, AMoveIsSentToTheSubGoalPosition) {
  reachScan();
  planner.onObject(view(0, 0.5, 0.8), A{0.9, 0.9, 0.9, 0.9});
  const PlannerRequest r = planner.onForward({prediction(kMove, 1.0, 0.2, 0.5)});
  ASSERT_EQ(r.kind, Kind::Act);
  EXPECT_EQ(r.action, kMove);
  EXPECT_DOUBLE_EQ(r.x, 0.2);
  EXPECT_DOUBLE_EQ(r.y, 0.5);
  EXPECT_DOUBLE_EQ(r.object_x, 0.5);
}

// The table's push and carry take a place as the grid's move does (takesPlace): each is sent to the sub-goal's,
// and topple and roll to none.
TEST_F(PlannerTest, EachActionOfTheWorldThatTakesAPlaceIsSentToTheSubGoalPosition) {
  const RunConfig table = test::shippedConfig("table");
  ASSERT_EQ(table.planner.world, WorldKind::Table);
  for (int action = 0; action < kNumActions; ++action) {
    PlannerConfig c = config;
    c.world = WorldKind::Table;
    Planner p{c};
    ASSERT_EQ(p.startIteration().kind, Kind::LookAtGoal);
    ASSERT_EQ(p.onView(goal).kind, Kind::LookAtSceneAt);
    ASSERT_EQ(p.onView(scene_differs).kind, Kind::ScanScene);
    p.onObject(view(0, 0.5, 0.8), A{0.9, 0.9, 0.9, 0.9});
    std::vector<ForwardPrediction> predicted;
    for (int a = 0; a < kNumActions; ++a)  // the action's prediction meets the sub-goal; the others' miss it
      predicted.push_back(prediction(a, a == action ? 1.0 : 0.0, a == action ? 0.2 : 0.9, a == action ? 0.5 : 0.1));
    const PlannerRequest r = p.onForward(predicted);
    ASSERT_EQ(r.kind, Kind::Act) << action;
    EXPECT_EQ(r.action, action);
    const bool place = action == 0 || action == 1;  // push, carry
    EXPECT_DOUBLE_EQ(r.x, place ? 0.2 : -1.0) << actionName(WorldKind::Table, action);
    EXPECT_DOUBLE_EQ(r.y, place ? 0.5 : -1.0) << actionName(WorldKind::Table, action);
  }
}

TEST_F(PlannerTest, PredictionsThatMissTheImageOrThePlaceAreNotTaken) {
  reachScan();
  planner.onObject(view(0, 0.5, 0.8), A{0.9, 0.9, 0.9, 0.9});
  const PlannerRequest r = planner.onForward({prediction(kMove, 0.8, 0.2, 0.5),      // image off by 0.2 per value
                                              prediction(kTurnGreen, 1.0, 0.5, 0.8)}); // right look, wrong place
  EXPECT_EQ(r.kind, Kind::IterationDone);
  EXPECT_EQ(planner.subGoals()[0].actions_checked, 2);
  EXPECT_EQ(planner.attempts(), 0);
}

TEST_F(PlannerTest, ASubGoalTimesOutAfterItsIterations) {
  for (int i = 0; i < config.subgoal_timeout; ++i) {
    if (i == 0)
      reachScan();
    else
      ASSERT_EQ(planner.startIteration().kind, Kind::ScanScene) << "iteration " << i;
    ASSERT_EQ(planner.onObject(view(0, 0.5, 0.8), A{0.1, 0.1, 0.1, 0.1}).kind, Kind::IterationDone);
  }
  EXPECT_EQ(planner.subGoals()[0].iterations, config.subgoal_timeout);
  EXPECT_EQ(planner.startIteration().kind, Kind::LookAtGoal);  // time out: another sub-goal
}

TEST_F(PlannerTest, RepliesOutOfTurnAreRefused) {
  EXPECT_THROW(planner.onActed(), std::logic_error);
  EXPECT_THROW(planner.onForward({}), std::logic_error);
  planner.startIteration();
  EXPECT_THROW(planner.startIteration(), std::logic_error);
}

// ---- utility-based planner (Algorithm 3)

struct UtilityPlannerTest : ::testing::Test {
  PlannerConfig config = [] {
    PlannerConfig c = test::shippedConfig().planner;
    c.kind = PlannerKind::Utility;
    return c;
  }();
  // Two goals: value 1 at (0.2, 0.5), value 4 at (0.2, 0.2).
  Planner planner{config, {{0.2, 0.5, 1.0}, {0.2, 0.2, 4.0}}};

  // One iteration that picks the sub-goal at `at`, finds an object whose
  // turn-green affordance is `affordance` and whose predicted effect matches.
  // (If a sub-goal is still active, it must be the one at `at`.)
  PlannerRequest planFor(const View& at, double affordance) {
    if (planner.startIteration().kind == Kind::LookAtGoal) {
      planner.onView(at);
      EXPECT_EQ(planner.onView(view(0, at.x, at.y)).kind, Kind::ScanScene);
    }
    EXPECT_EQ(planner.onObject(view(0, at.x, at.y), A{0.1, affordance, 0.1, 0.1}).kind, Kind::Forward);
    return planner.onForward({prediction(kTurnGreen, 1.0, at.x, at.y)});
  }
};

TEST_F(UtilityPlannerTest, SubGoalsTakeTheValueOfTheNearestGoal) {
  EXPECT_DOUBLE_EQ(planner.subGoalValue(0.2, 0.5), 1.0);
  EXPECT_DOUBLE_EQ(planner.subGoalValue(0.21, 0.19), 4.0);
}

TEST_F(UtilityPlannerTest, EvaluationRaisesThePotentialUtilityWithoutActing) {
  const View low = view(255, 0.2, 0.5), high = view(255, 0.2, 0.2);
  EXPECT_EQ(planFor(low, 0.8).kind, Kind::IterationDone);  // U = 0.8 x 1
  EXPECT_NEAR(planner.potentialUtility(), 0.8, 1e-12);      // nu = 1: the estimate becomes U
  EXPECT_EQ(planFor(high, 0.6).kind, Kind::IterationDone);  // U = 0.6 x 4
  EXPECT_NEAR(planner.potentialUtility(), 2.4, 1e-12);
  EXPECT_EQ(planFor(low, 0.8).kind, Kind::IterationDone);   // lower U: the estimate stays
  EXPECT_NEAR(planner.potentialUtility(), 2.4, 1e-12);
  EXPECT_EQ(planner.attempts(), 0);
  EXPECT_FALSE(planner.subGoalActive());  // each planned couple ends its sub-goal
}

TEST_F(UtilityPlannerTest, ActsOnlyWhenTheUtilityReachesThePotentialAndLowersItPerChosenAction) {
  const View low = view(255, 0.2, 0.5), high = view(255, 0.2, 0.2);
  planFor(high, 0.6);  // estimate 2.4
  while (planner.evaluating()) {  // spend the evaluation period on iterations that find nothing
    if (planner.startIteration().kind == Kind::LookAtGoal) {
      planner.onView(low);
      ASSERT_EQ(planner.onView(view(0, 0.2, 0.5)).kind, Kind::ScanScene);
    }
    ASSERT_EQ(planner.onObject(view(0, 0.8, 0.8), A{0.1, 0.1, 0.1, 0.1}).kind, Kind::IterationDone);
  }
  EXPECT_NEAR(planner.potentialUtility(), 2.4, 1e-12);
  // U = 0.8 < 2.4: not taken, but the estimate falls by 10%.
  EXPECT_EQ(planFor(low, 0.8).kind, Kind::IterationDone);
  EXPECT_NEAR(planner.potentialUtility(), 2.16, 1e-12);
  EXPECT_EQ(planner.attempts(), 0);
  // U = 2.4 >= 2.16: taken; the estimate falls again; no check of the sub-goal follows.
  const PlannerRequest r = planFor(high, 0.6);
  ASSERT_EQ(r.kind, Kind::Act);
  EXPECT_EQ(r.action, kTurnGreen);
  EXPECT_NEAR(planner.potentialUtility(), 1.944, 1e-12);
  EXPECT_EQ(planner.onActed().kind, Kind::IterationDone);
  EXPECT_EQ(planner.attempts(), 1);
  EXPECT_EQ(planner.startIteration().kind, Kind::LookAtGoal);  // another sub-goal
}

}  // namespace
}  // namespace afford

#include <gtest/gtest.h>

#include "experiment/design/design.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

TEST(Welch, MatchesAWorkedExample) {
  // Two samples with unequal variances. Expected values by hand from Welch's
  // formulas: t = -3.5645, df = 6.9723; p = 0.009224 by numerical integration
  // of the t density (independent of GSL).
  const std::vector<double> a{1, 2, 3, 4, 5}, b{4, 6, 8, 10, 12, 14};
  const WelchResult w = welchTest(a, b);
  EXPECT_NEAR(w.mean_a, 3.0, 1e-12);
  EXPECT_NEAR(w.mean_b, 9.0, 1e-12);
  // var a = 2.5, var b = 14: se^2 = 0.5 + 14/6
  EXPECT_NEAR(w.t, -6.0 / std::sqrt(0.5 + 14.0 / 6.0), 1e-12);
  const double va = 0.5, vb = 14.0 / 6.0;
  EXPECT_NEAR(w.df, (va + vb) * (va + vb) / (va * va / 4 + vb * vb / 5), 1e-12);
  EXPECT_NEAR(w.t, -3.564531, 1e-6);
  EXPECT_NEAR(w.df, 6.972256, 1e-6);
  EXPECT_NEAR(w.p, 0.009224, 1e-6);
}

TEST(Welch, IsSymmetricAndOneForEqualMeans) {
  const std::vector<double> a{1, 3, 5, 7}, b{2, 4, 4, 6};
  const WelchResult ab = welchTest(a, b), ba = welchTest(b, a);
  EXPECT_NEAR(ab.p, ba.p, 1e-15);
  EXPECT_NEAR(ab.t, -ba.t, 1e-15);
  EXPECT_NEAR(ab.p, 1.0, 1e-12);  // both means are 4
}

TEST(Welch, AFarShiftGivesATinyP) {
  std::vector<double> a, b;
  for (int i = 0; i < 50; ++i) a.push_back(i % 5), b.push_back(10 + i % 5);
  EXPECT_LT(welchTest(a, b).p, 1e-20);
}

TEST(Welch, RefusesSamplesTooSmall) { EXPECT_THROW(welchTest({1.0}, {1.0, 2.0}), std::invalid_argument); }

TEST(Design, ConditionsAreEveryCombinationFirstKeySlowest) {
  ExtrinsicDesign d;
  d.vary = {{"planner.kind", {"goal", "utility"}}, {"planner.max_attempts", {"1", "2", "3"}}};
  const auto cs = conditionsOf(d);
  ASSERT_EQ(cs.size(), 6u);
  EXPECT_EQ(cs[0].label, "planner.kind=goal planner.max_attempts=1");
  EXPECT_EQ(cs[4].value("planner.kind"), "utility");
  EXPECT_EQ(cs[4].value("planner.max_attempts"), "2");
  EXPECT_EQ(cs[4].value("planner.budget"), "");
  EXPECT_EQ(conditionsOf(ExtrinsicDesign{}).size(), 1u);
}

TEST(Design, UtilityAnalysisComparesThePlannersPerBudget) {
  ExtrinsicDesign d;
  d.vary = {{"planner.kind", {"goal", "utility"}}, {"planner.max_attempts", {"1", "2"}}};
  d.analysis = "utility";
  const auto cs = conditionsOf(d);
  std::vector<TestRecord> tests;
  for (int c = 0; c < 4; ++c)
    for (int i = 0; i < 10; ++i) {
      TestRecord t;
      t.system = "IMP";
      t.agent = i % 2;
      t.scenario = "utility";
      t.condition = c;
      t.ok = true;
      t.utility = (c >= 2 ? 4.0 : 1.0) + (i % 2);  // the utility planner gains 3 more
      t.active_sub_goals = 2;
      t.actions_checked = 3;
      tests.push_back(t);
    }
  tests[0].ok = false;  // an infrastructure failure is not a result
  Summary summary;
  summariseDesign(summary, tests, cs, d, {"IMP"}, {"utility"});
  ASSERT_TRUE(summary.utility);
  const UtilityAnalysis& u = *summary.utility;
  EXPECT_EQ(u.budgets, std::vector<std::int64_t>({1, 2}));
  EXPECT_NEAR(u.goal_mean[0], (4 * 1.0 + 5 * 2.0) / 9, 1e-12);
  EXPECT_NEAR(u.utility_mean[1], 4.5, 1e-12);
  ASSERT_TRUE(u.p_values[0]);
  EXPECT_LT(*u.p_values[0], 1e-6);
  const auto& cond = summary.systems.at("IMP").extrinsic->conditions->at(0).scenarios.at("utility");
  EXPECT_EQ(cond.tests, 10);
  EXPECT_EQ(cond.tests_completed, 9);
  EXPECT_NEAR(cond.actions_checked_per_sub_goal.mean, 1.5, 1e-12);
  EXPECT_EQ(cond.utility_agent_means.size(), 2u);
}

TEST(Design, TheCompletionFitRecoversAQuadraticAndNeedsTwoSubGoalCounts) {
  std::vector<std::pair<double, double>> points;
  for (int x = 1; x <= 5; ++x) points.emplace_back(x, 1.364 * x * x - 0.808 * x);
  const auto fit = fitCompletion(points);
  ASSERT_TRUE(fit);
  EXPECT_NEAR(fit->a, 1.364, 1e-9);
  EXPECT_NEAR(fit->b, -0.808, 1e-9);
  EXPECT_FALSE(fitCompletion({{3, 9}, {3, 10}, {3, 8}}));  // one sub-goal count: a and b are not determined
  EXPECT_FALSE(fitCompletion({}));
}

// With several conditions each gets its own completion steps per scenario and its own fit over its solved tests.
TEST(Design, EachConditionHasItsOwnCompletionFit) {
  ExtrinsicDesign d;
  d.vary = {{"eye.attention", {"a", "b"}}};
  const auto cs = conditionsOf(d);
  std::vector<TestRecord> tests;
  for (int c = 0; c < 2; ++c)
    for (int k = 1; k <= 4; ++k)
      for (int i = 0; i < 3; ++i) {
        TestRecord t;
        t.system = "IMP";
        t.agent = static_cast<std::size_t>(i);
        t.scenario = "s" + std::to_string(k);
        t.condition = c;
        t.ok = true;
        t.sub_goals = k;
        t.success = i < 2;  // the third test of each fails: it does not count
        t.completion = t.success ? (c == 0 ? k * k : 2 * k) : 0;
        tests.push_back(t);
      }
  Summary summary;
  summariseDesign(summary, tests, cs, d, {"IMP"}, {"s1", "s2", "s3", "s4"});
  const auto& conds = *summary.systems.at("IMP").extrinsic->conditions;
  ASSERT_TRUE(conds[0].completion_fit && conds[1].completion_fit);
  EXPECT_NEAR(conds[0].completion_fit->a, 1.0, 1e-9);
  EXPECT_NEAR(conds[0].completion_fit->b, 0.0, 1e-9);
  EXPECT_NEAR(conds[1].completion_fit->a, 0.0, 1e-9);
  EXPECT_NEAR(conds[1].completion_fit->b, 2.0, 1e-9);
  const auto& s3 = conds[0].scenarios.at("s3");
  EXPECT_EQ(s3.sub_goals, 3);
  EXPECT_EQ(s3.completion_steps.n, 2);
  EXPECT_NEAR(s3.completion_steps.median, 9.0, 1e-12);
}

TEST(Design, AnAnalysisWithoutItsConditionsSaysWhatIsMissing) {
  ExtrinsicDesign d;
  d.vary = {{"planner.kind", {"goal", "utility"}}};
  d.analysis = "utility";
  Summary summary;
  try {
    summariseDesign(summary, {}, conditionsOf(d), d, {"IMP"}, {"utility"});
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("extrinsic.vary.planner.max_attempts"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace afford

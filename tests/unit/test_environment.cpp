#include <gtest/gtest.h>

#include "afford/actions.hpp"
#include "environment/environment.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

int index(const Environment& env, const std::string& name, const RunConfig& c) {
  for (std::size_t i = 0; i < c.world.objects.size(); ++i)
    if (c.world.objects[i].name == name) return static_cast<int>(i);
  return -1;
}

double ux(const WorldObject& o, const RunConfig& c) { return toUnit(o.centre.col, c.world.size_px); }
double uy(const WorldObject& o, const RunConfig& c) { return toUnit(o.centre.row, c.world.size_px); }

TEST(Environment, StartsWithTheLayoutOfTheAuthorsCode) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  const cv::Mat scene = env.render();
  EXPECT_EQ(scene.at<cv::Vec3b>(30, 30), cv::Vec3b(255, 0, 0));    // red square at (0.2, 0.2)
  EXPECT_EQ(scene.at<cv::Vec3b>(75, 75), cv::Vec3b(0, 255, 0));    // green circle at (0.5, 0.5)
  EXPECT_EQ(scene.at<cv::Vec3b>(120, 120), cv::Vec3b(0, 0, 255));  // blue rectangle at (0.8, 0.8)
  EXPECT_EQ(scene.at<cv::Vec3b>(75, 50), cv::Vec3b(0, 0, 0));
}

TEST(Environment, ColourActionRecoloursTheObjectUnderTheGaze) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  const int i = index(env, "red square", c);
  const ActionOutcome out = env.execute(0, kTurnGreen, 0.2, 0.2);
  EXPECT_TRUE(out.on_object);
  EXPECT_TRUE(out.succeeded);
  EXPECT_EQ(env.objects()[i].colour, Colour::Green);
  EXPECT_EQ(env.render().at<cv::Vec3b>(30, 30), cv::Vec3b(0, 255, 0));
}

TEST(Environment, TurningAnObjectIntoItsOwnColourChangesNothing) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  const cv::Mat before = env.render();
  EXPECT_FALSE(env.execute(0, kTurnRed, 0.2, 0.2).succeeded);
  EXPECT_EQ(cv::norm(before, env.render(), cv::NORM_L1), 0.0);
}

TEST(Environment, AffordancesFollowTheObjectsCurrentLook) {
  // late2: circles afford nothing; a square turned green is a green square.
  const RunConfig c = test::shippedConfig("late2");
  Environment env(c);
  ASSERT_TRUE(env.execute(0, kTurnGreen, 0.2, 0.2).succeeded);  // red square -> green square
  EXPECT_FALSE(env.execute(1, kTurnGreen, 0.2, 0.2).succeeded);  // a green square cannot turn green
  EXPECT_TRUE(env.execute(2, kTurnRed, 0.2, 0.2).succeeded);     // but can turn red again
  EXPECT_FALSE(env.execute(3, kTurnBlue, 0.5, 0.2).succeeded);   // the red circle affords nothing
}

TEST(Environment, IntrinsicMoveGoesToARandomFreePlaceInTheTable) {
  const RunConfig c = test::shippedConfig();
  for (int step = 0; step < 50; ++step) {
    Environment env(c);
    const ActionOutcome out = env.execute(step, kMove, 0.5, 0.5);
    ASSERT_TRUE(out.succeeded) << "step " << step;
    const auto& o = env.objects()[index(env, "green circle", c)];
    EXPECT_DOUBLE_EQ(ux(o, c), out.target_x);
    EXPECT_DOUBLE_EQ(uy(o, c), out.target_y);
    EXPECT_GE(out.target_x, c.world.table_min);
    EXPECT_LE(out.target_x, c.world.table_max);
    // Free: no other object within the focus window around the new place.
    for (const auto& other : env.objects()) {
      if (&other == &o) continue;
      EXPECT_GT(std::max(std::abs(other.centre.col - o.centre.col), std::abs(other.centre.row - o.centre.row)), 10 + 7);
    }
  }
}

TEST(Environment, MoveTargetsAreKeyedBySeedAndStep) {
  const RunConfig c = test::shippedConfig();
  Environment a(c), b(c);
  EXPECT_DOUBLE_EQ(a.execute(17, kMove, 0.5, 0.5).target_x, b.execute(17, kMove, 0.5, 0.5).target_x);
  Environment d(c), e(c);
  const ActionOutcome at17 = d.execute(17, kMove, 0.5, 0.5), at18 = e.execute(18, kMove, 0.5, 0.5);
  EXPECT_TRUE(at17.target_x != at18.target_x || at17.target_y != at18.target_y);
}

TEST(Environment, CommandedMoveToAnOccupiedPlaceDoesNothing) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  const ActionOutcome out = env.execute(0, kMove, 0.5, 0.5, std::make_pair(0.2, 0.2));
  EXPECT_FALSE(out.succeeded);
  EXPECT_EQ(env.objects()[index(env, "green circle", c)].centre, (Pixel{75, 75}));
}

TEST(Environment, ActionOnEmptySpaceHasNoEffect) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  const ActionOutcome out = env.execute(0, kTurnBlue, 0.35, 0.35);
  EXPECT_FALSE(out.on_object);
  EXPECT_FALSE(out.succeeded);
}

TEST(Environment, StochasticSuccessMatchesTheTable) {
  const RunConfig c = test::shippedConfig("stochastic");  // red objects move with p = 0.6 (Table 7)
  int successes = 0;
  const int n = 3000;
  for (int step = 0; step < n; ++step) {
    Environment env(c);
    successes += env.execute(step, kMove, 0.2, 0.2).succeeded;
  }
  EXPECT_NEAR(static_cast<double>(successes) / n, 0.6, 0.03);
}

TEST(Environment, LateObjectsAppearAtTheirStep) {
  const RunConfig c = test::shippedConfig("late1");
  Environment env(c);
  const int rect = index(env, "red rectangle", c);
  EXPECT_FALSE(env.objects()[rect].present);
  EXPECT_FALSE(env.objectsAppearAt(1999));
  EXPECT_TRUE(env.objectsAppearAt(2000));
  EXPECT_TRUE(env.introduceObjectsAt(2000));
  EXPECT_TRUE(env.objects()[rect].present);
  EXPECT_FALSE(env.execute(2000, kMove, 0.8, 0.2).succeeded);  // late1 rectangles are not movable
}

TEST(Environment, ProbeImagesAreWhatTheEyeSeesOfEachObject) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  const auto probes = env.probeImages();
  ASSERT_EQ(probes.size(), 9u);
  const cv::Mat scene = env.render();
  for (std::size_t i = 0; i < probes.size(); ++i)
    EXPECT_EQ(probes[i], cropFocus(scene, env.objects()[i].centre, c.eye.focus_side)) << c.world.objects[i].name;
}

}  // namespace
}  // namespace afford

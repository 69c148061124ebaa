#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "afford/image.hpp"
#include "tests/support.hpp"
#include "viewer/viewer.hpp"

namespace afford {
namespace {

double spread(const cv::Mat& m) {
  cv::Scalar mean, sd;
  cv::meanStdDev(m, mean, sd);
  return sd[0] + sd[1] + sd[2];
}

TEST(Viewer, DrawsWhatItIsFed) {
  Viewer v(50);
  const cv::Mat empty = v.render();
  ASSERT_FALSE(empty.empty());
  EXPECT_EQ(empty.type(), CV_8UC3);

  const RunConfig c = test::shippedConfig();
  cv::Mat scene = blankScene(150);
  paintObject(scene, Shape::Square, Colour::Red, 0.2, 0.2, c.world);
  v.onRun("r1", "intrinsic base IMP");
  v.onScene(3, scene, false);
  v.onFocus(3, cropFocus(scene, {30, 30}, 21), 21, 0.2, 0.2, false);
  v.onPrediction(3, {0.9, 0.1, 0.5, 0.7});
  for (int t = 0; t < 20; ++t) v.onDecision(t, t % 2 == 0, 0, 0.5 + 0.01 * t, 0.4);
  const cv::Mat full = v.render();
  EXPECT_EQ(full.size(), empty.size());
  EXPECT_GT(spread(full), spread(empty));  // the scene, bars and traces add structure
  EXPECT_EQ(v.step(), 19);

  // The red square shows in the scene panel (BGR: red is channel 2).
  cv::Mat diff;
  cv::absdiff(full, empty, diff);
  EXPECT_GT(cv::countNonZero(diff.reshape(1)), 1000);
}

// The goals phase: the agent's own goal boxed on the scene, its image as the sub-goal, its goals counted.
TEST(Viewer, ShowsTheAgentsOwnGoalAndTheGoalsReached) {
  const RunConfig c = test::shippedConfig();
  cv::Mat scene = blankScene(150);
  paintObject(scene, Shape::Square, Colour::Red, 0.2, 0.2, c.world);
  cv::Mat green = blankScene(150);
  paintObject(green, Shape::Square, Colour::Green, 0.2, 0.2, c.world);
  Viewer plain(50), goals(50);
  for (Viewer* v : {&plain, &goals}) {
    v->onRun("r1", "goals base GOALS");
    v->onScene(3, scene, false);
  }
  goals.onGoal(3, 7, "colour", cropFocus(green, {30, 30}, 21), 21, 0.2, 0.2);
  goals.onGoalResult(4, 7, "colour", true);
  goals.onGoalResult(6, 8, "move", false);
  const cv::Mat a = plain.render(), b = goals.render();
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  EXPECT_GT(cv::countNonZero(diff.reshape(1)), 1500);  // the box, the sub-goal panel, the header and the counts
  EXPECT_EQ(goals.step(), 6);
}

TEST(Viewer, IgnoresAFocusOfTheWrongSize) {
  Viewer v;
  const cv::Mat before = v.render();
  v.onFocus(1, std::vector<std::uint8_t>(10, 255), 21, 0.5, 0.5, false);
  cv::Mat diff;
  cv::absdiff(before, v.render(), diff);
  // Only the step in the header may change.
  EXPECT_LT(cv::countNonZero(diff.reshape(1)), 400);
}

}  // namespace
}  // namespace afford

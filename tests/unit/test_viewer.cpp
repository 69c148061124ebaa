#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

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

// A scene of the table world is 320 x 240: drawn in its proportions, the gaze boxed where the object is (places are
// a column or row over the width), and the actions named as that world names them.
TEST(Viewer, AWideSceneKeepsItsProportionsAndTheGazeBoxIsOnTheObject) {
  Viewer v(50);
  cv::Mat scene(240, 320, CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Point object(80, 200);  // near the bottom: a square panel's rows would put the box above it
  cv::rectangle(scene, cv::Rect(object.x - 6, object.y - 6, 13, 13), cv::Scalar(0, 255, 0), cv::FILLED);
  v.onRun("r1", "intrinsic table IMP");
  RunConfig c = test::shippedConfig("table");
  v.onConfig(run_config_t{}, c);
  v.onScene(1, scene, false);
  v.onFocus(1, cropFocus(scene, {object.x, object.y}, 21), 21, object.x / 320.0, object.y / 320.0, false);
  std::vector<DrawnText> texts;
  const cv::Mat out = v.render(&texts);
  // The green object drawn, and the gaze's yellow (BGR 0, 255, 255) box around it: yellow pixels above, below,
  // left and right of the object's drawn centre, within the box's half-side.
  const cv::Mat panel = out(cv::Rect(0, 0, 315, 370));  // the scene's panel, above the focus's
  cv::Mat green, yellow;
  cv::inRange(panel, cv::Scalar(0, 200, 0), cv::Scalar(60, 255, 60), green);
  cv::inRange(panel, cv::Scalar(0, 200, 200), cv::Scalar(60, 255, 255), yellow);
  ASSERT_GT(cv::countNonZero(green), 20);
  const cv::Rect g = cv::boundingRect(green);
  const cv::Point at(g.x + g.width / 2, g.y + g.height / 2);
  EXPECT_NEAR(static_cast<double>(g.width) / g.height, 1.0, 0.2) << "a square object stays square";
  const cv::Rect y = cv::boundingRect(yellow);
  EXPECT_TRUE(y.contains(at)) << "the box " << y << " is around the object at " << at;
  EXPECT_LT(std::abs(y.x + y.width / 2 - at.x), 4);
  EXPECT_LT(std::abs(y.y + y.height / 2 - at.y), 4);
  bool named = false;
  for (const DrawnText& t : texts) named = named || t.text == "topple";
  EXPECT_TRUE(named) << "the table world's actions name the bars";
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

// The longest words each kind of run puts in the picture: its run id (the plan's: date-time prefix, experiment,
// table, system, seed, scenario and test; 80 characters here), its phase with the longest experiment name of
// config/experiments, the largest numbers, the longest action and goal module; the goals phase's counts per
// module (100,000 goals, as many as a 100,000-step run can end).
struct Longest {
  std::string run_id = "20261206-191500-" + std::string(48, 'x') + "-GOALS-s1000000-e99";
  std::string experiment;
  Longest() {
    for (const auto& f : std::filesystem::directory_iterator(std::string(AFFORD_SOURCE_DIR) + "/config/experiments"))
      if (f.path().stem().string().size() > experiment.size()) experiment = f.path().stem().string();
  }
};

// A viewer fed a run of `phase` ("intrinsic", "extrinsic" or "goals") and `system` with the longest of it.
Viewer fedTheLongest(const std::string& phase, const std::string& system) {
  const Longest longest;
  const RunConfig c = test::shippedConfig();
  cv::Mat scene = blankScene(150);
  paintObject(scene, Shape::Square, Colour::Red, 0.2, 0.2, c.world);
  Viewer v(400);
  v.onRun(longest.run_id, phase + " " + longest.experiment + " " + system);
  v.onScene(999999998, scene, false);
  if (phase == "extrinsic") v.onScene(999999998, scene, true);
  v.onFocus(999999998, cropFocus(scene, {30, 30}, 21), 21, 0.2, 0.2, phase == "extrinsic");
  v.onPrediction(999999998, {0.9, 0.1, 0.5, 0.7});
  for (int t = 0; t < 400; ++t) v.onDecision(999999999, true, 1, 1e-9 * t, 1e-9);  // "act: turn green"
  if (phase == "goals") {
    const char* modules[] = {"explore", "colour", "move", "colour and place"};
    for (int id = 0; id < 100000; ++id) v.onGoalResult(999999999, id, modules[id % 4], false);
    for (const char* module : modules) v.onGoalResult(999999999, 999999999, module, false);
    v.onGoal(999999999, 999999999, "colour and place", cropFocus(scene, {30, 30}, 21), 21, 0.2, 0.2);
    v.onGoalResult(999999999, 999999999, "colour and place", false);  // "... not reached"
  }
  return v;
}

// Nothing is cut at the picture's edges: the margin of 6 pixels around it is the background's, for the longest
// words of every system (the goals phase's counts ran over the right edge).
TEST(Viewer, NothingIsCutAtThePicturesEdgesForAnySystem) {
  for (const auto& [phase, system] : std::vector<std::pair<std::string, std::string>>{
           {"intrinsic", "FIX"}, {"intrinsic", "IGN"}, {"intrinsic", "IMP"}, {"extrinsic", "IMP"},
           {"goals", "GOALS"}}) {
    SCOPED_TRACE(phase + " " + system);
    const cv::Mat frame = fedTheLongest(phase, system).render();
    const int m = 6;
    cv::Mat inside = cv::Mat::zeros(frame.size(), CV_8U);
    inside(cv::Rect(m, m, frame.cols - 2 * m, frame.rows - 2 * m)).setTo(255);
    cv::Mat background;
    cv::inRange(frame, cv::Scalar(40, 40, 40), cv::Scalar(40, 40, 40), background);
    cv::Mat drawn_in_margin = ~background & ~inside;
    EXPECT_EQ(cv::countNonZero(drawn_in_margin), 0);
  }
}

// Every text of the picture whole, at a legible scale, within its room and the picture, measured with OpenCV's
// getTextSize at the scale it was drawn, for the longest words of every system.
TEST(Viewer, EveryTextFitsItsRoomForTheLongestWordsOfEverySystem) {
  for (const auto& [phase, system] : std::vector<std::pair<std::string, std::string>>{
           {"intrinsic", "FIX"}, {"intrinsic", "IGN"}, {"intrinsic", "IMP"}, {"extrinsic", "IMP"},
           {"goals", "GOALS"}}) {
    SCOPED_TRACE(phase + " " + system);
    std::vector<DrawnText> drawn;
    const cv::Mat frame = fedTheLongest(phase, system).render(&drawn);
    const cv::Rect picture(0, 0, frame.cols, frame.rows);
    ASSERT_GE(drawn.size(), 12u);
    bool counts = false;
    for (const DrawnText& t : drawn) {
      SCOPED_TRACE(t.text);
      int baseline = 0;
      const cv::Size size = cv::getTextSize(t.text, cv::FONT_HERSHEY_SIMPLEX, t.scale, 1, &baseline);
      EXPECT_TRUE(t.whole);
      EXPECT_LE(size.width, t.room.width);  // all of it, at its scale
      EXPECT_EQ(t.box.width, size.width);
      EXPECT_GE(t.scale, 0.35);
      EXPECT_EQ(t.room & picture, t.room);
      EXPECT_EQ(t.box & t.room, t.box);
      counts = counts || t.text.rfind("colour and place: 0 of 250", 0) == 0;  // (25,002 goals ended)
    }
    EXPECT_EQ(counts, phase == "goals");
  }
}

// A run id of the protocol's longest (200 bytes) is shortened in its middle, and stays in the picture.
TEST(Viewer, ARunIdTooLongForThePictureIsShortenedInItsMiddle) {
  Viewer v;
  const std::string id = "head-" + std::string(190, 'x') + "-tail";
  v.onRun(id, "goals goals GOALS");
  std::vector<DrawnText> drawn;
  const cv::Mat frame = v.render(&drawn);
  ASSERT_FALSE(drawn.empty());
  const DrawnText& header = drawn.front();
  EXPECT_EQ(header.text.rfind(id, 0), 0u);
  EXPECT_FALSE(header.whole);
  EXPECT_EQ(header.box & cv::Rect(0, 0, frame.cols, frame.rows), header.box);
  EXPECT_LE(header.box.width, header.room.width);
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

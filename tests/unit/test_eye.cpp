#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <string>

#include "afford/actions.hpp"
#include "afford/image.hpp"
#include "environment/environment.hpp"
#include "eye/eye.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

// The eye's focus is on an object: within a pixel of its centre (the
// continuous world's eye centres its window on the blob's centroid, half a
// pixel off a rectangle's real centre), and so is its reported place.
bool onAnObject(const Environment& env, const Focus& f) {
  for (const auto& o : env.objects())
    if (o.present && std::abs(f.gaze.col - o.centre.col) <= 1 && std::abs(f.gaze.row - o.centre.row) <= 1 &&
        std::abs(f.x - o.x) <= 1.0 / 150 && std::abs(f.y - o.y) <= 1.0 / 150)
      return true;
  return false;
}

TEST(Eye, ScanLandsOnAnObjectAndCentresTheFoveaOnIt) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  Eye eye(c);
  eye.setScene(env.render());
  for (int step = 0; step < 40; ++step) {
    const Focus& f = eye.scan(step);
    EXPECT_TRUE(onAnObject(env, f)) << "step " << step << " gaze " << f.gaze.col << "," << f.gaze.row;
    EXPECT_NE(eye.labelAt(f.gaze), 0);
    EXPECT_EQ(f.image.size(), 21u * 21u * 3u);
  }
}

TEST(Eye, ScanMovesToAnotherObjectEveryTimeAndVisitsThemAll) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  Eye eye(c);
  eye.setScene(env.render());
  std::set<std::pair<int, int>> visited;
  Pixel last{-1, -1};
  for (int step = 0; step < 200; ++step) {
    const Focus f = eye.scan(step);
    EXPECT_FALSE(f.gaze == last) << "step " << step;
    last = f.gaze;
    visited.insert({f.gaze.col, f.gaze.row});
  }
  EXPECT_EQ(visited.size(), 9u);
}

// ... and so in the twenty-object world, whose blobs the eye tells apart.
TEST(Eye, ScanVisitsAllTwentyObjectsOfTheLargerWorld) {
  const RunConfig c = test::shippedConfig("large-world", System::IMP, 1);
  Environment env(c);
  Eye eye(c);
  eye.setScene(env.render());
  std::set<std::pair<int, int>> visited;
  for (int step = 0; step < 1000; ++step) {
    const Focus f = eye.scan(step);
    visited.insert({f.gaze.col, f.gaze.row});
  }
  EXPECT_EQ(visited.size(), 20u);
}

TEST(Eye, ThePapersNoiseThenSmoothOrderAlsoLandsOnObjects) {
  const RunConfig c = test::shippedConfig("base", System::IMP, 1, {"eye.saliency_order=noise_then_smooth"});
  Environment env(c);
  Eye eye(c);
  eye.setScene(env.render());
  for (int step = 0; step < 20; ++step) {
    const Focus f = eye.scan(step);
    EXPECT_TRUE(onAnObject(env, f)) << "step " << step;
  }
}

TEST(Eye, ScansAreKeyedByStep) {
  const RunConfig c = test::shippedConfig();
  Environment env(c);
  Eye a(c), b(c);
  a.setScene(env.render());
  b.setScene(env.render());
  for (int step = 0; step < 20; ++step) EXPECT_EQ(a.scan(step).gaze, b.scan(step).gaze);
}

// An eye looking at the base-test scene.
struct EyeOnBaseScene : ::testing::Test {
  RunConfig c = test::shippedConfig();
  Environment env{c};
  Eye eye{c};
  void SetUp() override { eye.setScene(env.render()); }
  // Scan until the gaze is on the object at `centre`.
  void lookAt(Pixel centre) {
    for (int step = 0; step < 500; ++step)
      if (eye.scan(step).gaze == centre) return;
    FAIL() << "never looked at " << centre.col << "," << centre.row;
  }
};

TEST_F(EyeOnBaseScene, ColourChangeIsSeenAsTheTurnGreenAffordance) {
  lookAt({30, 30});  // red square
  ASSERT_TRUE(env.execute(7, kTurnGreen, 0.2, 0.2).succeeded);
  const Effect e = eye.scanEffect(7, env.render(), kTurnGreen);
  EXPECT_TRUE(e.image_changed);
  EXPECT_FALSE(e.position_changed);
  EXPECT_TRUE(e.affordance);
  EXPECT_EQ(e.after.gaze, (Pixel{30, 30}));
  EXPECT_NEAR(e.image_change, 2.0 * 225 / 1323.0, 1e-9);  // R off and G on over 225 px
}

TEST_F(EyeOnBaseScene, MoveIsSeenWhereTheObjectArrives) {
  lookAt({75, 75});  // green circle
  const ActionOutcome out = env.execute(3, kMove, 0.5, 0.5);
  ASSERT_TRUE(out.succeeded);
  const Effect e = eye.scanEffect(3, env.render(), kMove);
  EXPECT_TRUE(e.position_changed);
  EXPECT_TRUE(e.affordance);
  EXPECT_EQ(e.after.gaze, toPixel(out.target_x, out.target_y, 150));
}

// The image a moved circle leaves in the focus: in the pixel world its one
// footprint, unchanged; in the continuous world (the default) the pixels of
// its new real-valued centre, which the eye must report as they are.
TEST(Eye, AMovedCircleLooksAsItsNewPlaceDrawsIt) {
  for (const char* world : {"pixel", "continuous"}) {
    SCOPED_TRACE(world);
    const RunConfig c = test::shippedConfig("base", System::IMP, 1, {std::string("world.positions=") + world});
    Environment env(c);
    Eye eye(c);
    eye.setScene(env.render());
    std::size_t circle = env.objects().size();
    for (std::size_t i = 0; i < env.objects().size(); ++i)
      if (env.objects()[i].centre == Pixel{75, 75}) circle = i;
    ASSERT_LT(circle, env.objects().size());
    const WorldObject before = env.objects()[circle];
    int step = 0;
    while (!(eye.scan(step).gaze == before.centre)) ASSERT_LT(++step, 500);
    ASSERT_TRUE(env.execute(step, kMove, before.x, before.y).succeeded);
    const WorldObject after = env.objects()[circle];
    const Effect e = eye.scanEffect(step, env.render(), kMove);
    ASSERT_LE(std::abs(e.after.gaze.col - after.centre.col), 1);
    ASSERT_LE(std::abs(e.after.gaze.row - after.centre.row), 1);
    // The circle alone, before and after, in windows placed as the eye placed them.
    const auto alone = [&](const WorldObject& o, Pixel gaze) {
      cv::Mat scene = blankScene(150);
      paintObject(scene, o.shape, o.colour, o.x, o.y, c.world);
      return cropFocus(scene, gaze, 21);
    };
    const double expected = imageChange(alone(before, e.before.gaze), alone(after, e.after.gaze));
    EXPECT_DOUBLE_EQ(e.image_change, expected);
    EXPECT_EQ(e.image_changed, expected > c.eye.image_change_threshold);
    if (std::string(world) == "pixel") {
      EXPECT_EQ(expected, 0.0);
    }
  }
}

TEST_F(EyeOnBaseScene, NoChangeMeansNoAffordanceAndTheGazeStays) {
  lookAt({30, 30});
  ASSERT_FALSE(env.execute(2, kTurnRed, 0.2, 0.2).succeeded);  // red square is red already
  const Effect e = eye.scanEffect(2, env.render(), kTurnRed);
  EXPECT_FALSE(e.affordance);
  EXPECT_EQ(e.after.gaze, (Pixel{30, 30}));
  EXPECT_DOUBLE_EQ(e.image_change, 0.0);
}

TEST_F(EyeOnBaseScene, AColourChangeDoesNotCountAsAMove) {
  lookAt({30, 30});
  ASSERT_TRUE(env.execute(5, kTurnBlue, 0.2, 0.2).succeeded);
  EXPECT_FALSE(eye.scanEffect(5, env.render(), kMove).affordance);
}

TEST_F(EyeOnBaseScene, TheWrongColourDoesNotCountForAnotherColourAction) {
  lookAt({30, 30});
  ASSERT_TRUE(env.execute(5, kTurnBlue, 0.2, 0.2).succeeded);
  EXPECT_FALSE(eye.scanEffect(5, env.render(), kTurnGreen).affordance);
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

// Late objects may land on each other (world.late_overlap, the authors' code):
// the eye then sees one blob of two colours. Its focus must still be on that
// blob, and an action there must act on an object (the one on top).
TEST(Eye, OverlappingObjectsAreOneBlobTheEyeLooksAtAndActsOn) {
  for (std::int64_t seed = 1; seed <= 200; ++seed) {
    const RunConfig c = test::shippedConfig("late1", System::IMP, seed);
    Environment env(c);
    env.introduceObjectsAt(2000);
    const auto& objs = env.objects();
    int overlapping = -1;  // an object drawn over another
    for (std::size_t b = 0; b < objs.size() && overlapping < 0; ++b)
      for (std::size_t a = 0; a < b && overlapping < 0; ++a)
        for (const Pixel& p : objs[b].pixels)
          if (objs[a].present && objs[b].present &&
              std::find(objs[a].pixels.begin(), objs[a].pixels.end(), p) != objs[a].pixels.end()) {
            overlapping = static_cast<int>(b);
            break;
          }
    if (overlapping < 0) continue;
    Eye eye(c);
    eye.setScene(env.render());
    bool on_pair = false;
    for (int step = 0; step < 300; ++step) {
      const Focus& f = eye.scan(step);
      ASSERT_NE(eye.labelAt(f.gaze), 0) << "seed " << seed << " step " << step;
      Environment acted = env;
      const ActionOutcome out = acted.execute(step, kTurnBlue, f.x, f.y);
      EXPECT_TRUE(out.on_object) << "seed " << seed << " step " << step << " at " << f.x << "," << f.y;
      on_pair = on_pair || eye.labelAt(f.gaze) == eye.labelAt(objs[static_cast<std::size_t>(overlapping)].centre);
    }
    EXPECT_TRUE(on_pair) << "seed " << seed << ": the eye never looked at the overlapping pair";
    return;
  }
  FAIL() << "no seed in 1..200 put two late objects over each other";
}

// The authors' eye (issue 28, eye.fovea = true_centre). A rectangle 10 pixels
// wide covers the same pixels at two real centres a fraction of a pixel apart,
// while the window placed on its true centre lands a column apart: the
// centroid eye sees one image, the authors' eye two, and reports the true centre.
TEST(Eye, TheAuthorsEyeSeesARectanglesTwoDrawingPhasesAndTheCentroidEyeOne) {
  const RunConfig ours = test::shippedConfig("base");
  const RunConfig authors = test::shippedConfig("base", System::IMP, 1, {"eye.fovea=true_centre"});
  const double y = 0.5;
  double x0 = -1, x1 = -1;
  for (int k = 0; k < 1500 && x1 < 0; ++k) {  // two centres, the same pixels, windows a column apart
    const double a = 0.4 + k / 15000.0, b = a + 1.0 / 1500;
    if (shapePixels(Shape::Rectangle, a, y, ours.world) == shapePixels(Shape::Rectangle, b, y, ours.world) &&
        windowCorner(a, y, 21, 150).col != windowCorner(b, y, 21, 150).col) {
      x0 = a;
      x1 = b;
    }
  }
  ASSERT_GT(x1, 0) << "no two centres draw the same rectangle";
  const auto look = [&](const RunConfig& c, double x) {
    cv::Mat scene = blankScene(150);
    paintObject(scene, Shape::Rectangle, Colour::Green, x, y, c.world);
    Eye eye(c);
    eye.setScene(scene, {{x, y}});
    return eye.scan(0);
  };
  const Focus c0 = look(ours, x0), c1 = look(ours, x1);
  EXPECT_EQ(c0.image, c1.image) << "the centroid eye sees both phases alike";
  EXPECT_DOUBLE_EQ(c0.x, c1.x);
  const Focus t0 = look(authors, x0), t1 = look(authors, x1);
  EXPECT_NE(t0.image, t1.image) << "the authors' eye sees the two phases";
  EXPECT_DOUBLE_EQ(t0.x, x0);
  EXPECT_DOUBLE_EQ(t1.x, x1);
  EXPECT_DOUBLE_EQ(t0.y, y);
}

// Every scan, effect and look of the authors' eye is on a listed object's true
// centre; the centroid eye ignores the list.
TEST(Eye, TheAuthorsEyeLooksAtTrueCentresAndOursIgnoresTheList) {
  const RunConfig authors = test::shippedConfig("base", System::IMP, 1, {"eye.fovea=true_centre"});
  Environment env(authors);
  Eye eye(authors);
  eye.setScene(env.render(), env.centres());
  for (int step = 0; step < 60; ++step) {
    const Focus f = eye.scan(step);
    bool on_centre = false;
    for (const WorldObject& o : env.objects()) on_centre = on_centre || (f.x == o.x && f.y == o.y);
    ASSERT_TRUE(on_centre) << "step " << step << " at " << f.x << "," << f.y;
    if (step % 3 == 0) {
      ASSERT_TRUE(env.execute(step, kMove, f.x, f.y).succeeded);
      const Effect e = eye.scanEffect(step, env.render(), kMove, env.centres());
      bool moved_there = false;
      for (const WorldObject& o : env.objects()) moved_there = moved_there || (e.after.x == o.x && e.after.y == o.y);
      EXPECT_TRUE(moved_there) << "step " << step;
    }
  }
  const RunConfig ours = test::shippedConfig("base");
  Environment env2(ours);
  Eye with(ours), without(ours);
  with.setScene(env2.render(), {{0.9, 0.9}});  // not even where the objects are: never read
  without.setScene(env2.render());
  for (int step = 0; step < 20; ++step) EXPECT_EQ(with.scan(step).image, without.scan(step).image);
}

// A list that leaves an object out is refused, naming the fields, and the eye
// keeps the scene it had.
TEST(Eye, TheAuthorsEyeRefusesAListWithoutAnObjectItSees) {
  const RunConfig c = test::shippedConfig("base", System::IMP, 1, {"eye.fovea=true_centre"});
  Environment env(c);
  Eye eye(c);
  eye.setScene(env.render(), env.centres());
  const Focus before = eye.scan(0);
  std::vector<cv::Point2d> short_list = env.centres();
  short_list.pop_back();
  for (const auto& list : {short_list, std::vector<cv::Point2d>{}}) {
    cv::Mat other = env.render();
    other.setTo(cv::Scalar(0, 0, 0));
    paintObject(other, Shape::Square, Colour::Blue, 0.5, 0.5, c.world);
    paintObject(other, Shape::Square, Colour::Red, 0.3, 0.3, c.world);
    try {
      eye.setScene(env.render(), list);
      FAIL() << "a list of " << list.size() << " objects was taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("object_x, object_y"), std::string::npos) << e.what();
    }
    EXPECT_THROW(eye.checkScene(other, {{0.5, 0.5}}), std::invalid_argument);
    EXPECT_NO_THROW(eye.checkScene(other, {{0.5, 0.5}, {0.3, 0.3}}));
  }
  EXPECT_EQ(eye.atGaze().image, before.image);
  EXPECT_TRUE(sameImage(eye.scene(), env.render()));
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

// Top-down attention (issue 12): the look at the differences of a scenario
// with a colour change, a move and a distractor.
TEST(EyeDifferences, ListTheChangedAndMovedObjectsAndNotTheDistractor) {
  const RunConfig c = test::shippedConfig();
  Scenario s;
  s.objects.push_back({Shape::Square, {Colour::Red, 0.3, 0.3}, {Colour::Green, 0.3, 0.3}, 1, 1, "", -1});     // colour
  s.objects.push_back({Shape::Circle, {Colour::Blue, 0.7, 0.3}, {Colour::Blue, 0.5, 0.7}, 1, 1, "", -1});     // move
  s.objects.push_back({Shape::Rectangle, {Colour::Green, 0.3, 0.7}, {Colour::Green, 0.3, 0.7}, 1, 1, "", -1});  // stays
  const Environment env(c, s);
  Eye eye(c);
  eye.setGoal(env.goalScene());
  eye.setScene(env.render());
  const Focus before = eye.focus();
  const std::vector<Difference> d = eye.goalDifferences(c.planner.subgoal_match);
  auto near = [](const Difference& x, double px, double py) { return std::abs(x.x - px) < 0.01 && std::abs(x.y - py) < 0.01; };
  std::vector<Difference> goal, scene;
  for (const Difference& x : d) (x.in_goal ? goal : scene).push_back(x);
  ASSERT_EQ(goal.size(), 2u);   // the green square and the circle's new place
  ASSERT_EQ(scene.size(), 2u);  // the red square and the circle's old place
  EXPECT_TRUE(std::any_of(goal.begin(), goal.end(), [&](const Difference& x) { return near(x, 0.3, 0.3); }));
  EXPECT_TRUE(std::any_of(goal.begin(), goal.end(), [&](const Difference& x) { return near(x, 0.5, 0.7); }));
  EXPECT_TRUE(std::any_of(scene.begin(), scene.end(), [&](const Difference& x) { return near(x, 0.3, 0.3); }));
  EXPECT_TRUE(std::any_of(scene.begin(), scene.end(), [&](const Difference& x) { return near(x, 0.7, 0.3); }));
  for (const Difference& x : d) EXPECT_FALSE(near(x, 0.3, 0.7)) << "the rectangle is as the goal has it";
  // The goal's window at the square's place shows it green, the scene's red.
  for (const Difference& x : d)
    if (near(x, 0.3, 0.3)) {
      EXPECT_GT(imageDistance(x.image, std::vector<std::uint8_t>(x.image.size(), 0)), 0.0);
    }
  for (const Difference& x : goal)
    for (const Difference& y : scene)
      if (near(x, 0.3, 0.3) && near(y, 0.3, 0.3)) {
        EXPECT_GE(imageDistance(x.image, y.image), c.planner.subgoal_match);
      }
  EXPECT_EQ(eye.focus().gaze.col, before.gaze.col);  // looking at the differences does not move the gaze...
  // ...but attending an object does: the window on the blob under the place.
  const Focus& f = eye.attend(0.7, 0.3);
  EXPECT_NEAR(f.x, 0.7, 1.0 / 150);
  EXPECT_NEAR(f.y, 0.3, 1.0 / 150);
}

TEST(EyeDifferences, NoneWhenTheSceneIsTheGoal) {
  const RunConfig c = test::shippedConfig();
  Scenario s;
  s.objects.push_back({Shape::Square, {Colour::Red, 0.3, 0.3}, {Colour::Red, 0.3, 0.3}, 1, 1, "", -1});
  const Environment env(c, s);
  Eye eye(c);
  eye.setGoal(env.goalScene());
  eye.setScene(env.render());
  EXPECT_TRUE(eye.goalDifferences(c.planner.subgoal_match).empty());
}

}  // namespace
}  // namespace afford

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

// Does any pixel of `o` lie in the focus window around (x, y)?
bool inWindow(const WorldObject& o, double x, double y, const RunConfig& c) {
  const Pixel lo = windowCorner(x, y, c.eye.focus_side, c.world.size_px);
  for (const Pixel& p : o.pixels)
    if (p.col >= lo.col && p.col < lo.col + c.eye.focus_side && p.row >= lo.row && p.row < lo.row + c.eye.focus_side)
      return true;
  return false;
}
bool overlap(const WorldObject& a, const WorldObject& b) {
  for (const Pixel& p : a.pixels)
    for (const Pixel& q : b.pixels)
      if (p == q) return true;
  return false;
}
RunConfig withSettings(const std::string& experiment, std::int64_t seed, std::vector<std::string> settings) {
  return test::shippedConfig(experiment, System::IMP, seed, std::move(settings));
}

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
    EXPECT_DOUBLE_EQ(o.x, out.target_x);  // a real-valued place: nothing snaps to a pixel
    EXPECT_DOUBLE_EQ(o.y, out.target_y);
    EXPECT_GE(out.target_x, c.world.table_min);
    EXPECT_LE(out.target_x, c.world.table_max);
    // Free: no other object within the focus window around the new place.
    for (const auto& other : env.objects()) {
      if (&other != &o) {
        EXPECT_FALSE(inWindow(other, o.x, o.y, c)) << "step " << step;
      }
    }
  }
}

// A rectangle is 22.5 px tall, taller than the 21 x 21 window a move target
// must have free: moved anywhere, it still touches no other object (touching
// objects are one blob to the eye, whose gaze then falls between them).
TEST(Environment, AMovedObjectTouchesNoOtherInTheContinuousWorld) {
  const RunConfig c = withSettings("base", 4, {"world.positions=continuous"});
  Environment env(c);
  int rectangle_moves = 0;
  for (int step = 0; step < 3000; ++step) {
    const auto& objs = env.objects();
    const WorldObject& o = objs[static_cast<std::size_t>(step) % objs.size()];
    const ActionOutcome out = env.execute(step, kMove, o.x, o.y);
    if (!out.succeeded) continue;
    rectangle_moves += o.shape == Shape::Rectangle;
    for (const auto& other : objs) {
      if (&other == &o) continue;
      for (const Pixel& p : o.pixels)
        for (const Pixel& q : other.pixels)
          ASSERT_FALSE(std::abs(p.col - q.col) <= 1 && std::abs(p.row - q.row) <= 1) << "step " << step;
    }
  }
  EXPECT_GT(rectangle_moves, 500);
}

// Twenty objects on the larger table (config/experiments/large-world.yaml): every move goes to a place whose focus
// window holds no other object, and no two objects ever overlap or touch; a move finds a free place nearly always.
TEST(Environment, TwentyObjectsStayApartAndMovesFindFreePlaces) {
  const RunConfig c = withSettings("large-world", 3, {});
  ASSERT_EQ(c.world.objects.size(), 20u);
  Environment env(c);
  int moves = 0, tries = 0;
  for (int step = 0; step < 2000; ++step) {
    const auto& objs = env.objects();
    const WorldObject& o = objs[static_cast<std::size_t>(step * 7) % objs.size()];
    ++tries;
    const ActionOutcome out = env.execute(step, kMove, o.x, o.y);
    if (!out.succeeded) continue;
    ++moves;
    for (const auto& other : objs) {
      if (&other == &o) continue;
      ASSERT_FALSE(inWindow(other, o.x, o.y, c)) << "step " << step << ": " << toString(other.shape);
      for (const Pixel& p : o.pixels)
        for (const Pixel& q : other.pixels)
          ASSERT_FALSE(std::abs(p.col - q.col) <= 1 && std::abs(p.row - q.row) <= 1) << "step " << step;
    }
  }
  EXPECT_GT(moves, tries * 99 / 100) << moves << " of " << tries;
}

TEST(Environment, MoveTargetsAreRealNumbersInTheContinuousWorldAndPixelsInThePixelWorld) {
  int off_pixel = 0;
  for (int step = 0; step < 20; ++step) {
    Environment cont(withSettings("base", 1, {"world.positions=continuous"})),
        pix(withSettings("base", 1, {"world.positions=pixel"}));
    const ActionOutcome a = cont.execute(step, kMove, 0.5, 0.5), b = pix.execute(step, kMove, 0.5, 0.5);
    ASSERT_TRUE(a.succeeded && b.succeeded);
    off_pixel += std::abs(a.target_x * 150 - std::round(a.target_x * 150)) > 1e-6;
    EXPECT_NEAR(b.target_x * 150, std::round(b.target_x * 150), 1e-9);
    EXPECT_NEAR(b.target_y * 150, std::round(b.target_y * 150), 1e-9);
  }
  EXPECT_GT(off_pixel, 15);
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
  const WorldObject& r = env.objects()[rect];
  EXPECT_TRUE(r.present);
  EXPECT_FALSE(env.execute(2000, kMove, r.x, r.y).succeeded);  // late1 rectangles are not movable
}

// Continuous world (authors' code): each late object goes to a random place whose
// window is free in the scene as it was before its step; late objects of one
// step may overlap each other unless world.late_overlap is false.
TEST(Environment, LateObjectsGoToRandomPlacesFreeOfTheObjectsBeforeThem) {
  int overlapping = 0, moved = 0;
  for (std::int64_t seed = 1; seed <= 60; ++seed) {
    for (bool allow : {true, false}) {
      const RunConfig c = withSettings("late1", seed, {"world.positions=continuous",
                                                       std::string("world.late_overlap=") + (allow ? "true" : "false")});
      Environment env(c);
      std::vector<int> late, early;
      for (std::size_t i = 0; i < c.world.objects.size(); ++i)
        (c.world.objects[i].appears_at == 2000 ? late : early).push_back(static_cast<int>(i));
      ASSERT_TRUE(env.introduceObjectsAt(2000));
      for (int i : late) {
        const WorldObject& o = env.objects()[i];
        moved += std::abs(o.x - c.world.objects[i].x) > 1e-9 || std::abs(o.y - c.world.objects[i].y) > 1e-9;
        EXPECT_GE(o.x, c.world.table_min);
        EXPECT_LE(o.x, c.world.table_max);
        for (int j : early) EXPECT_FALSE(inWindow(env.objects()[j], o.x, o.y, c)) << "seed " << seed;
        for (int j : late)
          if (j < i && overlap(env.objects()[j], o)) {
            EXPECT_TRUE(allow) << "seed " << seed << ": late objects overlap with late_overlap false";
            overlapping += allow;
          }
      }
    }
  }
  EXPECT_GT(moved, 100);      // not the configured places
  EXPECT_GT(overlapping, 0);  // with late_overlap, some do overlap
}

TEST(Environment, ThePixelWorldPutsLateObjectsAtTheirConfiguredPlaces) {
  const RunConfig c = withSettings("late1", 3, {"world.positions=pixel"});
  Environment env(c);
  ASSERT_TRUE(env.introduceObjectsAt(2000));
  for (std::size_t i = 0; i < c.world.objects.size(); ++i)
    EXPECT_EQ(env.objects()[i].centre, toPixel(c.world.objects[i].x, c.world.objects[i].y, 150)) << i;
}

// Where late objects overlap, the one drawn last is on top: it is what the
// scene shows and what an action at that pixel acts on.
TEST(Environment, OverlappingObjectsActOnTheOneOnTop) {
  for (std::int64_t seed = 1; seed <= 200; ++seed) {
    const RunConfig c = withSettings("late1", seed, {"world.positions=continuous"});
    Environment env(c);
    env.introduceObjectsAt(2000);
    const auto& objs = env.objects();
    for (std::size_t a = 0; a < objs.size(); ++a)
      for (std::size_t b = a + 1; b < objs.size(); ++b) {
        if (!objs[a].present || !objs[b].present || !overlap(objs[a], objs[b])) continue;
        Pixel shared{};
        for (const Pixel& p : objs[a].pixels)
          if (std::find(objs[b].pixels.begin(), objs[b].pixels.end(), p) != objs[b].pixels.end()) shared = p;
        EXPECT_EQ(env.objectAt(shared), static_cast<int>(b));
        const Colour top = objs[b].colour;
        const cv::Vec3b px = env.render().at<cv::Vec3b>(shared.row, shared.col);
        EXPECT_EQ(px[top == Colour::Red ? 0 : top == Colour::Green ? 1 : 2], 255);
        return;  // one overlap is enough
      }
  }
  FAIL() << "no seed in 1..200 put two late objects over each other";
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

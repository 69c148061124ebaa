#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "afford/snapshot.hpp"
#include "motivation/component.hpp"
#include "motivation/goals.hpp"
#include "motivation/motivation.hpp"
#include "tests/said.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

using A = std::array<double, kNumActions>;

TEST(Entropy, IsOneBitAtOneHalfAndZeroAtCertainty) {
  EXPECT_DOUBLE_EQ(entropyBits(0.5), 1.0);
  EXPECT_DOUBLE_EQ(entropyBits(0.0), 0.0);
  EXPECT_DOUBLE_EQ(entropyBits(1.0), 0.0);
  EXPECT_DOUBLE_EQ(entropyBits(0.2), entropyBits(0.8));
}

TEST(Entropy, PointThreeBitsIsAPredictionOfAbout0947) {  // paper 2.4.1
  EXPECT_NEAR(entropyBits(0.947), 0.3, 0.003);
  EXPECT_NEAR(entropyBits(0.053), 0.3, 0.003);
}

TEST(Motivation, FixActsOnTheMostUncertainActionWhileAboveTheFixedThreshold) {
  Motivation m(test::shippedConfig("base", System::FIX));
  Decision d = m.decide(A{0.99, 0.5, 0.9, 0.99}, A{});
  EXPECT_TRUE(d.act);
  EXPECT_EQ(d.action, 1);
  EXPECT_DOUBLE_EQ(d.motivation, 1.0);
  EXPECT_DOUBLE_EQ(d.threshold, 0.3);
  d = m.decide(A{0.99, 0.98, 0.02, 0.99}, A{});
  EXPECT_FALSE(d.act);
  EXPECT_DOUBLE_EQ(m.threshold(), 0.3);  // FIX never moves its threshold
}

TEST(Motivation, IgnThresholdIsALeakyAverageOfTheActedSignalOrZero) {
  const RunConfig c = test::shippedConfig("base", System::IGN);
  Motivation m(c);
  const double nu = c.motivation.leak;
  double th = c.motivation.initial_threshold;
  Decision d = m.decide(A{0.5, 0.6, 0.9, 0.99}, A{});  // acts: H(0.5) = 1 >= th
  ASSERT_TRUE(d.act);
  th += nu * (1.0 - th);
  EXPECT_DOUBLE_EQ(m.threshold(), th);
  d = m.decide(A{0.999, 0.999, 0.999, 0.999}, A{});  // too certain: passes
  ASSERT_FALSE(d.act);
  th += nu * (0.0 - th);  // Algorithm 1 line 16
  EXPECT_DOUBLE_EQ(m.threshold(), th);
}

TEST(Motivation, ImpUsesTheAbsoluteLearningProgressAndTiesGoToTheLowestAction) {
  Motivation m(test::shippedConfig("base", System::IMP));
  Decision d = m.decide(A{0.5, 0.5, 0.5, 0.5}, A{0.01, -0.03, 0.03, 0.02});
  EXPECT_TRUE(d.act);
  EXPECT_EQ(d.action, 1);
  EXPECT_DOUBLE_EQ(d.motivation, 0.03);
}

TEST(Motivation, ActsWhenTheSignalPlusMarginReachesTheThreshold) {
  const RunConfig c = test::shippedConfig("base", System::FIX);
  Motivation m(c);
  const double p = 0.947;  // entropy just above 0.3
  const double h = entropyBits(p);
  EXPECT_EQ(m.decide(A{p, 1.0, 1.0, 1.0}, A{}).act, h + c.motivation.act_margin >= 0.3);
}

TEST(Motivation, ImpWithObservedChangeWaitsForTheObservation) {
  const RunConfig c = test::shippedConfig("base", System::IMP, 1, {"motivation.imp_threshold_input=observed_change"});
  Motivation m(c);
  const double th0 = m.threshold();
  ASSERT_TRUE(m.decide(A{}, A{0.02, 0, 0, 0}).act);
  EXPECT_TRUE(m.awaitingObservation());
  EXPECT_DOUBLE_EQ(m.threshold(), th0);
  m.observeChange(0.05);
  EXPECT_FALSE(m.awaitingObservation());
  EXPECT_DOUBLE_EQ(m.threshold(), th0 + c.motivation.leak * (0.05 - th0));
}

// ---- revisits (issue 11, docs/model.md#revisit) ------------------------------------

using Tried = std::array<std::int64_t, kNumActions>;

RevisitConfig revisitAfter(std::int64_t after_steps, RevisitOrder order = RevisitOrder::Actions) {
  RevisitConfig r;
  r.enabled = true;
  r.after_steps = after_steps;
  r.order = order;
  return r;
}

TEST(Revisit, NeverTriedActionsComeFirstInTheActionOrder) {
  const RevisitConfig r = revisitAfter(1000);
  EXPECT_EQ(revisitAction(Tried{-1, -1, -1, -1}, r, 1, 0), kMove);
  EXPECT_EQ(revisitAction(Tried{3, -1, -1, -1}, r, 1, 0), kTurnGreen);
  EXPECT_EQ(revisitAction(Tried{3, 4, 2, -1}, r, 1, 0), kTurnBlue);
  EXPECT_EQ(revisitAction(Tried{5000, 4, -1, 5000}, r, 1, 0), kTurnRed);  // never tried before stale
}

TEST(Revisit, OtherwiseTheActionNotTriedForLongestOnceItIsStale) {
  EXPECT_EQ(revisitAction(Tried{999, 10, 20, 30}, revisitAfter(1000), 1, 0), -1);
  EXPECT_EQ(revisitAction(Tried{1000, 10, 1500, 30}, revisitAfter(1000), 1, 0), kTurnRed);
  EXPECT_EQ(revisitAction(Tried{1500, 10, 1500, 30}, revisitAfter(1000), 1, 0), kMove);
  EXPECT_EQ(revisitAction(Tried{1000000, 10, 20, 30}, revisitAfter(0), 1, 0), -1);  // after_steps 0: never-tried only
}

// order: random keeps move first, draws every never-tried colour first at some steps, and the same (seed, step)
// always gives the same action.
TEST(Revisit, ARandomOrderKeepsMoveFirstAndVariesTheColoursByStep) {
  const RevisitConfig r = revisitAfter(1000, RevisitOrder::Random);
  std::map<int, int> first;
  for (std::int64_t step = 0; step < 300; ++step) {
    EXPECT_EQ(revisitAction(Tried{-1, -1, -1, -1}, r, 7, step), kMove);
    const int a = revisitAction(Tried{3, -1, -1, -1}, r, 7, step);
    EXPECT_EQ(a, revisitAction(Tried{3, -1, -1, -1}, r, 7, step));
    ++first[a];
    EXPECT_EQ(revisitAction(Tried{3, 4, -1, 9}, r, 7, step), kTurnRed);  // the only one never tried
  }
  EXPECT_EQ(first.size(), 3u);
  for (int a : {kTurnGreen, kTurnRed, kTurnBlue}) EXPECT_GT(first[a], 60) << a;
}

TEST(Revisit, ARevisitActsWhateverTheThresholdAndLeavesItAsItIs) {
  for (System s : {System::FIX, System::IGN, System::IMP}) {
    const RunConfig c = test::shippedConfig("base", s, 1, test::kMemoryOptions);
    Motivation m(c);
    const double th = m.threshold();
    const Tried tried{-1, 5, 5, 5};
    const Decision d = m.decide(A{0.999, 0.999, 0.001, 0.999}, A{}, &tried);  // nothing to learn by the IM signal
    EXPECT_TRUE(d.act) << toString(s);
    EXPECT_TRUE(d.revisit) << toString(s);
    EXPECT_EQ(d.action, kMove) << toString(s);
    EXPECT_DOUBLE_EQ(m.threshold(), th) << toString(s);
    EXPECT_FALSE(m.awaitingObservation()) << toString(s);
    // Nothing due: the paper's rule decides, and moves the threshold as it does.
    const Tried recent{5, 5, 5, 5};
    const Decision p = m.decide(A{0.5, 0.999, 0.001, 0.999}, A{0.01, 0, 0, 0}, &recent);
    EXPECT_FALSE(p.revisit) << toString(s);
    EXPECT_EQ(p.action, kMove) << toString(s);
  }
}

TEST(Revisit, IsRefusedWithoutWhatWasTriedOnTheLook) {
  Motivation m(test::shippedConfig("base", System::IGN, 1, test::kMemoryOptions));
  EXPECT_THROW(m.decide(A{0.5, 0.5, 0.5, 0.5}, A{}), std::invalid_argument);
}

// motivation.kind=novelty: on each look, the action chosen least often there
// (ties to the first), with the signal 1/sqrt(1+n); passes once even the least
// chosen one has been tried so often that the signal is below the threshold.
TEST(Novelty, CountsByLookAndPassesBelowItsThreshold) {
  RunConfig c = test::shippedConfig("base", System::IMP);
  c.motivation.kind = "novelty";
  c.motivation.novelty_threshold = 0.5;  // acts while n <= 3
  auto m = makeMotivation(c);
  EXPECT_TRUE(m->needsMemory());
  Percept p;
  p.look = 7;
  std::array<int, kNumActions> chosen{};
  for (int i = 0; i < 4 * kNumActions; ++i) {
    p.step = i;
    const Decision d = m->decide(p);
    ASSERT_TRUE(d.act) << "step " << i;
    EXPECT_EQ(d.action, i % kNumActions);  // least chosen, ties to the first: round robin
    EXPECT_DOUBLE_EQ(d.motivation, 1.0 / std::sqrt(1.0 + i / kNumActions));
    EXPECT_DOUBLE_EQ(d.threshold, 0.5);
    ++chosen[d.action];
  }
  p.step = 4 * kNumActions;
  Decision d = m->decide(p);  // n = 4 everywhere: 1/sqrt(5) < 0.5
  EXPECT_FALSE(d.act);
  EXPECT_DOUBLE_EQ(d.motivation, 1.0 / std::sqrt(5.0));
  EXPECT_FALSE(m->decide(p).act);  // a pass counts nothing
  p.look = 8;  // another look has its own counts
  d = m->decide(p);
  EXPECT_TRUE(d.act);
  EXPECT_EQ(d.action, 0);
  EXPECT_DOUBLE_EQ(d.motivation, 1.0);
}

// The same percepts in order give the same decisions: what replay and live restart rely on.
TEST(Novelty, IsAPureFunctionOfThePerceptsInOrder) {
  RunConfig c = test::shippedConfig("base", System::IMP);
  c.motivation.kind = "novelty";
  auto a = makeMotivation(c), b = makeMotivation(c);
  for (int i = 0; i < 200; ++i) {
    Percept p;
    p.step = i;
    p.look = (i * 7919) % 5;
    const Decision x = a->decide(p), y = b->decide(p);
    ASSERT_EQ(x.act, y.act);
    ASSERT_EQ(x.action, y.action);
    ASSERT_EQ(x.motivation, y.motivation);
  }
}

TEST(MotivationKind, ThePaperKindIsTheSystemsMotivation) {
  const RunConfig c = test::shippedConfig("base", System::IMP);
  ASSERT_EQ(c.motivation.kind, "paper");
  auto m = makeMotivation(c);
  Motivation core(c);
  Percept p;
  p.affordance = A{0.5, 0.5, 0.5, 0.5};
  p.learning_progress = A{0.01, -0.03, 0.03, 0.02};
  const Decision d = m->decide(p), e = core.decide(p.affordance, p.learning_progress);
  EXPECT_EQ(d.act, e.act);
  EXPECT_EQ(d.action, e.action);
  EXPECT_DOUBLE_EQ(d.motivation, e.motivation);
}

TEST(MotivationKind, AKindNotBuiltInIsRefusedNamingTheKeyAndTheWayToRunOnesOwn) {
  RunConfig c = test::shippedConfig("base", System::IMP);
  c.motivation.kind = "mine";
  try {
    makeMotivation(c);
    ADD_FAILURE() << "kind 'mine' was taken";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("motivation.kind"), std::string::npos) << what;
    EXPECT_NE(what.find("paper, novelty"), std::string::npos) << what;
    EXPECT_NE(what.find("--process motivation="), std::string::npos) << what;
  }
  registerMotivation("mine", makeNoveltyMotivation);  // what a process of one's own does first
  EXPECT_NO_THROW(makeMotivation(c));
  const auto kinds = motivationKinds();
  EXPECT_EQ(kinds.front(), "paper");
  EXPECT_EQ(kinds.back(), "mine");
}

// ---- the goal chooser (goals.kind: imgep) -------------------------------------

// A chooser of the goals experiment that sets goals from the first: no
// explorations first or after.
GoalParams goalParams() {
  GoalParams p(test::shippedConfig("goals", System::GOALS));
  p.goals.bootstrap = 0;
  p.goals.explore_share = 0;
  return p;
}

// A focus image: a square of `colour`, `half` pixels from its middle to its
// sides, centred `dc`, `dr` pixels off the look's middle, on the black table.
std::vector<std::uint8_t> look(int side, std::array<std::uint8_t, 3> colour, int half = 6, int dc = 0, int dr = 0) {
  std::vector<std::uint8_t> image(3 * static_cast<std::size_t>(side * side), 0);
  const int middle = side / 2;
  for (int row = 0; row < side; ++row)
    for (int col = 0; col < side; ++col)
      if (std::abs(col - middle - dc) <= half && std::abs(row - middle - dr) <= half)
        for (int k = 0; k < 3; ++k) image[3 * static_cast<std::size_t>(row * side + col) + k] = colour[k];
  return image;
}

// A move the agent saw: the object at (x, y) taken to (tx, ty).
SeenEffect moved(const std::vector<std::uint8_t>& object, double x, double y, double tx, double ty) {
  SeenEffect e;
  e.step = 1;
  e.action = kMove;
  e.before = Seen{object, x, y};
  e.after = Seen{object, tx, ty};
  e.target_x = tx;
  e.target_y = ty;
  e.affordance = true;
  return e;
}

TEST(GoalChooser, AMoveGoalTakesAnObjectAsLastSeenToAPlaceAMoveReachedOrLeft) {
  const GoalParams p = goalParams();
  ImgepChooser chooser(p);
  EXPECT_EQ(chooser.next(10, 0).module, GoalModule::Explore);  // nothing seen: nothing to aim at
  const auto red = look(p.focus_side, {255, 0, 0});
  chooser.sawEffect(moved(red, 0.2, 0.2, 0.7, 0.7));
  EXPECT_EQ(chooser.objects(), 1U);
  EXPECT_EQ(chooser.places(), 2U);
  const Goal g = chooser.next(11, 1);  // the only goal there is: back to where it stood
  EXPECT_EQ(g.module, GoalModule::Move);
  EXPECT_DOUBLE_EQ(g.object_x, 0.7);
  EXPECT_DOUBLE_EQ(g.object_y, 0.7);
  EXPECT_DOUBLE_EQ(g.x, 0.2);
  EXPECT_DOUBLE_EQ(g.y, 0.2);
  EXPECT_EQ(g.image, red);
}

TEST(GoalChooser, ALookShowingOnlyANeighboursEdgeSaysThePlaceIsEmpty) {
  const GoalParams p = goalParams();
  const int side = p.focus_side;
  ImgepChooser chooser(p);
  chooser.sawEffect(moved(look(side, {255, 0, 0}), 0.2, 0.2, 0.7, 0.7));
  ASSERT_EQ(chooser.objects(), 1U);
  // The object at (0.7, 0.7) has gone; a look there shows the edge of another object, three columns wide.
  const auto edge = look(side, {0, 0, 255}, side / 2, side - 2, 0);
  chooser.sawObject(12, Seen{edge, 0.7, 0.7});
  EXPECT_EQ(chooser.objects(), 0U);
  EXPECT_EQ(chooser.next(13, 2).module, GoalModule::Explore);  // no object to move: no goal of that edge
  // A look centred on an object, even one at the table's edge a little off the look's middle, is an object there.
  chooser.sawObject(14, Seen{look(side, {0, 0, 255}, 6, 2, -2), 0.7, 0.7});
  EXPECT_EQ(chooser.objects(), 1U);
  chooser.sawObject(15, Seen{std::vector<std::uint8_t>(3 * static_cast<std::size_t>(side * side), 0), 0.7, 0.7});
  EXPECT_EQ(chooser.objects(), 0U);  // the table alone
}

TEST(GoalChooser, AnObjectSeenNearWhereAnotherWasRememberedTakesItsPlace) {
  const GoalParams p = goalParams();
  const int side = p.focus_side;
  ImgepChooser chooser(p);
  chooser.sawObject(1, Seen{look(side, {255, 0, 0}), 0.50, 0.50});
  chooser.sawObject(2, Seen{look(side, {0, 255, 0}), 0.70, 0.50});
  ASSERT_EQ(chooser.objects(), 2U);
  // An object a fifth of its size from the red one: the red one has left, unseen (two objects never stand so close).
  const double near = 0.2 * p.world.object_size;
  chooser.sawObject(3, Seen{look(side, {0, 0, 255}), 0.50 + near, 0.50 - near / 2});
  EXPECT_EQ(chooser.objects(), 2U);
  // Farther than an object's size: both stand.
  chooser.sawObject(4, Seen{look(side, {255, 0, 0}), 0.50, 0.50 + 1.1 * p.world.object_size});
  EXPECT_EQ(chooser.objects(), 3U);
}

// On the physical table (world.kind: table) a push or carry is a move; a topple leaves the object in a new look
// where it stands, a goal for another object of its colour, at the place the change would put it.
TEST(GoalChooser, OnTheTableAToppledObjectsLookIsAGoalOfAnotherOfItsColour) {
  GoalParams p(test::shippedConfig("table", System::GOALS));
  p.goals.bootstrap = 0;
  p.goals.explore_share = 0;
  ASSERT_EQ(p.world.kind, WorldKind::Table);
  const int side = p.focus_side;
  ImgepChooser chooser(p);
  const std::array<std::uint8_t, 3> orange{217, 89, 0}, green{38, 230, 38};
  const auto standing = look(side, orange, 2), lying = look(side, orange, 6);  // 5 x 5 pixels; 13 x 13
  SeenEffect topple;
  topple.step = 3;
  topple.action = 2;  // topple
  topple.before = Seen{standing, 0.30, 0.30};
  topple.after = Seen{lying, 0.33, 0.30};
  topple.affordance = true;
  chooser.sawEffect(topple);
  EXPECT_EQ(chooser.objects(), 1U);  // the bar, lying where the scan found it
  EXPECT_EQ(chooser.colours(), 1U);  // its new look
  EXPECT_EQ(chooser.places(), 1U);   // the place it left
  chooser.sawObject(4, Seen{look(side, green, 3), 0.30, 0.55});   // another colour: no look of its own
  chooser.sawObject(5, Seen{standing, 0.60, 0.40});                // another of the bar's colour
  chooser.imagined(Imagined{6, 2, standing, look(side, orange, 5), 0.6, 0.4});  // predicted looks are not goals
  EXPECT_EQ(chooser.colours(), 1U);
  // The place the first bar left is not free (it lies beside it): no move. Every goal is a look, the second
  // bar's (the green object's colour has none), at its place moved as the first bar's centre moved.
  int looks = 0;
  for (int id = 0; id < 40; ++id) {
    const Goal g = chooser.next(7, id);
    ASSERT_EQ(g.module, GoalModule::Colour) << "goal " << id;
    ++looks;
    EXPECT_DOUBLE_EQ(g.object_x, 0.60);
    EXPECT_DOUBLE_EQ(g.object_y, 0.40);
    EXPECT_NEAR(g.x, 0.63, 1e-12);
    EXPECT_NEAR(g.y, 0.40, 1e-12);
    EXPECT_EQ(g.image, lying);
  }
  EXPECT_EQ(looks, 40);
  // A push that reached its place: the object as it looked, at its target.
  SeenEffect push;
  push.step = 8;
  push.action = 0;
  push.before = Seen{look(side, green, 3), 0.30, 0.55};
  push.after = Seen{look(side, green, 3), 0.45, 0.56};
  push.target_x = 0.45;
  push.target_y = 0.55;
  push.affordance = true;
  chooser.sawEffect(push);
  EXPECT_EQ(chooser.colours(), 1U);
  EXPECT_EQ(chooser.places(), 3U);
}

// Objects' reach and nearness: the grid's by its object size, the table's by its objects as the camera sees them.
TEST(GoalChooser, ObjectGeometryIsTheWorlds) {
  const RunConfig grid = test::shippedConfig("goals", System::GOALS);
  EXPECT_DOUBLE_EQ(objectGeometry(grid).reach, 0.75 * grid.world.object_size);
  EXPECT_DOUBLE_EQ(objectGeometry(grid).apart, 0.5 * grid.world.object_size);
  RunConfig table = test::shippedConfig("table", System::GOALS);
  const ObjectGeometry g = objectGeometry(table);
  // The bar (half-extents 1.5, 1.5, 6 cm) reaches farthest, 6.7 cm lying or tipped: about 17 of 320 pixels seen
  // from 1 m at its height; the disc (7.5 mm half-height) is the narrowest.
  EXPECT_GT(g.reach, 0.05);
  EXPECT_LT(g.reach, 0.07);
  EXPECT_GT(g.apart, 0.010);
  EXPECT_LT(g.apart, 0.014);
  table.table.spec.objects.resize(1);  // the cube alone: 2.5 cm half-extents
  EXPECT_LT(objectGeometry(table).reach, g.reach);
  EXPECT_GT(objectGeometry(table).apart, g.apart);
}

TEST(GoalChooser, AGoalFoundReachedWhenSetSaysNothingOfCompetence) {
  ImgepChooser chooser(goalParams());
  chooser.attempted(GoalAttempt{1, GoalModule::Move, true, 0.0, 0});
  EXPECT_EQ(chooser.competence().attempts(GoalModule::Move), 0U);
  chooser.attempted(GoalAttempt{2, GoalModule::Move, true, 0.0, 1});
  chooser.attempted(GoalAttempt{3, GoalModule::Colour, false, 0.2, 4});
  EXPECT_EQ(chooser.competence().attempts(GoalModule::Move), 1U);
  EXPECT_EQ(chooser.competence().attempts(GoalModule::Colour), 1U);
  chooser.attempted(GoalAttempt{4, GoalModule::Explore, false, -1, 1});
  EXPECT_EQ(chooser.competence().attempts(GoalModule::Explore), 0U);  // an exploration is no goal
}

TEST(GoalChooser, AModuleIsChosenByItsAbsoluteCompetenceProgressOrAtRandom) {
  Competence c(2);  // compares the last two attempts with the two before
  for (double v : {0.0, 0.0, 1.0, 1.0}) c.attempted(GoalModule::Colour, v);  // rising: progress 1
  for (double v : {1.0, 1.0, 1.0, 1.0}) c.attempted(GoalModule::Move, v);    // mastered: progress 0
  for (double v : {1.0, 1.0, 0.5, 0.5}) c.attempted(GoalModule::ColourPlace, v);  // falling: progress 0.5
  EXPECT_DOUBLE_EQ(c.progress(GoalModule::Colour), 1.0);
  EXPECT_DOUBLE_EQ(c.progress(GoalModule::Move), 0.0);
  EXPECT_DOUBLE_EQ(c.progress(GoalModule::ColourPlace), 0.5);
  const std::array<bool, kGoalModules> all = {false, true, true, true};
  // Not a random choice (u >= random_share): in proportion to progress, 1 : 0 : 0.5.
  EXPECT_EQ(c.choose(all, 0.2, 0.5, 0.0), GoalModule::Colour);
  EXPECT_EQ(c.choose(all, 0.2, 0.5, 0.66), GoalModule::Colour);
  EXPECT_EQ(c.choose(all, 0.2, 0.5, 0.67), GoalModule::ColourPlace);
  EXPECT_EQ(c.choose(all, 0.2, 0.5, 0.99), GoalModule::ColourPlace);
  // A random choice (u < random_share): uniform over the modules available, the mastered one too.
  EXPECT_EQ(c.choose(all, 0.2, 0.1, 0.5), GoalModule::Move);
  // Only the modules available, and an exploration when there is none.
  EXPECT_EQ(c.choose({false, false, true, true}, 0.2, 0.5, 0.1), GoalModule::ColourPlace);
  EXPECT_EQ(c.choose({false, false, true, false}, 0.2, 0.5, 0.1), GoalModule::Move);
  EXPECT_EQ(c.choose({false, false, false, false}, 0.2, 0.5, 0.1), GoalModule::Explore);
  // The window keeps 2 x window attempts: older ones no longer count.
  for (double v : {1.0, 1.0}) c.attempted(GoalModule::Colour, v);
  EXPECT_DOUBLE_EQ(c.progress(GoalModule::Colour), 0.0);
}

TEST(GoalChooser, GoalsAreKeyedDrawsAndASnapshotRestoresThem) {
  const GoalParams p = goalParams();
  const int side = p.focus_side;
  const auto fill = [&](ImgepChooser& c) {
    c.sawEffect(moved(look(side, {255, 0, 0}), 0.2, 0.2, 0.7, 0.7));
    c.sawEffect(moved(look(side, {0, 255, 0}), 0.5, 0.2, 0.2, 0.7));
    c.sawObject(3, Seen{look(side, {0, 0, 255}), 0.5, 0.8});
    SeenEffect turned;  // the blue square turned red: a colour outcome
    turned.step = 4;
    turned.action = kTurnRed;
    turned.before = Seen{look(side, {0, 0, 255}), 0.5, 0.8};
    turned.after = Seen{look(side, {255, 0, 0}), 0.5, 0.8};
    turned.affordance = true;
    c.sawEffect(turned);
    c.attempted(GoalAttempt{1, GoalModule::Move, true, 0.0, 1});
    c.attempted(GoalAttempt{2, GoalModule::Colour, false, 0.1, 4});
  };
  ImgepChooser a(p), b(p);
  fill(a);
  fill(b);
  const std::string path = test::tempDir("goal-chooser") + "/chooser.snapshot";
  {
    SnapshotWriter w(path);
    a.save(w);
    w.commit();
  }
  ImgepChooser restored(p);
  SnapshotReader r(path, 1 << 20);
  restored.load(r);
  std::set<std::pair<int, double>> distinct;
  for (int id = 3; id < 40; ++id) {
    const Goal g = a.next(100 + id, id);
    for (const ImgepChooser* other : {&b, &restored}) {  // the same state and key: the same goal
      const Goal h = const_cast<ImgepChooser*>(other)->next(100 + id, id);
      EXPECT_EQ(g.module, h.module) << id;
      EXPECT_EQ(g.image, h.image) << id;
      EXPECT_DOUBLE_EQ(g.x, h.x) << id;
      EXPECT_DOUBLE_EQ(g.object_x, h.object_x) << id;
    }
    distinct.emplace(static_cast<int>(g.module), g.x + 10 * g.object_x);
  }
  EXPECT_GT(distinct.size(), 3U);  // the draws differ from goal to goal
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

// The stable surface (docs/writing-a-component.md): a motivation factory of the whole RunConfig, the form before
// MotivationParams, still registers, is given the run's configuration, and says once what to write instead.
TEST(ComponentSurface, AMotivationFactoryOfTheWholeRunConfigStillRegistersAndSaysWhatToWriteInstead) {
  test::Said said;
  const auto before = spdlog::default_logger();
  spdlog::set_default_logger(said.log);
  std::int64_t seed = -1;
  std::string experiment;
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
  registerMotivation("whole-config", [&](const RunConfig& c) {
    seed = c.seed;
    experiment = c.experiment;
    return makeNoveltyMotivation(MotivationParams(c));
  });
#pragma GCC diagnostic pop
  spdlog::set_default_logger(before);
  EXPECT_EQ(said.count("motivation 'whole-config': its factory takes the whole RunConfig, which is deprecated"), 1)
      << said.text.str();
  EXPECT_EQ(said.count("take const afford::MotivationParams&"), 1) << said.text.str();
  // As the motivation process has it: parsed from the RUN_CONFIG's text.
  const RunConfig c =
      parseRunConfigText(test::shippedConfigYaml("base", System::IMP, 7, 1000, {"motivation.kind=whole-config"}));
  EXPECT_NE(makeMotivation(MotivationParams(c)), nullptr);
  EXPECT_EQ(seed, 7);
  EXPECT_EQ(experiment, "base");
}

}  // namespace
}  // namespace afford

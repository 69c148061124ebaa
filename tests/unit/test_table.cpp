// The table world's simulation and camera (processes/environment/table): the model built from its spec,
// physics that the spec's numbers decide, a state that continues bit for bit, the hand moved by its
// actuators, and a camera whose images are the same bytes for the same state and show each object where
// the simulation has it.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <future>
#include <cstring>
#include <memory>
#include <thread>

#include "environment/table/camera.hpp"
#include "environment/table/physics.hpp"
#include "environment/table/primitives.hpp"
#include "environment/table/truth.hpp"
#include "tests/support.hpp"

namespace afford::table {
namespace {

// A small world for the tests (these are fixtures, not the experiments' values).
TableSpec sampleSpec() {
  TableSpec t;
  t.half_x = 0.3;
  t.half_y = 0.6;
  t.rim_height = 0.02;
  t.friction = 0.8;
  t.rgb = {0.15, 0.15, 0.15};
  t.timestep = 0.002;
  t.camera = {160, 120, 1.0, 45.0};
  HandSpec& h = t.hand;
  h.palm_half[0] = 0.02, h.palm_half[1] = 0.05, h.palm_half[2] = 0.01;
  h.finger_half[0] = 0.01, h.finger_half[1] = 0.005, h.finger_half[2] = 0.03;
  h.finger_travel = 0.045;
  h.mass = 0.4;
  h.friction = 1.5;
  h.kp_move = 4000;
  h.kp_yaw = 40;
  h.kp_finger = 200;
  h.time_constant = 0.025;
  h.rest_height = 0.3;
  h.park[0] = 0.3, h.park[1] = 0.0, h.park[2] = 0.3;
  h.reach_x = 0.3;
  h.reach_y = 0.6;
  h.rgb = {0.9, 0.9, 0.9};
  t.objects = {
      {"cube", Shape::Box, {0.025, 0.025, 0.025}, false, 0.1, 0.8, 0.005, 0.0001, {0.9, 0.1, 0.1}},
      {"ball", Shape::Sphere, {0.025}, false, 0.05, 0.8, 0.005, 0.0001, {0.1, 0.9, 0.1}},
      {"log", Shape::Cylinder, {0.02, 0.05}, true, 0.08, 0.8, 0.005, 0.0001, {0.1, 0.1, 0.9}},
      {"can", Shape::Cylinder, {0.025, 0.04}, false, 0.1, 0.8, 0.005, 0.0001, {0.9, 0.9, 0.1}},
      {"bar", Shape::Box, {0.015, 0.015, 0.06}, false, 0.08, 0.8, 0.005, 0.0001, {0.9, 0.5, 0.1}},
  };
  return t;
}

PrimitiveSpec samplePrimitives() {
  PrimitiveSpec p;
  p.travel_speed = 1.0;
  p.contact_speed = 0.15;
  p.tap_speed = 0.5;
  p.safe_height = 0.16;
  p.clearance = 0.02;
  p.push_height = 0.005;
  p.push_gap = 0.6;
  p.grasp_height = 0.3;
  p.carry_height = 0.1;
  p.topple_height = 0.7;
  p.topple_drop = 0.25;
  p.tap_stroke = 0.02;
  p.roll_distance = 0.1;
  p.success_radius = 0.03;
  p.reach_tolerance = 0.005;
  p.waypoint_bound_s = 3;
  p.rest_speed = 0.002;
  p.rest_hold_s = 0.1;
  p.settle_bound_s = 3;
  return p;  // no noise: the tests that want it set it
}

// Object `i` alone in the middle of the table (the others out of the way, at the far end).
TablePhysics& aloneAt(TablePhysics& sim, int i, double x, double y, double yaw = 0) {
  for (int k = 0; k < sim.objectCount(); ++k)
    if (k != i) sim.placeObject(k, -0.25, -0.55 + 0.05 * k, 0);
  sim.placeObject(i, x, y, yaw);
  sim.step(100);
  return sim;
}

double planarDistance(const Pose& a, double x, double y) { return std::hypot(a.pos[0] - x, a.pos[1] - y); }

TEST(TableModel, EveryObjectOfTheSpecIsABodyOfTheModelWithItsShapeSizeMassAndFriction) {
  TablePhysics sim(sampleSpec());
  const mjModel* m = sim.model();
  for (const ObjectSpec& o : sampleSpec().objects) {
    const int body = mj_name2id(m, mjOBJ_BODY, o.name.c_str());
    const int geom = mj_name2id(m, mjOBJ_GEOM, o.name.c_str());
    ASSERT_GE(body, 0) << o.name;
    ASSERT_GE(geom, 0) << o.name;
    EXPECT_NEAR(m->body_mass[body], o.mass, 1e-12) << o.name;
    EXPECT_DOUBLE_EQ(m->geom_friction[3 * geom], o.friction) << o.name;
    const int type = o.shape == Shape::Box ? mjGEOM_BOX : o.shape == Shape::Sphere ? mjGEOM_SPHERE : mjGEOM_CYLINDER;
    EXPECT_EQ(m->geom_type[geom], type) << o.name;
    for (std::size_t k = 0; k < o.size.size(); ++k) EXPECT_DOUBLE_EQ(m->geom_size[3 * geom + k], o.size[k]) << o.name;
  }
  EXPECT_EQ(m->nu, 6) << "the hand's x, y, z, yaw and two fingers";
}

TEST(TableModel, AWrongSpecIsRefusedNamingTheObjectAndField) {
  TableSpec t = sampleSpec();
  t.objects[1].size = {0.02, 0.03};
  try {
    TablePhysics sim(t);
    FAIL() << "a sphere with two sizes was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("table.objects[1] ('ball')"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("takes 1 size values, not 2"), std::string::npos) << e.what();
  }
  t = sampleSpec();
  t.objects[2].name = "cube";
  EXPECT_THROW(TablePhysics{t}, std::invalid_argument);
  t = sampleSpec();
  t.objects[0].lying = true;
  EXPECT_THROW(TablePhysics{t}, std::invalid_argument);
  t = sampleSpec();
  t.objects[3].name = "bad\"name";  // would break the model's text
  EXPECT_THROW(TablePhysics{t}, std::invalid_argument);
  t = sampleSpec();
  t.objects[0].mass = 0;
  EXPECT_THROW(TablePhysics{t}, std::invalid_argument);
}

TEST(TablePhysics, ObjectsPlacedOnTheTableStayAtRestWhereTheyWerePut) {
  TablePhysics sim(sampleSpec());
  const double places[4][2] = {{0.1, -0.3}, {-0.1, -0.1}, {0.1, 0.15}, {-0.15, 0.4}};
  for (int i = 0; i < 4; ++i) sim.placeObject(i, places[i][0], places[i][1], 0.3 * i);
  sim.step(1000);  // 2 s
  EXPECT_TRUE(sim.atRest(1e-3, 1e-2));
  for (int i = 0; i < 4; ++i) {
    const Pose p = sim.objectPose(i);
    EXPECT_LT(planarDistance(p, places[i][0], places[i][1]), 2e-3) << sampleSpec().objects[i].name;
    EXPECT_NEAR(p.pos[2], sampleSpec().objects[i].restingHeight(), 2e-3) << sampleSpec().objects[i].name;
  }
}

// Physics decides, and the spec's numbers are its inputs: the same shove slides a box on a slippery table
// further than on a rough one, and a ball rolls further than either.
double travelAfterShove(TableSpec t, int object, double speed) {
  TablePhysics sim(t);
  aloneAt(sim, object, 0, -0.3, 0);
  auto* data = const_cast<mjData*>(sim.data());
  const int joint = mj_name2id(sim.model(), mjOBJ_JOINT, t.objects[static_cast<std::size_t>(object)].name.c_str());
  data->qvel[sim.model()->jnt_dofadr[joint] + 1] = speed;  // along +y
  sim.step(1500);
  return sim.objectPose(object).pos[1] + 0.3;
}

TEST(TablePhysics, FrictionFromTheSpecDecidesHowFarAShovedBoxSlides) {
  TableSpec rough = sampleSpec(), slippery = sampleSpec();
  rough.objects[0].friction = 1.0;
  rough.friction = 1.0;
  slippery.objects[0].friction = 0.1;
  slippery.friction = 0.1;
  const double far = travelAfterShove(slippery, 0, 0.8), near = travelAfterShove(rough, 0, 0.8);
  EXPECT_GT(near, 0.005);
  EXPECT_GT(far, 3 * near) << "slippery " << far << " m, rough " << near << " m";
  const double rolled = travelAfterShove(rough, 1, 0.8);  // the ball, on the rough table
  EXPECT_GT(rolled, 3 * near) << "the ball rolled " << rolled << " m, the box slid " << near << " m";
}

TEST(TablePhysics, AStateSetAgainContinuesBitForBit) {
  TablePhysics a(sampleSpec());
  for (int i = 0; i < 4; ++i) a.placeObject(i, 0.05 * i - 0.1, 0.25 * i - 0.4, 0.2 * i);
  a.commandHand({0.05, -0.1, 0.08, 0.3, 0.2});
  a.step(300);  // mid-motion: the hand on its way down, objects settling
  const std::vector<double> saved = a.state();
  a.step(400);
  const std::vector<double> straight = a.state();

  TablePhysics b(sampleSpec());
  b.setState(saved);
  b.step(400);
  const std::vector<double> resumed = b.state();
  ASSERT_EQ(straight.size(), resumed.size());
  EXPECT_EQ(std::memcmp(straight.data(), resumed.data(), straight.size() * sizeof(double)), 0)
      << "the run continued from its saved state is not the run that went on";

  TableSpec other = sampleSpec();
  other.objects.pop_back();
  TablePhysics c(other);
  EXPECT_THROW(c.setState(saved), std::invalid_argument);
}

TEST(TablePhysics, TheHandGoesWhereItIsCommandedByItsActuators) {
  TablePhysics sim(sampleSpec());
  const HandCommand goal{0.12, -0.25, 0.15, 0.5, 0.0};
  sim.commandHand(goal);
  sim.step(1500);
  const HandCommand now = sim.handNow();
  EXPECT_NEAR(now.x, goal.x, 5e-3);
  EXPECT_NEAR(now.y, goal.y, 5e-3);
  EXPECT_NEAR(now.z, goal.z, 5e-3);
  EXPECT_NEAR(now.yaw, goal.yaw, 2e-2);
  EXPECT_NEAR(now.opening, 0.0, 0.05);
  EXPECT_TRUE(sim.atRest(2e-2, 5e-2));
}

TEST(TablePrimitives, APushBringsACubeToThePlaceAndACarryBringsItBack) {
  TablePhysics sim(sampleSpec());
  aloneAt(sim, 0, 0.05, -0.1, 0.3);
  const PrimitiveResult pushed = runPrimitive(sim, samplePrimitives(), 1, 0, kPush, 0, std::make_pair(0.1, 0.1));
  EXPECT_TRUE(pushed.succeeded);
  EXPECT_TRUE(pushed.settled);
  EXPECT_LT(planarDistance(sim.objectPose(0), 0.1, 0.1), 0.03);
  const PrimitiveResult carried = runPrimitive(sim, samplePrimitives(), 1, 1, kCarry, 0, std::make_pair(-0.1, -0.2));
  EXPECT_TRUE(carried.succeeded);
  EXPECT_LT(planarDistance(sim.objectPose(0), -0.1, -0.2), 0.03);
  EXPECT_FALSE(toppled(sim, 0, 0.25, sampleSpec().objects[0].restingHeight()));
  EXPECT_GT(carried.physics_steps, pushed.physics_steps / 2);
}

TEST(TablePrimitives, ToppleFellsATallBarAndNotACube) {
  TablePhysics bar(sampleSpec()), cube(sampleSpec());
  aloneAt(bar, 4, 0.0, 0.0);
  aloneAt(cube, 0, 0.0, 0.0);
  EXPECT_TRUE(runPrimitive(bar, samplePrimitives(), 1, 0, kTopple, 4, std::nullopt).succeeded);
  EXPECT_LT(bar.objectPose(4).pos[2], 0.03) << "the bar lies";
  EXPECT_FALSE(runPrimitive(cube, samplePrimitives(), 1, 0, kTopple, 0, std::nullopt).succeeded);
  // Lying, the bar does not topple again: the goal is a fall from where it was, not being low.
  EXPECT_FALSE(runPrimitive(bar, samplePrimitives(), 1, 1, kTopple, 4, std::nullopt).succeeded);
}

TEST(TablePrimitives, ATapRollsABallOnAndNotACube) {
  TablePhysics ball(sampleSpec()), cube(sampleSpec());
  aloneAt(ball, 1, 0.0, 0.0);
  aloneAt(cube, 0, 0.0, 0.0);
  const PrimitiveResult rolled = runPrimitive(ball, samplePrimitives(), 1, 0, kRoll, 1, std::nullopt);
  EXPECT_TRUE(rolled.succeeded) << "the ball is " << planarDistance(ball.objectPose(1), 0, 0) << " m away";
  EXPECT_FALSE(runPrimitive(cube, samplePrimitives(), 1, 0, kRoll, 0, std::nullopt).succeeded)
      << "the cube is " << planarDistance(cube.objectPose(0), 0, 0) << " m away";
}

TEST(TablePrimitives, TheNoiseIsKeyedBySeedAndStep) {
  PrimitiveSpec noisy = samplePrimitives();
  noisy.noise_position = 0.01;
  noisy.noise_height = 0.005;
  noisy.noise_direction = 0.2;
  auto run = [&](std::int64_t seed, std::int64_t step) {
    TablePhysics sim(sampleSpec());
    aloneAt(sim, 0, 0.05, -0.1, 0.3);
    runPrimitive(sim, noisy, seed, step, kPush, 0, std::make_pair(0.1, 0.1));
    return sim.state();
  };
  const std::vector<double> a = run(7, 3), b = run(7, 3), c = run(7, 4), d = run(8, 3);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0) << "the same draw gave two runs";
  EXPECT_NE(a, c) << "another step drew the same noise";
  EXPECT_NE(a, d) << "another seed drew the same noise";
}

TruthSpec sampleTruth() {
  TruthSpec t;
  t.region_x = 0.15;
  t.region_y = 0.4;
  t.place_min = 0.08;
  t.place_max = 0.2;
  return t;
}

PrimitiveSpec noisyPrimitives() {
  PrimitiveSpec p = samplePrimitives();
  p.noise_position = 0.01;
  p.noise_height = 0.005;
  p.noise_direction = 0.15;
  p.noise_yaw = 0.15;
  return p;
}

// Physics decides: the same push and roll, with the same noise, work on a cube and a ball in opposite ways.
TEST(TableTruth, TheSameActionsAffordDifferentlyByTheObjectsShape) {
  const TruthTable t = estimateTruth(sampleSpec(), noisyPrimitives(), sampleTruth(), 11, 6, {0, 1});
  ASSERT_EQ(t.objects.size(), 5u);
  const TruthCell& cube_push = t.cells[0][kPush];
  const TruthCell& ball_push = t.cells[1][kPush];
  const TruthCell& cube_roll = t.cells[0][kRoll];
  const TruthCell& ball_roll = t.cells[1][kRoll];
  EXPECT_EQ(cube_push.trials, 6);
  EXPECT_GE(cube_push.rate() - ball_push.rate(), 0.5) << cube_push.rate() << " against " << ball_push.rate();
  EXPECT_GE(ball_roll.rate() - cube_roll.rate(), 0.5) << ball_roll.rate() << " against " << cube_roll.rate();
  EXPECT_EQ(t.cells[2][kPush].trials, 0) << "an object not asked for was tried";
  // Its interval holds its rate, and is narrower with more trials.
  EXPECT_LE(cube_push.low(), cube_push.rate());
  EXPECT_GE(cube_push.high(), cube_push.rate());
  TruthCell more{10 * cube_push.successes, 10 * cube_push.trials};
  EXPECT_LT(more.high() - more.low(), cube_push.high() - cube_push.low());
  // At the edges a rate is inside its own interval: no success starts it at 0, all successes end it at 1.
  for (int n : {1, 7, 200, 1000}) {
    EXPECT_EQ((TruthCell{0, n}.low()), 0.0) << n;
    EXPECT_EQ((TruthCell{n, n}.high()), 1.0) << n;
    EXPECT_GT((TruthCell{0, n}.high()), 0.0) << n;
    EXPECT_LT((TruthCell{n, n}.low()), 1.0) << n;
  }
}

TEST(TableTruth, TheSameSeedGivesTheSameTable) {
  const TruthTable a = estimateTruth(sampleSpec(), noisyPrimitives(), sampleTruth(), 5, 2, {3});
  const TruthTable b = estimateTruth(sampleSpec(), noisyPrimitives(), sampleTruth(), 5, 2, {3});
  for (int act = 0; act < kTableActions; ++act) EXPECT_EQ(a.cells[3][act].successes, b.cells[3][act].successes);
}

class TableCameraTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { gl_ = std::make_unique<GlContext>(); }
  static void TearDownTestSuite() { gl_.reset(); }
  static std::unique_ptr<GlContext> gl_;
};
std::unique_ptr<GlContext> TableCameraTest::gl_;

TEST_F(TableCameraTest, TheSameStateGivesTheSameImageBytes) {
  TablePhysics a(sampleSpec()), b(sampleSpec());
  for (TablePhysics* s : {&a, &b}) {
    for (int i = 0; i < 4; ++i) s->placeObject(i, 0.05 * i - 0.1, 0.25 * i - 0.4, 0.2 * i);
    s->step(200);
  }
  TableCamera ca(a), cb(b);
  const cv::Mat ia = ca.rgb(a), ib = cb.rgb(b);
  ASSERT_EQ(ia.type(), CV_8UC3);
  ASSERT_EQ(ia.cols, 160);
  ASSERT_EQ(ia.rows, 120);
  EXPECT_EQ(cv::norm(ia, ib, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(ia, ca.rgb(a), cv::NORM_INF), 0) << "the same camera drew the same state twice differently";
  a.step(200);
  a.placeObject(0, 0.2, 0.45, 0);
  EXPECT_GT(cv::norm(ca.rgb(a), ib, cv::NORM_INF), 0) << "an object moved and the image stayed";
}

// Its buffers live in the OpenGL context of the thread that made it: another thread's draw is refused, saying so
// (afford.env's worlds are each made and stepped on one thread of their own).
TEST_F(TableCameraTest, ACameraDrawsOnTheThreadThatMadeItAlone) {
  TablePhysics sim(sampleSpec());
  TableCamera camera(sim);
  std::string refused;
  std::thread other([&] {
    try {
      camera.rgb(sim);
    } catch (const std::logic_error& e) {
      refused = e.what();
    }
  });
  other.join();
  EXPECT_NE(refused.find("the thread that made it"), std::string::npos) << refused;
  EXPECT_EQ(camera.rgb(sim).cols, 160);
}

// A person's view draws the hand, which the agent's leaves out; the oblique one looks at the table from its side.
TEST_F(TableCameraTest, APersonsViewDrawsTheHandTheAgentsLeavesOut) {
  TablePhysics sim(sampleSpec());
  sim.commandHand({0.0, 0.0, 0.05, 0.0, 1.0});
  sim.step(500);
  sim.forward();
  TableCamera agent(sim), person(sim, {true, false}), side(sim, {true, true});
  const cv::Mat a = agent.rgb(sim), p = person.rgb(sim), o = side.rgb(sim);
  EXPECT_GT(cv::countNonZero(cv::Mat(cv::abs(p - a)).reshape(1)), 50) << "the hand over the centre is not drawn";
  EXPECT_GT(cv::norm(o, p, cv::NORM_INF), 0) << "the side view is the top camera's";
}

TEST_F(TableCameraTest, EachObjectIsSeenWhereTheSimulationHasItInItsOwnColour) {
  TablePhysics sim(sampleSpec());
  const double places[4][2] = {{0.15, -0.4}, {-0.12, -0.05}, {0.05, 0.2}, {-0.15, 0.45}};
  for (int i = 0; i < 4; ++i) sim.placeObject(i, places[i][0], places[i][1], 0);
  sim.step(50);
  TableCamera camera(sim);
  const cv::Mat ids = camera.objects(sim), image = camera.rgb(sim);
  for (int i = 0; i < 4; ++i) {
    const ObjectSpec& o = sampleSpec().objects[static_cast<std::size_t>(i)];
    double su = 0, sv = 0, n = 0;
    cv::Vec3d colour(0, 0, 0);
    for (int v = 0; v < ids.rows; ++v)
      for (int u = 0; u < ids.cols; ++u)
        if (ids.at<int>(v, u) == i) {
          su += u + 0.5, sv += v + 0.5, n += 1;
          colour += cv::Vec3d(image.at<cv::Vec3b>(v, u));
        }
    ASSERT_GT(n, 10) << o.name << " is not seen";
    const Pose p = sim.objectPose(i);
    const cv::Point2d at = camera.pixelOf(p.pos[0], p.pos[1], p.pos[2]);
    EXPECT_NEAR(su / n, at.x, 1.5) << o.name;
    EXPECT_NEAR(sv / n, at.y, 1.5) << o.name;
    // Lit from above, its pixels are brightest in its own colour's channel.
    const cv::Vec3d mean = colour / n;
    const int strongest = o.rgb[0] > 0.5 && o.rgb[1] > 0.5 ? -1 : o.rgb[0] > 0.5 ? 0 : o.rgb[1] > 0.5 ? 1 : 2;
    if (strongest >= 0) {
      for (int c = 0; c < 3; ++c) {
        if (c == strongest) continue;
        EXPECT_GT(mean[strongest], mean[c] + 40) << o.name;
      }
    }
  }
  // The table's point under a pixel and the pixel of a table point are one mapping.
  const cv::Point2d q = camera.tableAt(37.5, 81.5), back = camera.pixelOf(q.x, q.y);
  EXPECT_NEAR(back.x, 37.5, 1e-9);
  EXPECT_NEAR(back.y, 81.5, 1e-9);
}

}  // namespace
}  // namespace afford::table

namespace afford {
namespace {

TEST(WorldTruthCommand, ATableExperimentsTruthIsEstimatedOnceAndReadAfter) {
  const std::string out = test::tempDir("world-truth");
  const std::string args = "world truth table --trials 2 --object cube --object ball --out " + out;
  const test::CommandResult first = test::runAfford(args);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("cube "), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("roll"), std::string::npos) << first.output;
  EXPECT_EQ(first.output.find("log "), std::string::npos) << "an object not asked for is in the table\n" << first.output;
  EXPECT_NE(first.output.find("wrote " + out + "/table-"), std::string::npos) << first.output;
  const test::CommandResult again = test::runAfford(args);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("read from " + out + "/table-"), std::string::npos) << again.output;
  EXPECT_EQ(again.output.find("estimating"), std::string::npos) << "the table was estimated again\n" << again.output;
  // The same cells, read back.
  EXPECT_EQ(first.output.substr(0, first.output.find("wrote")).substr(first.output.find("object ")),
            again.output.substr(0, again.output.find("read from")));
  // An experiment of the same table under another name (table-extrinsic extends table) reads the same file.
  const test::CommandResult same_world =
      test::runAfford("world truth table-extrinsic --trials 2 --object cube --object ball --out " + out);
  ASSERT_EQ(same_world.exit_code, 0) << same_world.output;
  EXPECT_NE(same_world.output.find("read from " + out + "/table-"), std::string::npos) << same_world.output;
  EXPECT_EQ(same_world.output.find("estimating"), std::string::npos) << "the same world was estimated again\n"
                                                                      << same_world.output;
  // What is in its place and is not a table it wrote (too large, or not a table) is estimated again.
  const std::size_t at = first.output.find("wrote ") + 6;
  const std::string file = first.output.substr(at, first.output.find('\n', at) - at);
  std::ofstream(file) << std::string(5u << 20, '[');
  const test::CommandResult large = test::runAfford(args);
  ASSERT_EQ(large.exit_code, 0) << large.output;
  EXPECT_NE(large.output.find("more than a truth table holds"), std::string::npos) << large.output;
  EXPECT_NE(large.output.find("wrote " + file), std::string::npos) << large.output;
  std::ofstream(file) << "{\"table\": 7}";
  const test::CommandResult broken = test::runAfford(args);
  ASSERT_EQ(broken.exit_code, 0) << broken.output;
  EXPECT_NE(broken.output.find("not a truth table"), std::string::npos) << broken.output;
  EXPECT_NE(broken.output.find("wrote " + file), std::string::npos) << broken.output;
  // Another world's configuration is another table.
  const test::CommandResult rough = test::runAfford(args + " --set table.top.friction=1.2");
  ASSERT_EQ(rough.exit_code, 0) << rough.output;
  EXPECT_NE(rough.output.find("wrote"), std::string::npos) << rough.output;
}

// Two processes asked for the same truth at once (a study's workers, sharing its truth folder): one estimates it,
// the other waits for its lock and reads what it wrote; both print the same cells.
TEST(WorldTruthCommand, TwoProcessesAskingForOneTruthEstimateItOnce) {
  const std::string out = test::tempDir("world-truth-twice");
  const std::string args = "world truth table --trials 8 --object cube --object ball --out " + out;
  auto a = std::async(std::launch::async, [&] { return test::runAfford(args); });
  auto b = std::async(std::launch::async, [&] { return test::runAfford(args); });
  const test::CommandResult ra = a.get(), rb = b.get();
  ASSERT_EQ(ra.exit_code, 0) << ra.output;
  ASSERT_EQ(rb.exit_code, 0) << rb.output;
  const bool a_wrote = ra.output.find("wrote " + out) != std::string::npos,
             b_wrote = rb.output.find("wrote " + out) != std::string::npos;
  EXPECT_NE(a_wrote, b_wrote) << "estimated " << (a_wrote && b_wrote ? "twice" : "by neither") << "\n"
                              << ra.output << "\n" << rb.output;
  const test::CommandResult& reader = a_wrote ? rb : ra;
  EXPECT_NE(reader.output.find("read from " + out), std::string::npos) << reader.output;
  const auto cells = [](const std::string& o) { return o.substr(o.find("object "), o.find("cube ") + 200 - o.find("object ")); };
  EXPECT_EQ(cells(ra.output), cells(rb.output));
}

TEST(WorldTruthCommand, TheWrongExperimentOrObjectIsNamedWithTheFix) {
  const test::CommandResult grid = test::runAfford("world truth base");
  EXPECT_EQ(grid.exit_code, 2);
  EXPECT_NE(grid.output.find("world.kind: grid"), std::string::npos) << grid.output;
  const test::CommandResult typo = test::runAfford("world truth table --object cbe --out " + test::tempDir("truth-typo"));
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.output.find("did you mean 'cube'"), std::string::npos) << typo.output;
  // A run of the paper's world carries no table section, and takes no table key.
  const test::CommandResult grid_config = test::runAfford("config base");
  ASSERT_EQ(grid_config.exit_code, 0) << grid_config.output;
  EXPECT_EQ(grid_config.output.find("\ntable:"), std::string::npos) << grid_config.output;
  EXPECT_EQ(grid_config.output.find("kind: grid"), std::string::npos) << grid_config.output;
  const test::CommandResult grid_set = test::runAfford("config base --set table.top.friction=1.2");
  EXPECT_EQ(grid_set.exit_code, 2);
  EXPECT_NE(grid_set.output.find("the table section is the physical table's"), std::string::npos) << grid_set.output;
  const test::CommandResult bad =
      test::runAfford("config table --set 'table.objects=[{name: cube, shape: sphere, size: [0.1, 0.2], mass: 1, "
                      "friction: 1, torsional_friction: 0, rolling_friction: 0, colour: [1, 0, 0]}]'");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("table.objects[0].size"), std::string::npos) << bad.output;
  // A table scenario checked against the paper's world is refused naming the way to its own; it has no grid picture.
  const test::CommandResult scenario = test::runAfford("scenario table1");
  EXPECT_EQ(scenario.exit_code, 2);
  EXPECT_NE(scenario.output.find("the scenario is of the table world, and this run's world is grid"), std::string::npos)
      << scenario.output;
  EXPECT_NE(scenario.output.find("e.g. table"), std::string::npos) << scenario.output;
  const test::CommandResult own = test::runAfford("scenario table1 --experiment table");
  EXPECT_EQ(own.exit_code, 0) << own.output;
  EXPECT_NE(own.output.find("table1: 1 object(s), valid"), std::string::npos) << own.output;
  const std::string png = test::tempDir("table-scenario-png") + "/t.png";
  const test::CommandResult picture = test::runAfford("scenario table1 --experiment table --png " + png);
  EXPECT_EQ(picture.exit_code, 2);
  EXPECT_NE(picture.output.find("--png draws the paper's world's scenarios"), std::string::npos) << picture.output;
  EXPECT_FALSE(std::filesystem::exists(png));
  // The camera's image is the scene a SCENE carries: no wider than the paper's world's largest scene.
  const test::CommandResult wide = test::runAfford("config table --set table.camera.width=4000");
  EXPECT_EQ(wide.exit_code, 2);
  EXPECT_NE(wide.output.find("table.camera.width"), std::string::npos) << wide.output;
}

}  // namespace
}  // namespace afford

// The table world as the environment process runs it (processes/environment/table_world.hpp) and as the eye
// sees it: the camera's image is the scene, the objects are the blobs on its black top, the gaze's pixel
// names the object the hand acts on, a place in scene units is the point of the top the pixel shows, the
// scene set up by (seed, step), and a state saved and loaded continues as the run would have.
#include <gtest/gtest.h>

#include <cstdlib>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "afford/snapshot.hpp"
#include "environment/table_world.hpp"
#include "eye/eye.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {
using test::shippedConfig;

const RunConfig& tableConfig() {
  static const RunConfig c = shippedConfig("table", System::IMP, 1);
  return c;
}

// The eye's blobs of an image: (count, centroids in scene units).
std::vector<cv::Point2d> blobs(const cv::Mat& rgb) {
  cv::Mat gray;
  cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
  cv::Mat mask = gray > 0, labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  std::vector<cv::Point2d> out;
  for (int i = 1; i < n; ++i)
    out.emplace_back(centroids.at<double>(i, 0) / rgb.cols, centroids.at<double>(i, 1) / rgb.cols);
  return out;
}

TEST(TableWorld, TheSceneIsTheCameraImageWithEachObjectABlobOnTheBlackTop) {
  const RunConfig& c = tableConfig();
  ASSERT_EQ(c.world.size_px, c.table.spec.camera.width);
  ASSERT_EQ(c.world.rows(), c.table.spec.camera.height);
  TableWorld w(c);
  const cv::Mat scene = w.render();
  ASSERT_EQ(scene.cols, c.table.spec.camera.width);
  ASSERT_EQ(scene.rows, c.table.spec.camera.height);
  if (const char* dir = std::getenv("AFFORD_TEST_IMAGES")) {  // for a look at it
    cv::Mat bgr;
    cv::cvtColor(scene, bgr, cv::COLOR_RGB2BGR);
    cv::imwrite(std::string(dir) + "/table_world_scene.png", bgr);
  }
  const std::vector<cv::Point2d> seen = blobs(scene);
  const std::vector<cv::Point2d> centres = w.centres();
  ASSERT_EQ(seen.size(), centres.size()) << "every object a blob of its own, the top black";
  // Each object's listed centre is within a few pixels of a blob's centroid, and the object under it is it.
  for (std::size_t i = 0; i < centres.size(); ++i) {
    double nearest = 1e9;
    for (const cv::Point2d& b : seen) nearest = std::min(nearest, std::hypot(b.x - centres[i].x, b.y - centres[i].y));
    EXPECT_LT(nearest * scene.cols, 4.0) << c.table.spec.objects[i].name;
    EXPECT_EQ(w.objectAt(centres[i].x, centres[i].y), static_cast<int>(i)) << c.table.spec.objects[i].name;
  }
  EXPECT_EQ(w.objectAt(0.0, 0.0), -1) << "the image's corner is the table";
}

// The paper's bottom-up scan (saliency: the image's brightness, noise +-0.05) visits every object of the table:
// the camera draws flat colours and the objects' colours are of one brightness, as the paper's shapes are. (With
// shaded objects of different brightness, scans went to the two brightest, and agents acted on the disc in nine
// actions of ten.)
TEST(TableWorld, ThePapersScansVisitEveryObjectOfTheTable) {
  const RunConfig& c = tableConfig();
  TableWorld w(c);
  Eye eye(c);
  eye.setScene(w.render(), {});
  const int n = static_cast<int>(c.table.spec.objects.size()), scans = 600;
  std::vector<int> seen(static_cast<std::size_t>(n), 0);
  for (int s = 0; s < scans; ++s) {
    const Focus& f = eye.scan(s);
    const int o = w.objectAt(f.x, f.y);
    ASSERT_GE(o, 0) << "scan " << s << " looked at the top";
    ++seen[static_cast<std::size_t>(o)];
  }
  for (int o = 0; o < n; ++o)  // an even share is 100 of 600; a share by area gives the smallest about 60
    EXPECT_GT(seen[static_cast<std::size_t>(o)], scans / n / 3) << c.table.spec.objects[static_cast<std::size_t>(o)].name;
}

TEST(TableWorld, APlaceInSceneUnitsIsThePointOfTheTopItsPixelShows) {
  TableWorld w(tableConfig());
  for (const cv::Point2d& p : {cv::Point2d(0, 0), cv::Point2d(0.15, -0.4), cv::Point2d(-0.2, 0.5)}) {
    const cv::Point2d s = w.toScene(p.x, p.y);
    EXPECT_GE(s.x, 0.0);
    EXPECT_LE(s.x, 1.0);
    EXPECT_GE(s.y, 0.0);
    EXPECT_LE(s.y, 0.75) << "scene units are columns / width: the rows reach height / width";
    const cv::Point2d back = w.toTable(s.x, s.y);
    EXPECT_NEAR(back.x, p.x, 1e-12);
    EXPECT_NEAR(back.y, p.y, 1e-12);
  }
}

TEST(TableWorld, TheSceneIsSetUpAgainEveryResetStepsByTheSeed) {
  const RunConfig& c = tableConfig();
  const std::int64_t k = c.table.scene.reset_every;
  ASSERT_GT(k, 0);
  TableWorld a(c), b(c);
  RunConfig other = c;
  other.seed = c.seed + 1;
  TableWorld d(other);
  EXPECT_FALSE(a.objectsAppearAt(k - 1));
  EXPECT_TRUE(a.objectsAppearAt(k));
  EXPECT_TRUE(c.world.lateObjectsAt(k)) << "the eye and the planner know the steps from the configuration";
  EXPECT_NE(a.centres(), d.centres()) << "another seed, another scene";
  const std::vector<cv::Point2d> start = a.centres();
  a.execute(0, 0, start[0].x, start[0].y);  // a push moves the first object
  EXPECT_TRUE(a.introduceObjectsAt(k));
  EXPECT_TRUE(b.introduceObjectsAt(k));
  EXPECT_EQ(a.centres(), b.centres()) << "set up by (seed, step), whatever came before";
  EXPECT_NE(a.centres(), start);
  EXPECT_TRUE(sameImage(a.render(), b.render()));
}

TEST(TableWorld, AStateSavedAndLoadedGoesOnAsTheRunWould) {
  // Saved at several steps (a scene set up anew among them), set in a world just built, and both worlds driven
  // on by the same actions: the same state, bit for bit, and the same images, at every step. MuJoCo's forward
  // pass normalises the free bodies' quaternions in place: a state normalised once more on loading went on a
  // bit off within a step or two.
  RunConfig c = tableConfig();
  c.table.scene.reset_every = 10;
  c.world.reset_every = 10;
  const std::string dir = test::tempDir("table-world-snapshot");
  TableWorld a(c);
  std::vector<std::unique_ptr<TableWorld>> loaded;
  for (std::int64_t s = 0; s < 24; ++s) {
    if (s == 2 || s == 10 || s == 17) {
      const std::string path = dir + "/at-" + std::to_string(s) + ".snapshot";
      {
        SnapshotWriter w(path);
        a.save(w);
        w.commit();
      }
      loaded.push_back(std::make_unique<TableWorld>(c));
      SnapshotReader r(path, 1 << 20);
      loaded.back()->load(r);
    }
    const std::vector<cv::Point2d> all = a.centres();
    const cv::Point2d at = all[static_cast<std::size_t>(s) % all.size()];
    const int action = static_cast<int>(s % kNumActions);
    const ActionOutcome x = a.execute(s, action, at.x, at.y);
    const cv::Mat image = a.render();
    a.introduceObjectsAt(s + 1);
    for (auto& b : loaded) {
      const ActionOutcome y = b->execute(s, action, at.x, at.y);
      EXPECT_EQ(x.succeeded, y.succeeded);
      EXPECT_EQ(x.target_x, y.target_x);
      EXPECT_TRUE(sameImage(image, b->render())) << "step " << s;
      b->introduceObjectsAt(s + 1);
      ASSERT_EQ(a.physics().state(), b->physics().state()) << "step " << s;
    }
  }
}

// The eye judges an action by what it sees (eye.hpp, the table world's rules), the primitive by the simulation's
// state: over actions on every object, the two agree on most, and both see successes and failures.
TEST(TableWorld, TheEyeSeesAnActionsEffectMostlyAsPhysicsDecidedIt) {
  const RunConfig& c = tableConfig();
  TableWorld w(c);
  Eye eye(c);
  int agree = 0, n = 0, physics_yes = 0, eye_yes = 0;
  for (std::int64_t s = 0; s < 48; ++s) {
    if (w.introduceObjectsAt(s)) {}
    eye.setScene(w.render(), {});
    const std::vector<cv::Point2d> at = w.centres();
    const cv::Point2d o = at[static_cast<std::size_t>(s / kNumActions) % at.size()];
    const Focus f = eye.attend(o.x, o.y);
    const int action = static_cast<int>(s % kNumActions);
    const ActionOutcome out = w.execute(s, action, f.x, f.y);
    if (!out.on_object) continue;  // two objects touching are one blob, whose centroid may be on neither
    const std::optional<cv::Point2d> target =
        out.target_x >= 0 ? std::optional<cv::Point2d>(cv::Point2d(out.target_x, out.target_y)) : std::nullopt;
    const Effect e = eye.scanEffect(s, w.render(), action, {}, target);
    agree += e.affordance == out.succeeded;
    physics_yes += out.succeeded;
    eye_yes += e.affordance;
    ++n;
  }
  EXPECT_GE(n, 40) << "the window is on the object it was put on";
  EXPECT_GE(agree, n * 8 / 10) << agree << " of " << n;
  EXPECT_GT(physics_yes, 0);
  EXPECT_LT(physics_yes, n);
  EXPECT_GT(eye_yes, 0);
  EXPECT_LT(eye_yes, n);
}

// A world made unstable on purpose (a stiff hand at a long step): MuJoCo sets its data back to the model's
// start in the middle of a primitive. The action fails, says so, and the scene is set up anew where the run
// was: the simulation's clock goes on, every object rests in the region in its configured pose.
TEST(TableWorld, AnActionInWhichTheSimulationBecameUnstableFailsAndTheSceneIsSetUpAnew) {
  RunConfig c = tableConfig();
  c.table.spec.timestep = 0.01;
  c.table.spec.hand.kp_move = 1e6;
  TableWorld w(c);
  bool seen = false;
  for (std::int64_t s = 0; s < 60 && !seen; ++s) {
    const int before = w.physics().instabilities();
    const double clock = w.physics().time();
    const std::vector<cv::Point2d> all = w.centres();
    const cv::Point2d at = all[static_cast<std::size_t>(s) % all.size()];
    const ActionOutcome out = w.execute(s, static_cast<int>(s % kNumActions), at.x, at.y);
    EXPECT_EQ(out.unstable, w.physics().instabilities() != before) << "step " << s;
    if (!out.unstable) continue;
    seen = true;
    EXPECT_FALSE(out.succeeded);
    EXPECT_GE(w.physics().time(), clock) << "the clock went back: the simulation's reset was kept";
    for (int i = 0; i < w.physics().objectCount(); ++i) {
      const table::Pose p = w.physics().objectPose(i);
      EXPECT_LE(std::abs(p.pos[0]), c.table.truth.region_x) << i;
      EXPECT_LE(std::abs(p.pos[1]), c.table.truth.region_y) << i;
      EXPECT_NEAR(p.pos[2], c.table.spec.objects[static_cast<std::size_t>(i)].restingHeight(), 1e-9) << i;
    }
  }
  EXPECT_TRUE(seen) << "no instability in 60 actions: the test needs a world that has one";
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

// A table run's extrinsic test of `scenario` (YAML of a scenario file), as the runner configures one.
RunConfig tableTest(const std::string& scenario) {
  RunConfig c = test::shippedConfig("table", System::IMP, 1);
  c.phase = Phase::Extrinsic;
  c.scenario = parseScenario(YAML::Load(scenario), "extrinsic.scenario", c.world);
  validateScenario(*c.scenario, c);
  return c;
}

const char* kTwoObjects = R"(
name: two
world: table
objects:
  - {object: cube, initial: {position: [0.2974, 0.3734]}, goal: {position: [0.418, 0.3734]}}
  - {object: disc, initial: {position: [0.6593, 0.293]}, goal: {position: [0.6593, 0.293]}}
)";

TEST(TableWorld, ATestShowsTheScenariosObjectsAloneAndItsGoalImageWithThemAtTheirGoals) {
  const RunConfig c = tableTest(kTwoObjects);
  TableWorld w(c);
  const auto near = [](const std::vector<cv::Point2d>& seen, double x, double y) {
    double best = 1e9;
    for (const cv::Point2d& b : seen) best = std::min(best, std::hypot(b.x - x, b.y - y));
    return best;
  };
  const std::vector<cv::Point2d> now = blobs(w.render()), goal = blobs(w.goalScene());
  ASSERT_EQ(now.size(), 2u) << "the scenario's two objects, the other four out of the camera's view";
  ASSERT_EQ(goal.size(), 2u);
  ASSERT_EQ(w.centres().size(), 2u);
  ASSERT_EQ(w.goalCentres().size(), 2u);
  const int width = c.table.spec.camera.width;
  for (const ScenarioObject& o : c.scenario->objects) {
    EXPECT_LT(near(now, o.initial.x, o.initial.y) * width, 4.0) << o.object << " starts where the scenario says";
    EXPECT_LT(near(goal, o.goal.x, o.goal.y) * width, 4.0) << o.object << " is where its goal is in the goal image";
  }
  EXPECT_FALSE(w.objectsAppearAt(c.table.scene.reset_every)) << "a test's scene is not set up anew";
}

TEST(TableWorld, ATestsGoalDistanceIsZeroWhenEveryObjectRestsWithinTheSuccessRadiusOfItsGoal) {
  const RunConfig c = tableTest(kTwoObjects);
  TableWorld w(c);
  const ScenarioObject& cube = c.scenario->objects[0];
  const cv::Point2d from = w.toTable(cube.initial.x, cube.initial.y), to = w.toTable(cube.goal.x, cube.goal.y);
  const double diagonal = std::hypot(2 * c.table.truth.region_x, 2 * c.table.truth.region_y);
  const double radius = c.table.primitives.success_radius;
  // The cube 15 cm from its goal, the disc at its own: half of (15 cm less the radius) over the diagonal.
  EXPECT_NEAR(w.goalDistance(), (std::hypot(to.x - from.x, to.y - from.y) - radius) / 2 / diagonal, 1e-3);
  EXPECT_DOUBLE_EQ(w.goalUtility(), 1.0) << "the disc is at its goal";
  // Carried to its goal by the hand (carry: 1), given the goal's place as a planner gives it.
  const ActionOutcome out = w.execute(0, 1, cube.initial.x, cube.initial.y, std::make_pair(cube.goal.x, cube.goal.y));
  ASSERT_TRUE(out.on_object);
  ASSERT_TRUE(out.succeeded) << "the cube is carried (0.99 of carries succeed)";
  EXPECT_NEAR(out.target_x, cube.goal.x, 1e-9);
  EXPECT_NEAR(out.target_y, cube.goal.y, 1e-9);
  EXPECT_EQ(w.goalDistance(), 0.0);
  EXPECT_DOUBLE_EQ(w.goalUtility(), 2.0);
  EXPECT_EQ(blobs(w.render()).size(), 2u) << "the hand is not in the image; no object came into view";
}

TEST(TableWorld, APlaceOffTheTableIsTakenAsTheNearestPointOfTheRegion) {
  const RunConfig c = tableTest(kTwoObjects);
  TableWorld w(c);
  const ScenarioObject& cube = c.scenario->objects[0];
  // Carried toward the image's top-left corner, off the region: it rests within reach of the region's corner.
  const ActionOutcome out = w.execute(0, 1, cube.initial.x, cube.initial.y, std::make_pair(0.0, 0.0));
  ASSERT_TRUE(out.on_object);
  const table::Pose p = w.physics().objectPose(cube.object_index);
  const double r = c.table.primitives.success_radius;
  EXPECT_LE(std::abs(p.pos[0]), c.table.truth.region_x + r);
  EXPECT_LE(std::abs(p.pos[1]), c.table.truth.region_y + r);
  EXPECT_EQ(blobs(w.render()).size(), 2u) << "the cube is still in view";
}

TEST(TableWorld, ATableScenarioIsRefusedNamingWhatIsWrong) {
  const auto refusal = [](const std::string& yaml) -> std::string {
    try {
      tableTest(yaml);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  const std::string one = "name: t\nworld: table\nobjects:\n  - ";
  EXPECT_NE(refusal(one + "{object: teapot, initial: {position: [0.3, 0.37]}, goal: {position: [0.4, 0.37]}}")
                .find("'teapot' is none of table.objects (cube, ball, log, can, bar, disc)"),
            std::string::npos);
  EXPECT_NE(refusal(one + "{object: cube, initial: {position: [0.02, 0.37]}, goal: {position: [0.4, 0.37]}}")
                .find("objects[0].initial.position': shows the table's point"),
            std::string::npos);
  EXPECT_NE(refusal(one + "{object: cube, initial: {position: [0.3, 0.37]}, goal: {position: [0.4, 0.9]}}")
                .find("goal.position"),
            std::string::npos);
  EXPECT_NE(refusal(one + "{object: cube, initial: {position: [0.3, 0.37]}, goal: {position: [0.4, 0.37]}}\n"
                          "  - {object: disc, initial: {position: [0.32, 0.37]}, goal: {position: [0.6, 0.37]}}")
                .find("objects[1].initial.position': 'disc' is within table.scene.gap"),
            std::string::npos);
  EXPECT_NE(refusal("name: t\nobjects:\n  - {object: cube, initial: {position: [0.3, 0.37]}, goal: {position: [0.4, 0.37]}}")
                .find("the scenario is of the grid world (it says no `world:`), and this run's world is table"),
            std::string::npos);
  // And a table scenario given to the paper's world.
  RunConfig grid = test::shippedConfig();
  try {
    parseScenario(YAML::Load(one + "{object: cube, initial: {position: [0.3, 0.37]}, goal: {position: [0.4, 0.37]}}"), "",
                  grid.world);
    ADD_FAILURE() << "a table scenario was taken by the grid";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("the scenario is of the table world, and this run's world is grid"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace afford

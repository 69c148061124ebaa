// The physical table as the environment process's world (world.kind: table, docs/model.md#a-physical-table):
// MuJoCo's simulation of the table, its objects and the hand (table/physics.hpp), the top camera's image as
// the scene (table/camera.hpp), each action a motor primitive of the hand (table/primitives.hpp).
//
// The scene is the camera's image, width x height; scene units are a pixel's column and row divided by the
// width. The object an action is for is the one the camera shows at the gaze's pixel (the renderer's
// segmentation); a place in scene units is the point of the table's top that pixel shows. No LCM here.
#pragma once
#include <functional>
#include <memory>

#include "environment/environment.hpp"
#include "environment/table/camera.hpp"
#include "environment/table/primitives.hpp"
#include "environment/table/truth.hpp"

namespace afford {

class TableWorld : public SimWorld {
 public:
  // The run's table, its objects set up as table.scene says (drawn by (seed, 0)); in the extrinsic phase, the
  // scenario's objects at their initial places (the others off the table, out of the camera's view), and the
  // goal image drawn with them at their goal places. Needs an OpenGL context: one is made for the calling
  // thread, which must be the one that uses the world.
  // Throws ConfigError naming the key when the objects do not fit the region, std::runtime_error when there
  // is no OpenGL to be had.
  explicit TableWorld(const RunConfig& config);

  cv::Mat render() const override;
  std::vector<std::vector<std::uint8_t>> probeImages() const override;
  std::vector<std::string> probeNames() const override;
  ActionOutcome execute(std::int64_t step, int action, double x, double y,
                        std::optional<std::pair<double, double>> target = std::nullopt) override;
  bool introduceObjectsAt(std::int64_t step) override;
  bool objectsAppearAt(std::int64_t step) const override;
  std::vector<cv::Point2d> centres() const override;
  // Extrinsic phase: the goal image; the scenario's objects' goal places; the goal distance: the mean, over
  // the scenario's objects, of how much further than table.primitives.success_radius each rests from its goal
  // place, over the region's diagonal (0: every object at its goal), and the summed value of those within it.
  const cv::Mat& goalScene() const override;
  std::vector<cv::Point2d> goalCentres() const override;
  double goalDistance() const override;
  double goalUtility() const override;
  // The simulation's whole state (table/physics.hpp: state()), which continues bit for bit.
  void save(SnapshotWriter& w) const override;
  void load(SnapshotReader& r) override;

  const table::TablePhysics& physics() const { return physics_; }
  // `f` with the simulation after every `every`-th physics step of the actions from now on, its bodies' places
  // computed for a camera (the run goes on as without it); an empty `f` stops it (afford render --primitive).
  void observe(std::function<void(const table::TablePhysics&)> f, int every);
  // The last action's primitive: its physics steps, whether the scene came to rest.
  const table::PrimitiveResult& lastPrimitive() const { return last_; }
  // The object the camera shows at a place (scene units), or -1.
  int objectAt(double x, double y) const;
  // A point of the table's top (m) in scene units, at height z, and back (z = 0).
  cv::Point2d toScene(double x, double y, double z = 0) const;
  cv::Point2d toTable(double sx, double sy) const;

 private:
  // Every object at a drawn free place of the region, in its configured pose turned by a drawn yaw.
  void setUp(std::int64_t step);
  // The scenario's objects at their initial (or goal) places, unturned; the others parked off the table.
  void setUpScenario(bool goal);
  // How far an object of the scenario rests from its goal place (m).
  double fromGoal(const ScenarioObject& o) const;
  // A place for a push or a carry of `object`: drawn by (seed, step) as the truth's trials draw theirs.
  std::pair<double, double> drawPlace(std::int64_t step, int object) const;

  table::TableWorldConfig table_;
  int focus_side_ = 0;
  std::int64_t seed_ = 0, steps_ = 0;
  table::TablePhysics physics_;
  std::unique_ptr<table::TableCamera> camera_;
  table::PrimitiveResult last_;
  std::optional<Scenario> scenario_;   // extrinsic phase
  cv::Mat goal_;
  std::vector<cv::Point2d> goal_centres_;
  std::vector<bool> present_;          // the objects in the scene (the others are parked off the table)
  mutable cv::Mat segments_;  // the camera's objects at the state it was drawn for (empty: to draw)
  mutable std::vector<std::vector<std::uint8_t>> probes_;
};

}  // namespace afford

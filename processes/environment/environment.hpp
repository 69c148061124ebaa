// Environment core (paper 2.2, 2.3.2): the objects, their affordance table,
// the rendered scene, the pre-wired action routines and stochastic success.
// No LCM here: the node (node.hpp) wires it to channels.
#pragma once
#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <vector>

#include "afford/config.hpp"
#include "afford/image.hpp"
#include "afford/snapshot.hpp"

namespace afford {

struct WorldObject {
  int table_index = 0;   // row of the experiment's affordance table (= probe index)
  Shape shape = Shape::Square;
  Colour colour = Colour::Red;
  double x = 0, y = 0;   // centre, scene units (a pixel's, in the pixel world)
  Pixel centre;          // the nearest pixel
  std::vector<Pixel> pixels;  // what it covers (image.hpp: shapePixels)
  bool present = false;
};

struct ActionOutcome {
  bool on_object = false;     // an object was under the gaze
  bool succeeded = false;     // the action's effect happened
  double target_x = -1.0;     // move target (scene units), -1 for colour actions
  double target_y = -1.0;
  // The table world: the simulation became unstable in the action (MuJoCo set its data back); the action
  // failed and the scene was set up anew.
  bool unstable = false;
};

// What the environment is given of the run's configuration: the world (its objects and their table), the
// eye's window side (a move target's window must be free, paper 2.3.2) and the run's seed.
struct EnvironmentParams {
  WorldConfig world;
  int focus_side = 0;
  std::int64_t seed = 0;
  EnvironmentParams() = default;
  EnvironmentParams(const RunConfig& c)  // NOLINT: the sections a run's configuration gives
      : world(c.world), focus_side(c.eye.focus_side), seed(c.seed) {}
};

// A world the environment process simulates (world.kind): the paper's grid (Environment) or the physical
// table (TableWorld). Positions are scene units: a pixel's column and row divided by the image's width.
class SimWorld {
 public:
  virtual ~SimWorld() = default;
  // The scene as it is now, and each configured object alone as the eye's focus would see it (their order).
  virtual cv::Mat render() const = 0;
  virtual std::vector<std::vector<std::uint8_t>> probeImages() const = 0;
  virtual std::vector<std::string> probeNames() const = 0;
  // Execute `action` at `step` on the object under the gaze (x, y). For an action that takes a place,
  // `target` is the commanded one (the table: the nearest point of table.truth.region); without one (intrinsic
  // phase) the world draws a place.
  virtual ActionOutcome execute(std::int64_t step, int action, double x, double y,
                                std::optional<std::pair<double, double>> target = std::nullopt) = 0;
  // The world changes the scene at `step` (objects appear; the table set up anew); true if it did.
  virtual bool introduceObjectsAt(std::int64_t step) = 0;
  virtual bool objectsAppearAt(std::int64_t step) const = 0;
  // The true centres of the objects in the scene (eye.fovea = true_centre), in the world's order.
  virtual std::vector<cv::Point2d> centres() const = 0;
  // Extrinsic phase: the goal scene, its objects' centres, the scene's distance from it and its utility.
  virtual const cv::Mat& goalScene() const = 0;
  virtual std::vector<cv::Point2d> goalCentres() const = 0;
  virtual double goalDistance() const = 0;
  virtual double goalUtility() const = 0;
  // A snapshot's part (afford/snapshot.hpp): the world's state now.
  virtual void save(SnapshotWriter& w) const = 0;
  virtual void load(SnapshotReader& r) = 0;
};

class Environment : public SimWorld {
 public:
  explicit Environment(const EnvironmentParams& params);
  // Extrinsic phase: the scenario's objects in their initial states. Their
  // affordances come from the experiment's table, by current look.
  Environment(const EnvironmentParams& params, const Scenario& scenario);

  // The goal configuration of the scenario (extrinsic phase).
  const cv::Mat& goalScene() const override;
  // Distance of the scene from the goal image: ||scene - goal||_2 / (size^2 * 3),
  // values in [0, 1]; the test succeeds below planner.success_distance.
  double goalDistance() const override;
  // The summed value of the scenario's objects that are in their goal state
  // (colour and place), the measure of the utility tests (paper 3.2.2).
  double goalUtility() const override;

  // The scene as it is now.
  cv::Mat render() const override;
  // Each configured object alone, centred, as the eye's focus would see it (Table order).
  std::vector<std::vector<std::uint8_t>> probeImages() const override;
  std::vector<std::string> probeNames() const override;

  // Execute `action` at `step` on the object under the gaze (x, y). For move,
  // `target` is the commanded position; without one (intrinsic phase) the
  // routine draws a random free target.
  ActionOutcome execute(std::int64_t step, int action, double x, double y,
                        std::optional<std::pair<double, double>> target = std::nullopt) override;
  // Put in the scene the objects that appear at `step`; true if any did.
  bool introduceObjectsAt(std::int64_t step) override;
  // True if objects are due to appear at `step`.
  bool objectsAppearAt(std::int64_t step) const override;

  const std::vector<WorldObject>& objects() const { return objects_; }
  // A snapshot's part (afford/snapshot.hpp): the objects as they are now (the goal and the configuration
  // come from the run's configuration). load() refuses objects the configuration does not have.
  void save(SnapshotWriter& w) const override;
  void load(SnapshotReader& r) override;
  // The true centres of the objects in the scene (render), or in the goal
  // (goalScene), in the environment's order: what a SCENE lists for the
  // eye's true_centre fovea (issue 28).
  std::vector<cv::Point2d> centres() const override;
  std::vector<cv::Point2d> goalCentres() const override;
  // Index into objects() of the present object covering a pixel, or -1; where
  // objects overlap, the one drawn last (on top).
  int objectAt(Pixel p) const;
  // Row of the affordance table that applies to an object as it looks now.
  // -1 if the table has no object that looks like it: it affords nothing.
  int tableRow(const WorldObject& o) const;

 private:
  // Put an object's centre at (x, y), scene units (snapped to a pixel in the pixel world).
  void place(WorldObject& o, double x, double y) const;
  // Is a place free for an object of `shape` (nullptr: no object)? Continuous
  // positions: the focus window there (windowCorner) holds no pixel of the
  // objects `counts` accepts (indices into objects_), and the shape drawn
  // there touches none of them. Pixel world: the square of half-size
  // free_half_ around the place's pixel holds none.
  template <class Counts>
  bool placeFree(double x, double y, const Shape* shape, Counts counts) const;
  bool placeFree(double x, double y, const Shape* shape) const;  // of every present object
  bool continuous() const { return config_.world.positions == Positions::Continuous; }

  EnvironmentParams config_;
  std::optional<Scenario> scenario_;
  std::vector<WorldObject> objects_;
  int free_half_ = 0;                           // pixel world: half-size of the square a place must have free
  cv::Mat goal_;                                // extrinsic phase: the goal scene
};

}  // namespace afford

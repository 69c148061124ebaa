// Eye core (paper 2.3.1): bottom-up saliency scan with keyed noise, the
// change-driven scan of action effects, the focus image and the change tests.
// Object identity comes from connected blobs on the black background; the
// fovea is centred on the chosen blob (docs/parameters.md, "saliency scan"),
// or, with eye.fovea = true_centre, on the true centre of the object the blob
// shows, from the list of centres given with the image (docs/model.md#fovea).
// No LCM here.
#pragma once
#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <vector>

#include "afford/config.hpp"
#include "afford/image.hpp"
#include "afford/snapshot.hpp"

namespace afford {

struct Focus {
  Pixel gaze;
  double x = 0, y = 0;               // gaze in scene units
  std::vector<std::uint8_t> image;   // focus_side^2 * 3 bytes
};

struct Effect {
  Focus before, after;
  double image_change = 0;           // L1 / dims
  double position_change = 0;        // L1 / 2
  bool image_changed = false, position_changed = false;
  bool affordance = false;           // the performed action's own effect was seen
};

// What the eye is given of the run's configuration: its own section, the scene's geometry (its side, how
// object centres become pixels) and the run's seed.
struct EyeParams {
  EyeConfig eye;
  struct World {
    int size_px = 0;
    Positions positions = Positions::Continuous;
    WorldKind kind = WorldKind::Grid;
    int height_px = 0;
  } world;
  // The table world's actions' effects as the eye sees them (scene units; docs/model.md#a-physical-table):
  // push and carry, the object within place_radius of the place; roll, moved at least roll_distance; topple,
  // the object's silhouette grown by topple_area.
  struct TableEffects {
    double place_radius = 0, roll_distance = 0, topple_area = 0;
  } table;
  std::int64_t seed = 0;
  EyeParams() = default;
  EyeParams(const RunConfig& c);  // NOLINT: the sections a run's configuration gives
};

class Eye {
 public:
  explicit Eye(const EyeParams& params);

  // Replace the scene the eye looks at (after a scene message). `objects`: the
  // true centres of the objects in it (scene units), read only with
  // eye.fovea = true_centre; then every blob must hold one of them, or
  // std::invalid_argument names the blob (and the eye keeps what it had).
  void setScene(cv::Mat scene, std::vector<cv::Point2d> objects = {});
  bool hasScene() const { return !outer_.rgb.empty(); }
  const cv::Mat& scene() const { return outer_.rgb; }
  const Focus& focus() const { return outer_.focus; }
  // The window at the gaze on the current scene (the gaze does not move).
  Focus atGaze() const { return refocus(outer_); }

  // Saliency scan (Algorithm 1, Scan): noise keyed by (seed, step), redrawn
  // until the gaze lands on another object than the current one.
  const Focus& scan(std::int64_t step);
  // The scan of `step` from the current scene and gaze, without moving the
  // gaze: scan(step) == look(peekScan(step)).
  Focus peekScan(std::int64_t step) const;
  // Move the gaze to a focus computed by peekScan on the current scene.
  const Focus& look(Focus f);
  // Change-driven scan after `action` was executed at `step` (ScanEffect and
  // Affordance): looks at the changed object in `after` and compares it with
  // the focus before the action. The eye then looks at `after`.
  // `objects` as for setScene.
  // `target`: the place the action was given (scene units), for the table world's push and carry.
  Effect scanEffect(std::int64_t step, cv::Mat after, int action, std::vector<cv::Point2d> objects = {},
                    std::optional<cv::Point2d> target = std::nullopt);
  // The object blob label under a pixel of the scene (0 = background).
  int labelAt(Pixel p) const { return labelAt(outer_, p); }
  // A snapshot's part (afford/snapshot.hpp): the scene, its listed objects and the focus on it (the goal is
  // the extrinsic phase's, which takes none).
  void save(SnapshotWriter& w) const;
  void load(SnapshotReader& r);

  // Extrinsic phase (paper 2.4.3). The inner eye looks at the memorised goal image.
  void setGoal(cv::Mat goal, std::vector<cv::Point2d> objects = {});
  // What setScene would refuse of this image and list, without taking it.
  void checkScene(cv::Mat scene, std::vector<cv::Point2d> objects) const;
  bool hasGoal() const { return !inner_.rgb.empty(); }
  // Scan: the inner eye's saliency scan of the goal image (a sub-goal).
  const Focus& scanGoal(std::int64_t step);
  // ScanEnvironmentWithSameFocusAsSubGoal: the outer eye looks at a place of
  // the scene (scene units), with the window it would put there for an object.
  const Focus& lookAt(double x, double y);

  // Top-down attention (issue 12). The places where goal and scene differ:
  // every goal blob whose window differs from the scene's window at its place
  // (imageDistance >= match), then every scene blob whose window differs from
  // the goal's at its place, each in label order (row-major first pixel). No
  // noise, and the gaze stays.
  std::vector<Difference> goalDifferences(double match) const;
  // The outer eye attends the object under (x, y): its blob, focused as a scan
  // would (focusOnBlob); with no object there, the window at (x, y).
  const Focus& attend(double x, double y);

 private:
  // One image the eye looks at, its saliency cache and the gaze on it.
  struct Retina {
    cv::Mat rgb;        // CV_8UC3 RGB
    cv::Mat gray;       // CV_32F: RGB mean in [0, 1] (the periphery)
    cv::Mat smooth;     // CV_32F: gray smoothed
    cv::Mat labels;     // CV_32S blob labels
    cv::Mat stats;      // blob bounding boxes
    cv::Mat centroids;  // blob centroids (CV_64F, pixel indices)
    int n_labels = 1;
    // eye.fovea = true_centre: the objects' true centres (scene units), and
    // for each blob label the one it shows (-1 for the background).
    std::vector<cv::Point2d> objects;
    std::vector<int> object_of;
    // smooth_then_noise: the pixels of `smooth` within 2 * noise of its
    // maximum, ascending, the only ones a scan can land on; the same for every
    // scan of this image, so found once.
    std::vector<int> contenders;
    Focus focus;
  };
  void setImage(Retina& r, cv::Mat image, std::vector<cv::Point2d> objects) const;
  // true_centre: which listed object each blob shows (its centre's pixel is
  // in the blob; of several, the nearest to the blob's centroid).
  void matchObjects(Retina& r) const;
  static int labelAt(const Retina& r, Pixel p);
  // The pixels of the blob under the gaze (0: none).
  static int areaAtGaze(const Retina& r);
  // The table world's rule: whether the action's goal is seen reached.
  bool tableEffect(const Effect& e, int action, int area_before, int area_after, std::optional<cv::Point2d> target) const;
  static Pixel blobCentre(const Retina& r, int label);
  Focus focusAt(const Retina& r, Pixel p) const;
  // The focus on a place (scene units). Continuous world: the window's corner
  // is windowCorner(x, y) (the authors' round-half-away(150 (x - 0.07))), and
  // the place is kept as given; pixel world: the window around the nearest pixel.
  Focus focusOn(const Retina& r, double x, double y) const;
  // The focus on a blob: continuous world, on its centroid (the eye's estimate
  // of the object's real centre); pixel world, on its bounding box's centre.
  // With eye.fovea = true_centre, on the true centre of the object it shows.
  Focus focusOnBlob(const Retina& r, int label) const;
  // The same place looked at again on a new image.
  Focus refocus(const Retina& r) const;
  Focus peekScan(const Retina& r, std::int64_t step, int purpose) const;
  // argmax of r's saliency (+ extra) + uniform noise (keyed), exact over the whole image.
  int noisyArgmax(const Retina& r, std::int64_t step, int purpose, std::uint64_t attempt, const cv::Mat* extra) const;

  EyeParams config_;
  Retina outer_;   // the scene
  Retina inner_;   // the goal image (extrinsic phase)
};

}  // namespace afford

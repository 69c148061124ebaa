// Eye core (paper 2.3.1): bottom-up saliency scan with keyed noise, the
// change-driven scan of action effects, the focus image and the change tests.
// Object identity comes from connected blobs on the black background; the
// fovea is centred on the chosen blob (PARAMETERS.md, "saliency scan").
// No LCM here.
#pragma once
#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

#include "afford/config.hpp"
#include "afford/image.hpp"

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

class Eye {
 public:
  explicit Eye(const RunConfig& config);

  // Replace the scene the eye looks at (after a scene message).
  void setScene(cv::Mat scene);
  bool hasScene() const { return !scene_.empty(); }
  const cv::Mat& scene() const { return scene_; }
  const Focus& focus() const { return focus_; }

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
  Effect scanEffect(std::int64_t step, cv::Mat after, int action);
  // The object blob label under a pixel (0 = background).
  int labelAt(Pixel p) const;
  int objectCount() const { return n_labels_ - 1; }

 private:
  Pixel blobCentre(int label) const;
  Focus focusAt(Pixel p) const;
  // argmax of base + uniform noise (keyed), exact over the whole image.
  int noisyArgmax(const cv::Mat& base, std::int64_t step, int purpose, std::uint64_t attempt,
                  const cv::Mat* extra) const;

  RunConfig config_;
  cv::Mat scene_;        // CV_8UC3 RGB
  cv::Mat gray_;         // CV_32F: RGB mean in [0, 1] (the periphery)
  cv::Mat smooth_;       // CV_32F: gray_ smoothed
  cv::Mat labels_;       // CV_32S blob labels
  cv::Mat stats_;        // blob bounding boxes
  int n_labels_ = 1;
  Focus focus_;
};

}  // namespace afford

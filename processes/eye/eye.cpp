#include "eye/eye.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>

#include "afford/actions.hpp"
#include "afford/rng.hpp"

namespace afford {
namespace {

cv::Mat blur(const cv::Mat& in, double sigma) {
  if (sigma <= 0) return in.clone();
  cv::Mat out;
  cv::GaussianBlur(in, out, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT_101);
  return out;
}

cv::Mat meanChannels(const cv::Mat& rgb) {
  cv::Mat gray(rgb.rows, rgb.cols, CV_32F);
  for (int r = 0; r < rgb.rows; ++r) {
    const auto* in = rgb.ptr<cv::Vec3b>(r);
    auto* out = gray.ptr<float>(r);
    for (int c = 0; c < rgb.cols; ++c) out[c] = (in[c][0] + in[c][1] + in[c][2]) / (3.0f * 255.0f);
  }
  return gray;
}

// Mean over channels of the positive part of after - before (paper 2.3.1 "change
// image"; positive part so that the gaze goes where an object arrives, not
// where it left).
cv::Mat positiveChange(const cv::Mat& before, const cv::Mat& after) {
  cv::Mat change(after.rows, after.cols, CV_32F);
  for (int r = 0; r < after.rows; ++r) {
    const auto* b = before.ptr<cv::Vec3b>(r);
    const auto* a = after.ptr<cv::Vec3b>(r);
    auto* out = change.ptr<float>(r);
    for (int c = 0; c < after.cols; ++c) {
      int sum = 0;
      for (int k = 0; k < 3; ++k) sum += std::max(0, static_cast<int>(a[c][k]) - static_cast<int>(b[c][k]));
      out[c] = sum / (3.0f * 255.0f);
    }
  }
  return change;
}

int dominantChannel(const std::vector<std::uint8_t>& image) {
  long sums[3] = {0, 0, 0};
  for (std::size_t i = 0; i < image.size(); ++i) sums[i % 3] += image[i];
  if (sums[0] == 0 && sums[1] == 0 && sums[2] == 0) return -1;
  return static_cast<int>(std::max_element(sums, sums + 3) - sums);
}

}  // namespace

Eye::Eye(const RunConfig& config) : config_(config) {
  focus_.gaze = toPixel(config.eye.initial_gaze_x, config.eye.initial_gaze_y, config.world.size_px);
  focus_.x = toUnit(focus_.gaze.col, config.world.size_px);
  focus_.y = toUnit(focus_.gaze.row, config.world.size_px);
}

void Eye::setScene(cv::Mat scene) {
  scene_ = std::move(scene);
  gray_ = meanChannels(scene_);
  smooth_ = blur(gray_, config_.eye.saliency_sigma_px);
  cv::Mat mask = gray_ > 0;
  cv::Mat centroids;
  n_labels_ = cv::connectedComponentsWithStats(mask, labels_, stats_, centroids, 8, CV_32S);
  if (!focus_.image.empty()) focus_ = focusAt(focus_.gaze);
}

int Eye::labelAt(Pixel p) const {
  if (p.row < 0 || p.col < 0 || p.row >= labels_.rows || p.col >= labels_.cols) return 0;
  return labels_.at<int>(p.row, p.col);
}

Pixel Eye::blobCentre(int label) const {
  const int left = stats_.at<int>(label, cv::CC_STAT_LEFT), top = stats_.at<int>(label, cv::CC_STAT_TOP);
  const int w = stats_.at<int>(label, cv::CC_STAT_WIDTH), h = stats_.at<int>(label, cv::CC_STAT_HEIGHT);
  return {left + w / 2, top + h / 2};
}

Focus Eye::focusAt(Pixel p) const {
  Focus f;
  f.gaze = p;
  f.x = toUnit(p.col, config_.world.size_px);
  f.y = toUnit(p.row, config_.world.size_px);
  f.image = cropFocus(scene_, p, config_.eye.focus_side);
  return f;
}

int Eye::noisyArgmax(const cv::Mat& base, std::int64_t step, int purpose, std::uint64_t attempt,
                     const cv::Mat* extra) const {
  const double noise = config_.eye.saliency_noise;
  const KeyedRng rng(config_.seed, step, static_cast<Purpose>(purpose));
  const std::uint64_t n = base.total();
  const std::uint64_t offset = attempt * n;
  if (config_.eye.saliency_order == SaliencyOrder::NoiseThenSmooth) {
    // Paper's order: noise on the periphery, then smoothing.
    cv::Mat noisy = gray_.clone();
    auto* p = noisy.ptr<float>();
    for (std::uint64_t i = 0; i < n; ++i) p[i] += static_cast<float>((rng.uniform(offset + i) * 2.0 - 1.0) * noise);
    cv::Mat s = blur(noisy, config_.eye.saliency_sigma_px);
    if (extra) s += *extra;
    double mx;
    cv::Point at;
    cv::minMaxLoc(s, nullptr, &mx, nullptr, &at);
    return at.y * base.cols + at.x;
  }
  // Authors' order: smoothing, then noise. Only pixels within 2 * noise of the
  // maximum can win, so only they need a draw: the result equals drawing noise
  // for every pixel, because draws are addressed by pixel index.
  cv::Mat sum = extra ? cv::Mat(base + *extra) : base;
  const float* b = sum.ptr<float>();
  double mx;
  cv::minMaxLoc(sum, nullptr, &mx);
  const double cut = mx - 2.0 * noise;
  int best = 0;
  double best_v = -std::numeric_limits<double>::infinity();
  for (std::uint64_t i = 0; i < n; ++i) {
    if (b[i] < cut) continue;
    const double v = b[i] + (rng.uniform(offset + i) * 2.0 - 1.0) * noise;
    if (v > best_v) {
      best_v = v;
      best = static_cast<int>(i);
    }
  }
  return best;
}

const Focus& Eye::scan(std::int64_t step) { return look(peekScan(step)); }

const Focus& Eye::look(Focus f) {
  focus_ = std::move(f);
  return focus_;
}

Focus Eye::peekScan(std::int64_t step) const {
  const int objects = objectCount();
  if (objects == 0) return focusAt(focus_.gaze);
  const int current = labelAt(focus_.gaze);
  int chosen = 0;
  for (int attempt = 0; attempt < config_.eye.max_scan_draws; ++attempt) {
    const int i = noisyArgmax(smooth_, step, static_cast<int>(Purpose::ScanNoise), attempt, nullptr);
    const int label = labels_.at<int>(i / labels_.cols, i % labels_.cols);
    if (label == 0) continue;
    chosen = label;
    if (objects == 1 || label != current) break;
  }
  return focusAt(chosen > 0 ? blobCentre(chosen) : focus_.gaze);
}

Effect Eye::scanEffect(std::int64_t step, cv::Mat after, int action) {
  Effect e;
  e.before = focus_;
  cv::Mat change = blur(positiveChange(scene_, after), config_.eye.change_sigma_px);
  setScene(std::move(after));
  double max_change;
  cv::minMaxLoc(change, nullptr, &max_change);
  if (max_change > 0) {
    const int i = noisyArgmax(smooth_, step, static_cast<int>(Purpose::EffectNoise), 0, &change);
    const Pixel p{i % labels_.cols, i / labels_.cols};
    const int label = labelAt(p);
    focus_ = focusAt(label > 0 ? blobCentre(label) : p);
  } else {
    focus_ = focusAt(focus_.gaze);  // nothing changed: no reflex, the gaze stays
  }
  e.after = focus_;
  e.image_change = imageChange(e.before.image, e.after.image);
  e.position_change = (std::abs(e.after.x - e.before.x) + std::abs(e.after.y - e.before.y)) / 2.0;
  e.image_changed = e.image_change > config_.eye.image_change_threshold;
  e.position_changed = e.position_change > config_.eye.position_change_threshold;
  // The effect must be the performed action's own (paper 2.3.1): a displacement
  // for move; for a colour action, the same place with the focus now in that colour.
  if (action == kMove)
    e.affordance = e.position_changed;
  else if (validAction(action))
    e.affordance = e.image_changed && !e.position_changed && dominantChannel(e.after.image) == kActionChannel[action];
  return e;
}

}  // namespace afford

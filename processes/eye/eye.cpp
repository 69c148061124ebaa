#include "eye/eye.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

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

// How many of 64 floats are not below a cut. Counted, not tested one by one,
// and kept out of line: GCC vectorises it so, and not once inlined and unrolled.
[[gnu::noinline]] int countNotBelow(const float* b, float cut) {
  int n = 0;
  for (int j = 0; j < 64; ++j) n += !(b[j] < cut);
  return n;
}

// The pixels of a saliency map a noisy argmax with noise in [-noise, noise]
// can choose: those within 2 * noise of its maximum, ascending.
std::vector<int> contenders(const cv::Mat& saliency, double noise) {
  double mx;
  cv::minMaxLoc(saliency, nullptr, &mx);
  const double cut = mx - 2.0 * noise;
  // The least float not below cut: a float b is below cut exactly when it is
  // below this, and the test needs no conversion to double.
  float fcut = static_cast<float>(cut);
  if (static_cast<double>(fcut) < cut) fcut = std::nextafter(fcut, std::numeric_limits<float>::infinity());
  const float* b = saliency.ptr<float>();
  const int n = static_cast<int>(saliency.total());
  std::vector<int> out;
  constexpr int kRun = 64;  // most of a scene is background, far below the cut: skipped a run at a time
  int i = 0;
  for (; i + kRun <= n; i += kRun) {
    if (countNotBelow(b + i, fcut) == 0) continue;
    for (int j = 0; j < kRun; ++j)
      if (!(b[i + j] < fcut)) out.push_back(i + j);
  }
  for (; i < n; ++i)
    if (!(b[i] < fcut)) out.push_back(i);
  return out;
}

int dominantChannel(const std::vector<std::uint8_t>& image) {
  long sums[3] = {0, 0, 0};
  for (std::size_t i = 0; i < image.size(); ++i) sums[i % 3] += image[i];
  if (sums[0] == 0 && sums[1] == 0 && sums[2] == 0) return -1;
  return static_cast<int>(std::max_element(sums, sums + 3) - sums);
}

}  // namespace

EyeParams::EyeParams(const RunConfig& c)
    : eye(c.eye), world{c.world.size_px, c.world.positions, c.world.kind, c.world.rows()}, seed(c.seed) {
  if (c.world.kind == WorldKind::Table) {
    // Scene units a metre of the table's top is: the camera's focal length in pixels over its height, per width.
    const table::CameraSpec& cam = c.table.spec.camera;
    const double per_metre = 0.5 * cam.height / std::tan(cam.fovy_deg * M_PI / 360.0) / cam.above / cam.width;
    table = {c.table.primitives.success_radius * per_metre, c.table.primitives.roll_distance * per_metre,
             c.table.perception.topple_area};
  }
}

Eye::Eye(const EyeParams& params) : config_(params) {
  const Pixel start = toPixel(params.eye.initial_gaze_x, params.eye.initial_gaze_y, params.world.size_px);
  for (Retina* r : {&outer_, &inner_}) {
    r->focus.gaze = start;
    r->focus.x = toUnit(start.col, params.world.size_px);
    r->focus.y = toUnit(start.row, params.world.size_px);
  }
}

void Eye::setImage(Retina& r, cv::Mat image, std::vector<cv::Point2d> objects) const {
  // With true_centre an image can be refused (a blob without a listed object):
  // it is then built aside, so that a refused one leaves the retina as it was.
  // Otherwise the retina takes it in place, its buffers reused scene to scene.
  const bool checked = config_.eye.fovea == Fovea::TrueCentre;
  Retina aside;
  Retina& n = checked ? aside : r;
  n.rgb = std::move(image);
  n.gray = meanChannels(n.rgb);
  n.smooth = blur(n.gray, config_.eye.saliency_sigma_px);
  cv::Mat mask = n.gray > 0;
  n.n_labels = cv::connectedComponentsWithStats(mask, n.labels, n.stats, n.centroids, 8, CV_32S);
  if (checked) {
    n.objects = std::move(objects);
    matchObjects(n);  // throws: a blob without an object
  }
  if (config_.eye.saliency_order == SaliencyOrder::SmoothThenNoise)
    n.contenders = contenders(n.smooth, config_.eye.saliency_noise);
  if (checked) {
    n.focus = std::move(r.focus);
    r = std::move(n);
  }
  if (!r.focus.image.empty()) r.focus = refocus(r);
}

void Eye::matchObjects(Retina& r) const {
  const int size = config_.world.size_px;
  r.object_of.assign(static_cast<std::size_t>(r.n_labels), -1);
  std::vector<double> best(static_cast<std::size_t>(r.n_labels), std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < r.objects.size(); ++i) {
    const cv::Point2d& o = r.objects[i];
    const int label = labelAt(r, toPixel(o.x, o.y, size));
    if (label == 0) continue;  // a listed object the image does not show: never looked at
    const double d = std::hypot(o.x * size - r.centroids.at<double>(label, 0), o.y * size - r.centroids.at<double>(label, 1));
    if (d < best[static_cast<std::size_t>(label)]) {
      best[static_cast<std::size_t>(label)] = d;
      r.object_of[static_cast<std::size_t>(label)] = static_cast<int>(i);
    }
  }
  for (int label = 1; label < r.n_labels; ++label)
    if (r.object_of[static_cast<std::size_t>(label)] < 0)
      throw std::invalid_argument(
          "object_x, object_y: the object seen at pixel (" + std::to_string(r.stats.at<int>(label, cv::CC_STAT_LEFT)) + ", " +
          std::to_string(r.stats.at<int>(label, cv::CC_STAT_TOP)) + ") holds none of the " + std::to_string(r.objects.size()) +
          " object centres listed, and eye.fovea = true_centre places the window on an object's true centre");
}

void Eye::setScene(cv::Mat scene, std::vector<cv::Point2d> objects) { setImage(outer_, std::move(scene), std::move(objects)); }
void Eye::setGoal(cv::Mat goal, std::vector<cv::Point2d> objects) { setImage(inner_, std::move(goal), std::move(objects)); }
void Eye::checkScene(cv::Mat scene, std::vector<cv::Point2d> objects) const {
  Retina r;
  setImage(r, std::move(scene), std::move(objects));
}

int Eye::labelAt(const Retina& r, Pixel p) {
  if (p.row < 0 || p.col < 0 || p.row >= r.labels.rows || p.col >= r.labels.cols) return 0;
  return r.labels.at<int>(p.row, p.col);
}

Pixel Eye::blobCentre(const Retina& r, int label) {
  const int left = r.stats.at<int>(label, cv::CC_STAT_LEFT), top = r.stats.at<int>(label, cv::CC_STAT_TOP);
  const int w = r.stats.at<int>(label, cv::CC_STAT_WIDTH), h = r.stats.at<int>(label, cv::CC_STAT_HEIGHT);
  return {left + w / 2, top + h / 2};
}

Focus Eye::focusAt(const Retina& r, Pixel p) const {
  Focus f;
  f.gaze = p;
  f.x = toUnit(p.col, config_.world.size_px);
  f.y = toUnit(p.row, config_.world.size_px);
  f.image = cropFocus(r.rgb, p, config_.eye.focus_side);
  return f;
}

Focus Eye::focusOn(const Retina& r, double x, double y) const {
  const int size = config_.world.size_px, side = config_.eye.focus_side;
  if (config_.world.positions == Positions::Pixel) return focusAt(r, toPixel(x, y, size));
  const Pixel corner = windowCorner(x, y, side, size);
  Focus f = focusAt(r, {corner.col + side / 2, corner.row + side / 2});
  f.x = x;
  f.y = y;
  return f;
}

Focus Eye::focusOnBlob(const Retina& r, int label) const {
  if (config_.eye.fovea == Fovea::TrueCentre) {  // setImage matched every blob to an object
    const cv::Point2d& o = r.objects[static_cast<std::size_t>(r.object_of[static_cast<std::size_t>(label)])];
    return focusOn(r, o.x, o.y);
  }
  if (config_.world.positions == Positions::Pixel) return focusAt(r, blobCentre(r, label));
  const double size = config_.world.size_px;
  return focusOn(r, r.centroids.at<double>(label, 0) / size, r.centroids.at<double>(label, 1) / size);
}

Focus Eye::refocus(const Retina& r) const {
  Focus f = focusAt(r, r.focus.gaze);
  f.x = r.focus.x;
  f.y = r.focus.y;
  return f;
}

int Eye::noisyArgmax(const Retina& r, std::int64_t step, int purpose, std::uint64_t attempt, const cv::Mat* extra) const {
  const double noise = config_.eye.saliency_noise;
  const KeyedRng rng(config_.seed, step, static_cast<Purpose>(purpose));
  const std::uint64_t n = r.smooth.total();
  const std::uint64_t offset = attempt * n;
  if (config_.eye.saliency_order == SaliencyOrder::NoiseThenSmooth) {
    // Paper's order: noise on the periphery, then smoothing.
    cv::Mat noisy = r.gray.clone();
    auto* p = noisy.ptr<float>();
    for (std::uint64_t i = 0; i < n; ++i) p[i] += static_cast<float>((rng.uniform(offset + i) * 2.0 - 1.0) * noise);
    cv::Mat s = blur(noisy, config_.eye.saliency_sigma_px);
    if (extra) s += *extra;
    double mx;
    cv::Point at;
    cv::minMaxLoc(s, nullptr, &mx, nullptr, &at);
    return at.y * r.smooth.cols + at.x;
  }
  // Authors' order: smoothing, then noise. Only pixels within 2 * noise of the
  // maximum can win, so only they need a draw: the result equals drawing noise
  // for every pixel, because draws are addressed by pixel index.
  const cv::Mat sum = extra ? cv::Mat(r.smooth + *extra) : r.smooth;
  const std::vector<int> own = extra ? contenders(sum, noise) : std::vector<int>();
  const float* b = sum.ptr<float>();
  int best = 0;
  double best_v = -std::numeric_limits<double>::infinity();
  for (const int i : extra ? own : r.contenders) {
    const double v = b[i] + (rng.uniform(offset + static_cast<std::uint64_t>(i)) * 2.0 - 1.0) * noise;
    if (v > best_v) {
      best_v = v;
      best = i;
    }
  }
  return best;
}

const Focus& Eye::scan(std::int64_t step) { return look(peekScan(step)); }

const Focus& Eye::look(Focus f) {
  outer_.focus = std::move(f);
  return outer_.focus;
}

Focus Eye::peekScan(std::int64_t step) const { return peekScan(outer_, step, static_cast<int>(Purpose::ScanNoise)); }

const Focus& Eye::scanGoal(std::int64_t step) {
  inner_.focus = peekScan(inner_, step, static_cast<int>(Purpose::GoalScanNoise));
  return inner_.focus;
}

const Focus& Eye::lookAt(double x, double y) {
  outer_.focus = focusOn(outer_, x, y);
  return outer_.focus;
}

std::vector<Difference> Eye::goalDifferences(double match) const {
  std::vector<Difference> out;
  for (const auto& [from, other, in_goal] : {std::tuple{&inner_, &outer_, true}, std::tuple{&outer_, &inner_, false}})
    for (int label = 1; label < from->n_labels; ++label) {
      Focus here = focusOnBlob(*from, label);
      const Focus there = focusOn(*other, here.x, here.y);
      if (imageDistance(here.image, there.image) >= match) out.push_back({here.x, here.y, in_goal, std::move(here.image)});
    }
  return out;
}

const Focus& Eye::attend(double x, double y) {
  const int label = labelAt(outer_, toPixel(x, y, config_.world.size_px));
  outer_.focus = label > 0 ? focusOnBlob(outer_, label) : focusOn(outer_, x, y);
  return outer_.focus;
}

Focus Eye::peekScan(const Retina& r, std::int64_t step, int purpose) const {
  const int objects = r.n_labels - 1;
  if (objects == 0) return refocus(r);
  const int current = labelAt(r, r.focus.gaze);
  int chosen = 0;
  for (int attempt = 0; attempt < config_.eye.max_scan_draws; ++attempt) {
    const int i = noisyArgmax(r, step, purpose, attempt, nullptr);
    const int label = r.labels.at<int>(i / r.labels.cols, i % r.labels.cols);
    if (label == 0) continue;
    chosen = label;
    if (objects == 1 || label != current) break;
  }
  return chosen > 0 ? focusOnBlob(r, chosen) : refocus(r);
}

int Eye::areaAtGaze(const Retina& r) {
  const int label = labelAt(r, r.focus.gaze);
  return label > 0 ? r.stats.at<int>(label, cv::CC_STAT_AREA) : 0;
}

bool Eye::tableEffect(const Effect& e, int action, int area_before, int area_after,
                      std::optional<cv::Point2d> target) const {
  if (area_before == 0 || area_after == 0) return false;  // no object was looked at, or none is seen now
  const double grown = static_cast<double>(area_after) / area_before;
  const double moved = std::hypot(e.after.x - e.before.x, e.after.y - e.before.y);
  const double fell = config_.table.topple_area;
  switch (action) {
    case 0:  // push
    case 1:  // carry: at the place, in the pose it had
      return target && e.position_changed && grown < fell && grown > 1.0 / fell &&
             std::hypot(e.after.x - target->x, e.after.y - target->y) <= config_.table.place_radius;
    case 2:  // topple: it lies, where it stood
      return grown >= fell;
    case 3:  // roll: it went on
      return moved >= config_.table.roll_distance;
    default:
      return false;
  }
}

Effect Eye::scanEffect(std::int64_t step, cv::Mat after, int action, std::vector<cv::Point2d> objects,
                       std::optional<cv::Point2d> target) {
  Effect e;
  e.before = outer_.focus;
  const bool table = config_.world.kind == WorldKind::Table;
  const int area_before = table ? areaAtGaze(outer_) : 0;
  cv::Mat change;
  double max_change = 0;
  if (!sameImage(outer_.rgb, after)) {  // else the action changed nothing: the retina stands as it is
    change = blur(positiveChange(outer_.rgb, after), config_.eye.change_sigma_px);
    setScene(std::move(after), std::move(objects));
    cv::minMaxLoc(change, nullptr, &max_change);
  } else if (config_.eye.fovea == Fovea::TrueCentre && objects != outer_.objects) {
    setScene(std::move(after), std::move(objects));  // the same pixels, objects moved within them: later looks see where
  }
  if (max_change > 0) {
    const int i = noisyArgmax(outer_, step, static_cast<int>(Purpose::EffectNoise), 0, &change);
    const Pixel p{i % outer_.labels.cols, i / outer_.labels.cols};
    const int label = labelAt(outer_, p);
    outer_.focus = label > 0 ? focusOnBlob(outer_, label) : focusAt(outer_, p);
  } else {
    outer_.focus = refocus(outer_);  // nothing changed: no reflex, the gaze stays
  }
  e.after = outer_.focus;
  e.image_change = imageChange(e.before.image, e.after.image);
  e.position_change = (std::abs(e.after.x - e.before.x) + std::abs(e.after.y - e.before.y)) / 2.0;
  e.image_changed = e.image_change > config_.eye.image_change_threshold;
  e.position_changed = e.position_change > config_.eye.position_change_threshold;
  // The effect must be the performed action's own (paper 2.3.1): a displacement
  // for move; for a colour action, the same place with the focus now in that colour.
  if (table)
    e.affordance = tableEffect(e, action, area_before, areaAtGaze(outer_), target);
  else if (action == kMove)
    e.affordance = e.position_changed;
  else if (validAction(action))
    e.affordance = e.image_changed && !e.position_changed && dominantChannel(e.after.image) == kActionChannel[action];
  return e;
}

void Eye::save(SnapshotWriter& w) const {
  const cv::Mat rgb = outer_.rgb.isContinuous() ? outer_.rgb : outer_.rgb.clone();
  w.i64(rgb.rows);
  w.i64(rgb.cols);
  w.bytes(rgb.data, rgb.total() * rgb.elemSize());
  w.i64(static_cast<std::int64_t>(outer_.objects.size()));
  for (const cv::Point2d& o : outer_.objects) {
    w.f64(o.x);
    w.f64(o.y);
  }
  w.i64(outer_.focus.gaze.col);
  w.i64(outer_.focus.gaze.row);
  w.f64(outer_.focus.x);
  w.f64(outer_.focus.y);
  w.blob(outer_.focus.image);
}

void Eye::load(SnapshotReader& r) {
  const int side = config_.world.size_px, height = config_.world.height_px ? config_.world.height_px : side;
  const auto rows = static_cast<int>(r.within("scene rows", 0, height));
  const auto cols = static_cast<int>(r.within("scene columns", rows == 0 ? 0 : side, rows == 0 ? 0 : side));
  cv::Mat rgb(rows, cols, CV_8UC3);
  r.bytes("scene", rgb.data, rgb.total() * rgb.elemSize());
  std::vector<cv::Point2d> objects(static_cast<std::size_t>(r.within("scene objects", 0, 100'000)));
  for (cv::Point2d& o : objects) {
    o.x = r.f64("scene object x");
    o.y = r.f64("scene object y");
  }
  Focus f;
  f.gaze.col = static_cast<int>(r.within("gaze", -side, 2 * side));
  f.gaze.row = static_cast<int>(r.within("gaze", -side, 2 * side));
  f.x = r.f64("gaze x");
  f.y = r.f64("gaze y");
  const std::size_t focus_bytes = 3u * static_cast<std::size_t>(config_.eye.focus_side) * config_.eye.focus_side;
  f.image = r.blob("focus image", focus_bytes);
  if (!f.image.empty() && f.image.size() != focus_bytes) r.refuse("focus image", "not of this run's focus side");
  outer_ = Retina{};
  if (rows > 0) {
    try {
      setScene(std::move(rgb), std::move(objects));
    } catch (const std::invalid_argument& e) {
      r.refuse("scene objects", e.what());
    }
  }
  outer_.focus = std::move(f);
}

}  // namespace afford

#include "environment/table_world.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "afford/actions.hpp"
#include "afford/rng.hpp"

namespace afford {

namespace {
constexpr double kPi = 3.14159265358979323846;
// A scene's set-up draws each object's place up to this many times before it says the objects do not fit.
constexpr int kPlaceDraws = 1000;

// The window the eye puts on a blob: on its centroid (mean of the pixels whose channels' mean is above 0, as
// the eye's blobs are found), the corner as windowCorner places it (eye.hpp: focusOnBlob).
std::vector<std::uint8_t> focusOnObject(const cv::Mat& rgb, int side) {
  double sx = 0, sy = 0;
  long n = 0;
  for (int r = 0; r < rgb.rows; ++r)
    for (int c = 0; c < rgb.cols; ++c) {
      const cv::Vec3b& p = rgb.at<cv::Vec3b>(r, c);
      if (p[0] + p[1] + p[2] > 0) {
        sx += c;
        sy += r;
        ++n;
      }
    }
  if (n == 0) return std::vector<std::uint8_t>(3u * static_cast<std::size_t>(side) * side, 0);
  const int w = rgb.cols;
  const Pixel corner = windowCorner(sx / n / w, sy / n / w, side, w);
  return cropFocus(rgb, {corner.col + side / 2, corner.row + side / 2}, side);
}
}  // namespace

TableWorld::TableWorld(const RunConfig& config)
    : table_(config.table),
      focus_side_(config.eye.focus_side),
      seed_(config.seed),
      steps_(config.steps),
      physics_(config.table.spec) {
  table::validate(table_.primitives);
  table::validate(table_.truth, table_.spec);
  table::GlContext::onThisThread();
  camera_ = std::make_unique<table::TableCamera>(physics_);
  present_.assign(static_cast<std::size_t>(physics_.objectCount()), true);
  if (config.phase != Phase::Extrinsic) {
    setUp(0);
    return;
  }
  if (!config.scenario) throw ConfigError("extrinsic.scenario: missing (an extrinsic run needs a scenario)", "extrinsic.scenario");
  scenario_ = *config.scenario;
  setUpScenario(true);  // the goal image: what the scene looks like with every object at its goal place
  goal_ = render();
  for (const ScenarioObject& o : scenario_->objects) {
    const table::Pose p = physics_.objectPose(o.object_index);
    goal_centres_.push_back(toScene(p.pos[0], p.pos[1], p.pos[2]));
  }
  setUpScenario(false);
}

void TableWorld::setUpScenario(bool goal) {
  std::fill(present_.begin(), present_.end(), false);
  for (const ScenarioObject& o : scenario_->objects) {
    const ObjectState& at = goal ? o.goal : o.initial;
    const cv::Point2d p = toTable(at.x, at.y);
    physics_.placeObject(o.object_index, p.x, p.y, 0);
    present_[static_cast<std::size_t>(o.object_index)] = true;
  }
  // Parked: in a row on the floor's plane beyond the rim, further than the camera sees.
  const auto corner = table_.spec.camera.tableAtPixel(0, 0);  // the view's half-extents on the table
  const double park = std::max({std::abs(corner[0]), std::abs(corner[1]), table_.spec.half_x, table_.spec.half_y}) + 0.5;
  for (int i = 0, parked = 0; i < physics_.objectCount(); ++i)
    if (!present_[static_cast<std::size_t>(i)]) physics_.placeObject(i, park + 0.3 * parked++, 0, 0);
  physics_.forward();
  segments_.release();
}

double TableWorld::fromGoal(const ScenarioObject& o) const {
  const table::Pose p = physics_.objectPose(o.object_index);
  const cv::Point2d g = toTable(o.goal.x, o.goal.y);
  return std::hypot(p.pos[0] - g.x, p.pos[1] - g.y);
}

void TableWorld::setUp(std::int64_t step) {
  const KeyedRng rng(seed_, step, Purpose::TableScene);
  const table::TruthSpec& region = table_.truth;
  std::vector<std::array<double, 3>> placed;  // x, y, footprint radius
  std::uint64_t draw = 0;
  for (int i = 0; i < physics_.objectCount(); ++i) {
    const double radius = table_.spec.objects[static_cast<std::size_t>(i)].footprintRadius();
    const double rx = std::max(0.0, region.region_x - radius), ry = std::max(0.0, region.region_y - radius);
    bool free = false;
    double x = 0, y = 0;
    for (int k = 0; k < kPlaceDraws && !free; ++k, draw += 2) {
      x = rng.uniform(draw, -rx, rx);
      y = rng.uniform(draw + 1, -ry, ry);
      free = std::all_of(placed.begin(), placed.end(), [&](const std::array<double, 3>& p) {
        return std::hypot(p[0] - x, p[1] - y) >= p[2] + radius + table_.scene.gap;
      });
    }
    if (!free)
      throw ConfigError("table.scene.gap: the " + std::to_string(physics_.objectCount()) +
                            " objects do not fit apart in table.truth.region (no free place for '" +
                            table_.spec.objects[static_cast<std::size_t>(i)].name + "' in " +
                            std::to_string(kPlaceDraws) + " draws)",
                        "table.scene.gap");
    placed.push_back({x, y, radius});
    physics_.placeObject(i, x, y, rng.uniform(1'000'000 + static_cast<std::uint64_t>(i), -kPi, kPi));
  }
  segments_.release();
}

cv::Mat TableWorld::render() const { return camera_->rgb(physics_); }

void TableWorld::observe(std::function<void(const table::TablePhysics&)> f, int every) {
  if (!f) return physics_.observe(nullptr, every);
  physics_.observe([this, f = std::move(f)] {
    physics_.forward();
    f(physics_);
  }, every);
}

std::vector<std::string> TableWorld::probeNames() const {
  std::vector<std::string> out;
  for (const table::ObjectSpec& o : table_.spec.objects) out.push_back(o.name);
  return out;
}

std::vector<std::vector<std::uint8_t>> TableWorld::probeImages() const {
  if (probes_.empty()) {
    // Each object alone at the table's centre, in its configured pose, unturned: drawn by a camera of its own.
    for (const table::ObjectSpec& o : table_.spec.objects) {
      table::TableSpec alone = table_.spec;
      alone.objects = {o};
      table::TablePhysics sim(alone);
      sim.placeObject(0, 0, 0, 0);
      table::TableCamera camera(sim);
      probes_.push_back(focusOnObject(camera.rgb(sim), focus_side_));
    }
  }
  return probes_;
}

cv::Point2d TableWorld::toScene(double x, double y, double z) const {
  const cv::Point2d uv = camera_->pixelOf(x, y, z);  // pixel centres at .5
  const double w = camera_->width();
  return {(uv.x - 0.5) / w, (uv.y - 0.5) / w};
}

cv::Point2d TableWorld::toTable(double sx, double sy) const {
  const double w = camera_->width();
  return camera_->tableAt(sx * w + 0.5, sy * w + 0.5);
}

int TableWorld::objectAt(double x, double y) const {
  if (segments_.empty()) segments_ = camera_->objects(physics_);
  const Pixel p = toPixel(x, y, camera_->width());
  if (p.col < 0 || p.row < 0 || p.col >= segments_.cols || p.row >= segments_.rows) return -1;
  return segments_.at<int>(p.row, p.col);
}

std::pair<double, double> TableWorld::drawPlace(std::int64_t step, int object) const {
  // As a truth trial draws its place: at a drawn distance and direction, redrawn up to 8 times to be in the
  // region, then the nearest point of the region.
  const KeyedRng rng(seed_, step, Purpose::TablePlace);
  const table::TruthSpec& t = table_.truth;
  const table::Pose at = physics_.objectPose(object);
  double px = 0, py = 0;
  for (std::uint64_t d = 0; d < 8; ++d) {
    const double angle = rng.uniform(2 * d, -kPi, kPi);
    const double r = rng.uniform(2 * d + 1, t.place_min, t.place_max);
    px = at.pos[0] + r * std::cos(angle), py = at.pos[1] + r * std::sin(angle);
    if (std::abs(px) <= t.region_x && std::abs(py) <= t.region_y) break;
  }
  return {std::clamp(px, -t.region_x, t.region_x), std::clamp(py, -t.region_y, t.region_y)};
}

ActionOutcome TableWorld::execute(std::int64_t step, int action, double x, double y,
                                  std::optional<std::pair<double, double>> target) {
  ActionOutcome out;
  if (!validAction(action)) return out;
  const int object = objectAt(x, y);
  if (object < 0) return out;  // the gaze is on no object: the hand does not move
  out.on_object = true;
  std::optional<std::pair<double, double>> place;
  if (table::tableActionTakesPlace(action)) {
    if (target) {  // the hand takes an object no further than the region objects are set up in
      const cv::Point2d p = toTable(target->first, target->second);
      const table::TruthSpec& t = table_.truth;
      place = std::make_pair(std::clamp(p.x, -t.region_x, t.region_x), std::clamp(p.y, -t.region_y, t.region_y));
    } else {
      place = drawPlace(step, object);
    }
    const cv::Point2d s = toScene(place->first, place->second);
    out.target_x = s.x;
    out.target_y = s.y;
  }
  const std::vector<double> before = physics_.state();
  const int instabilities = physics_.instabilities();
  last_ = table::runPrimitive(physics_, table_.primitives, seed_, step, action, object, place);
  physics_.forward();  // the camera draws where the bodies are after the primitive's last step
  out.succeeded = last_.succeeded;
  if (physics_.instabilities() != instabilities) {
    // MuJoCo found a bad acceleration and set its data back to the model's initial state in the middle of the
    // primitive: what it ended with is no scene. The action failed; the scene is set up anew (by seed and step),
    // or, in a test of a scenario, is as it was before the action.
    physics_.setState(before);
    if (!scenario_) setUp(step);
    out.succeeded = false;
    out.unstable = true;
  }
  segments_.release();
  return out;
}

bool TableWorld::objectsAppearAt(std::int64_t step) const {
  return !scenario_ && step > 0 && step < steps_ && table_.scene.reset_every > 0 && step % table_.scene.reset_every == 0;
}

bool TableWorld::introduceObjectsAt(std::int64_t step) {
  if (!objectsAppearAt(step)) return false;
  setUp(step);
  return true;
}

std::vector<cv::Point2d> TableWorld::centres() const {
  std::vector<cv::Point2d> out;
  for (int i = 0; i < physics_.objectCount(); ++i) {
    if (!present_[static_cast<std::size_t>(i)]) continue;
    const table::Pose p = physics_.objectPose(i);
    out.push_back(toScene(p.pos[0], p.pos[1], p.pos[2]));
  }
  return out;
}

const cv::Mat& TableWorld::goalScene() const {
  if (!scenario_) throw std::logic_error("TableWorld: no scenario, so no goal");
  return goal_;
}
std::vector<cv::Point2d> TableWorld::goalCentres() const { return goal_centres_; }

double TableWorld::goalDistance() const {
  if (!scenario_) return -1.0;
  const table::TruthSpec& t = table_.truth;
  double beyond = 0;
  for (const ScenarioObject& o : scenario_->objects) beyond += std::max(0.0, fromGoal(o) - table_.primitives.success_radius);
  return std::min(1.0, beyond / static_cast<double>(scenario_->objects.size()) / std::hypot(2 * t.region_x, 2 * t.region_y));
}

double TableWorld::goalUtility() const {
  if (!scenario_) return -1.0;
  double sum = 0;
  for (const ScenarioObject& o : scenario_->objects)
    if (fromGoal(o) <= table_.primitives.success_radius) sum += o.value;
  return sum;
}

void TableWorld::save(SnapshotWriter& w) const { w.doubles(physics_.state()); }

void TableWorld::load(SnapshotReader& r) {
  std::vector<double> state;
  r.doubles("table state", state, physics_.state().size());
  for (double v : state)
    if (!std::isfinite(v)) r.refuse("table state", "holds a value that is not finite");
  physics_.setState(state);
  segments_.release();
}

}  // namespace afford

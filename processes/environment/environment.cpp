#include "environment/environment.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "afford/actions.hpp"
#include "afford/rng.hpp"

namespace afford {

namespace {
// Pixel world: the focus window, or the largest shape if that reaches further, plus a pixel.
int clearanceOf(const std::vector<WorldObject>& objects, const WorldConfig& w, int focus_side) {
  int half = focus_side / 2;
  for (const WorldObject& o : objects)
    for (const Pixel& f : shapeFootprint(o.shape, w)) half = std::max({half, std::abs(f.col), std::abs(f.row)});
  return half + 1;
}
}  // namespace

Environment::Environment(const EnvironmentParams& params) : config_(params) {
  const auto& w = config_.world;
  for (std::size_t i = 0; i < w.objects.size(); ++i) {
    const ObjectSpec& spec = w.objects[i];
    WorldObject o;
    o.table_index = static_cast<int>(i);
    o.shape = spec.shape;
    o.colour = spec.colour;
    place(o, spec.x, spec.y);
    o.present = false;
    objects_.push_back(o);
  }
  free_half_ = clearanceOf(objects_, w, config_.focus_side);
  introduceObjectsAt(0);
}

Environment::Environment(const EnvironmentParams& params, const Scenario& scenario) : config_(params), scenario_(scenario) {
  for (const auto& so : scenario.objects) {
    WorldObject o;
    o.shape = so.shape;
    o.colour = so.initial.colour;
    place(o, so.initial.x, so.initial.y);
    o.present = true;
    o.table_index = -1;
    objects_.push_back(o);
  }
  free_half_ = clearanceOf(objects_, config_.world, config_.focus_side);
  goal_ = renderScenario(scenario, true, config_.world);
}

void Environment::place(WorldObject& o, double x, double y) const {
  const int size = config_.world.size_px;
  o.centre = toPixel(x, y, size);
  o.x = continuous() ? x : toUnit(o.centre.col, size);
  o.y = continuous() ? y : toUnit(o.centre.row, size);
  o.pixels = shapePixels(o.shape, o.x, o.y, config_.world);
}

template <class Counts>
bool Environment::placeFree(double x, double y, const Shape* shape, Counts counts) const {
  const int size = config_.world.size_px;
  Pixel lo, hi;  // the window, inclusive
  if (continuous()) {
    lo = windowCorner(x, y, config_.focus_side, size);
    hi = {lo.col + config_.focus_side - 1, lo.row + config_.focus_side - 1};
  } else {
    const Pixel c = toPixel(x, y, size);
    lo = {c.col - free_half_, c.row - free_half_};
    hi = {c.col + free_half_, c.row + free_half_};
  }
  std::vector<std::uint8_t> taken;  // continuous: the counted objects' pixels, to keep the shape off them
  if (continuous() && shape) taken.assign(static_cast<std::size_t>(size) * size, 0);
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    if (!counts(static_cast<int>(i))) continue;
    for (const Pixel& p : objects_[i].pixels) {
      if (p.col >= lo.col && p.col <= hi.col && p.row >= lo.row && p.row <= hi.row) return false;
      if (!taken.empty() && p.col >= 0 && p.row >= 0 && p.col < size && p.row < size)
        taken[static_cast<std::size_t>(p.row) * size + p.col] = 1;
    }
  }
  if (taken.empty()) return true;
  // A rectangle (22.5 px tall) reaches past the 21 x 21 window: it must not
  // touch another object either, or the eye sees the two as one blob.
  for (const Pixel& p : shapePixels(*shape, x, y, config_.world))
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        const int r = p.row + dr, c = p.col + dc;
        if (r >= 0 && c >= 0 && r < size && c < size && taken[static_cast<std::size_t>(r) * size + c]) return false;
      }
  return true;
}

std::vector<cv::Point2d> Environment::centres() const {
  std::vector<cv::Point2d> out;
  for (const WorldObject& o : objects_)
    if (o.present) out.emplace_back(o.x, o.y);
  return out;
}

std::vector<cv::Point2d> Environment::goalCentres() const {
  if (!scenario_) throw std::logic_error("Environment: no scenario, so no goal");
  std::vector<cv::Point2d> out;
  for (const auto& so : scenario_->objects) {
    WorldObject o;
    o.shape = so.shape;
    place(o, so.goal.x, so.goal.y);
    out.emplace_back(o.x, o.y);
  }
  return out;
}

const cv::Mat& Environment::goalScene() const {
  if (!scenario_) throw std::logic_error("Environment: no scenario, so no goal");
  return goal_;
}

bool Environment::placeFree(double x, double y, const Shape* shape) const {
  return placeFree(x, y, shape, [this](int i) { return objects_[i].present; });
}

double Environment::goalUtility() const {
  if (!scenario_) throw std::logic_error("Environment: no scenario, so no goal");
  const int size = config_.world.size_px;
  double sum = 0;
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    const ObjectState& g = scenario_->objects[i].goal;
    const WorldObject& o = objects_[i];
    // In place: on the goal's pixel (pixel world), or within a pixel of the goal's
    // centre in each direction (continuous: a move goes where the eye saw the goal
    // object, the centre of its drawn pixels, which can be a fraction of a pixel off).
    const bool placed = continuous() ? std::max(std::abs(o.x - g.x), std::abs(o.y - g.y)) * size <= 1.0 + 1e-9
                                     : o.centre == toPixel(g.x, g.y, size);
    if (o.colour == g.colour && placed) sum += scenario_->objects[i].value;
  }
  return sum;
}

double Environment::goalDistance() const {
  const cv::Mat scene = render(), &goal = goalScene();
  double sum = 0;
  for (std::size_t i = 0; i < scene.total() * 3; ++i) {
    const double d = (static_cast<int>(scene.data[i]) - static_cast<int>(goal.data[i])) / 255.0;
    sum += d * d;
  }
  return std::sqrt(sum) / static_cast<double>(scene.total() * 3);
}

cv::Mat Environment::render() const {
  cv::Mat scene = blankScene(config_.world.size_px);
  for (const auto& o : objects_)
    if (o.present) paintPixels(scene, o.pixels, o.colour);
  return scene;
}

std::vector<std::vector<std::uint8_t>> Environment::probeImages() const {
  std::vector<std::vector<std::uint8_t>> out;
  const int mid = config_.world.size_px / 2;
  const double u = toUnit(mid, config_.world.size_px);
  for (const auto& spec : config_.world.objects) {
    cv::Mat scene = blankScene(config_.world.size_px);
    paintObject(scene, spec.shape, spec.colour, u, u, config_.world);
    out.push_back(cropFocus(scene, {mid, mid}, config_.focus_side));
  }
  return out;
}

std::vector<std::string> Environment::probeNames() const {
  std::vector<std::string> names;
  for (const auto& spec : config_.world.objects) names.push_back(spec.name);
  return names;
}

int Environment::tableRow(const WorldObject& o) const {
  // Affordances belong to what the object is now (paper 2.1: the state s_{b,o}):
  // a green square turned red is a red square. Objects with no row of their
  // current look keep their own row (-1 for scenario objects: nothing).
  const auto& specs = config_.world.objects;
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (specs[i].shape == o.shape && specs[i].colour == o.colour) return static_cast<int>(i);
  return o.table_index;
}

int Environment::objectAt(Pixel p) const {
  for (std::size_t i = objects_.size(); i-- > 0;) {  // the last drawn is on top
    const auto& o = objects_[i];
    if (!o.present) continue;
    for (const Pixel& q : o.pixels)
      if (q == p) return static_cast<int>(i);
  }
  return -1;
}

ActionOutcome Environment::execute(std::int64_t step, int action, double x, double y,
                                   std::optional<std::pair<double, double>> target) {
  ActionOutcome out;
  const auto& w = config_.world;
  const int idx = objectAt(toPixel(x, y, w.size_px));
  double tx = -1, ty = -1;  // the move target, scene units (a pixel's, in the pixel world)
  bool have_target = false;
  auto aim = [&](double x0, double y0) {
    tx = continuous() ? x0 : toUnit(toPixel(x0, w.size_px), w.size_px);
    ty = continuous() ? y0 : toUnit(toPixel(y0, w.size_px), w.size_px);
    return placeFree(tx, ty, idx >= 0 ? &objects_[idx].shape : nullptr);
  };
  if (action == kMove) {
    // The window at the target must be free in the scene as it is, the moving
    // object included (docs/parameters.md: "redrawn until the focus window
    // there is free"), so a move always lands visibly away from where the object was.
    if (target) {
      have_target = aim(target->first, target->second);
    } else {
      // Intrinsic move (paper 2.3.2): uniform in the table limits, redrawn until free.
      const KeyedRng rng(config_.seed, step, Purpose::MoveTarget);
      for (int k = 0; k < w.max_target_draws && !have_target; ++k)
        have_target = aim(rng.uniform(2 * k, w.table_min, w.table_max), rng.uniform(2 * k + 1, w.table_min, w.table_max));
    }
    if (have_target) {
      out.target_x = tx;
      out.target_y = ty;
    }
  }
  if (idx < 0) return out;
  out.on_object = true;
  WorldObject& o = objects_[idx];
  const int row = tableRow(o);
  const double p = row < 0 ? 0.0 : w.objects[row].affordance[action];
  const KeyedRng success_rng(config_.seed, step, Purpose::ActionSuccess);
  const bool lucky = p >= 1.0 || (p > 0.0 && success_rng.uniform(0) < p);
  if (!lucky) return out;
  if (action == kMove) {
    if (!have_target) return out;  // nowhere free to go: the routine does nothing
    out.succeeded = !(o.x == tx && o.y == ty);
    place(o, tx, ty);
  } else {
    const Colour c = action == kTurnGreen ? Colour::Green : action == kTurnRed ? Colour::Red : Colour::Blue;
    out.succeeded = o.colour != c;
    o.colour = c;
  }
  return out;
}

bool Environment::objectsAppearAt(std::int64_t step) const {
  for (std::size_t i = 0; i < objects_.size(); ++i)
    if (!objects_[i].present && config_.world.objects[i].appears_at == step) return true;
  return false;
}

bool Environment::introduceObjectsAt(std::int64_t step) {
  bool any = false;
  const auto& w = config_.world;
  std::vector<bool> before(objects_.size());  // present before this step's newcomers
  for (std::size_t i = 0; i < objects_.size(); ++i) before[i] = objects_[i].present;
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    WorldObject& o = objects_[i];
    if (o.present || w.objects[i].appears_at != step) continue;
    if (step > 0) {
      // Continuous positions (authors' code): a random place whose window is free
      // of the objects there before this step (with late_overlap), or of every
      // object present. Pixel world: the configured place, or a free one if that is taken.
      const auto counts = [&](int j) {
        return j != static_cast<int>(i) && (before[j] || (objects_[j].present && !(continuous() && w.late_overlap)));
      };
      if (continuous() || !placeFree(o.x, o.y, &o.shape, counts)) {
        const KeyedRng rng(config_.seed, step, Purpose::LatePlacement, i);
        for (int k = 0; k < w.max_target_draws; ++k) {
          const double x = rng.uniform(2 * k, w.table_min, w.table_max), y = rng.uniform(2 * k + 1, w.table_min, w.table_max);
          const double px = continuous() ? x : toUnit(toPixel(x, w.size_px), w.size_px);
          const double py = continuous() ? y : toUnit(toPixel(y, w.size_px), w.size_px);
          if (placeFree(px, py, &o.shape, counts)) {
            place(o, px, py);
            break;
          }
        }
      }
    }
    o.present = true;
    any = true;
  }
  return any;
}

void Environment::save(SnapshotWriter& w) const {
  w.i64(static_cast<std::int64_t>(objects_.size()));
  for (const WorldObject& o : objects_) {
    w.i64(o.table_index);
    w.i64(static_cast<std::int64_t>(o.shape));
    w.i64(static_cast<std::int64_t>(o.colour));
    w.f64(o.x);
    w.f64(o.y);
    w.i64(o.centre.col);
    w.i64(o.centre.row);
    w.i64(o.present ? 1 : 0);
    w.i64(static_cast<std::int64_t>(o.pixels.size()));
    w.bytes(o.pixels.data(), o.pixels.size() * sizeof(Pixel));
  }
}

void Environment::load(SnapshotReader& r) {
  const auto n = r.within("objects", static_cast<std::int64_t>(objects_.size()), static_cast<std::int64_t>(objects_.size()));
  const std::int64_t side = config_.world.size_px;
  for (std::int64_t i = 0; i < n; ++i) {
    WorldObject& o = objects_[static_cast<std::size_t>(i)];
    o.table_index = static_cast<int>(r.within("object table row", 0, 1'000'000));
    o.shape = static_cast<Shape>(r.within("object shape", static_cast<int>(o.shape), static_cast<int>(o.shape)));
    o.colour = static_cast<Colour>(r.within("object colour", 0, static_cast<int>(Colour::Blue)));
    o.x = r.f64("object x");
    o.y = r.f64("object y");
    o.centre.col = static_cast<int>(r.within("object centre", -side, 2 * side));
    o.centre.row = static_cast<int>(r.within("object centre", -side, 2 * side));
    o.present = r.within("object present", 0, 1) == 1;
    o.pixels.resize(static_cast<std::size_t>(r.within("object pixels", 0, side * side)));
    r.bytes("object pixels", o.pixels.data(), o.pixels.size() * sizeof(Pixel));
  }
}

}  // namespace afford

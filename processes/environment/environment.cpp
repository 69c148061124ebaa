#include "environment/environment.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "afford/actions.hpp"
#include "afford/rng.hpp"

namespace afford {

namespace {
// The focus window, or the largest shape if that reaches further, plus a pixel.
int clearanceOf(const std::vector<std::vector<Pixel>>& footprints, int focus_side) {
  int half = focus_side / 2;
  for (const auto& fp : footprints)
    for (const Pixel& f : fp) half = std::max({half, std::abs(f.col), std::abs(f.row)});
  return half + 1;
}
}  // namespace

Environment::Environment(const RunConfig& config) : config_(config) {
  const auto& w = config_.world;
  for (std::size_t i = 0; i < w.objects.size(); ++i) {
    const ObjectSpec& spec = w.objects[i];
    WorldObject o;
    o.table_index = static_cast<int>(i);
    o.shape = spec.shape;
    o.colour = spec.colour;
    o.centre = toPixel(spec.x, spec.y, w.size_px);
    o.present = false;
    objects_.push_back(o);
    footprints_.push_back(shapeFootprint(spec.shape, w));
  }
  free_half_ = clearanceOf(footprints_, config_.eye.focus_side);
  introduceObjectsAt(0);
}

Environment::Environment(const RunConfig& config, const Scenario& scenario) : config_(config), scenario_(scenario) {
  for (const auto& so : scenario.objects) {
    WorldObject o;
    o.shape = so.shape;
    o.colour = so.initial.colour;
    o.centre = toPixel(so.initial.x, so.initial.y, config_.world.size_px);
    o.present = true;
    o.table_index = -1;
    objects_.push_back(o);
    footprints_.push_back(shapeFootprint(so.shape, config_.world));
  }
  free_half_ = clearanceOf(footprints_, config_.eye.focus_side);
  goal_ = renderScenario(scenario, true, config_.world);
}

const cv::Mat& Environment::goalScene() const {
  if (!scenario_) throw std::logic_error("Environment: no scenario, so no goal");
  return goal_;
}

double Environment::goalUtility() const {
  if (!scenario_) throw std::logic_error("Environment: no scenario, so no goal");
  double sum = 0;
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    const ObjectState& g = scenario_->objects[i].goal;
    const WorldObject& o = objects_[i];
    if (o.colour == g.colour && o.centre == toPixel(g.x, g.y, config_.world.size_px)) sum += scenario_->objects[i].value;
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
    if (o.present) paintObject(scene, o.shape, o.colour, o.centre, config_.world);
  return scene;
}

std::vector<std::vector<std::uint8_t>> Environment::probeImages() const {
  std::vector<std::vector<std::uint8_t>> out;
  const int mid = config_.world.size_px / 2;
  for (const auto& spec : config_.world.objects) {
    cv::Mat scene = blankScene(config_.world.size_px);
    paintObject(scene, spec.shape, spec.colour, {mid, mid}, config_.world);
    out.push_back(cropFocus(scene, {mid, mid}, config_.eye.focus_side));
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
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    const auto& o = objects_[i];
    if (!o.present) continue;
    for (const Pixel& f : footprints_[i])
      if (o.centre.col + f.col == p.col && o.centre.row + f.row == p.row) return static_cast<int>(i);
  }
  return -1;
}


bool Environment::regionFree(Pixel centre, int half, int ignore) const {
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    if (static_cast<int>(i) == ignore || !objects_[i].present) continue;
    for (const Pixel& f : footprints_[i]) {
      const int c = objects_[i].centre.col + f.col, r = objects_[i].centre.row + f.row;
      if (std::abs(c - centre.col) <= half && std::abs(r - centre.row) <= half) return false;
    }
  }
  return true;
}

ActionOutcome Environment::execute(std::int64_t step, int action, double x, double y,
                                   std::optional<std::pair<double, double>> target) {
  ActionOutcome out;
  const auto& w = config_.world;
  const int idx = objectAt(toPixel(x, y, w.size_px));
  Pixel target_px{};
  bool have_target = false;
  if (action == kMove) {
    // The window at the target must be free in the scene as it is, the moving
    // object included (PARAMETERS.md: "redrawn until the focus window there is
    // free"), so a move always lands visibly away from where the object was.
    if (target) {
      target_px = toPixel(target->first, target->second, w.size_px);
      have_target = regionFree(target_px, freeHalf(), -1);
    } else {
      // Intrinsic move (paper 2.3.2): uniform in the table limits, redrawn until free.
      const KeyedRng rng(config_.seed, step, Purpose::MoveTarget);
      for (int k = 0; k < w.max_target_draws && !have_target; ++k) {
        const double tx = rng.uniform(2 * k, w.table_min, w.table_max);
        const double ty = rng.uniform(2 * k + 1, w.table_min, w.table_max);
        target_px = toPixel(tx, ty, w.size_px);
        have_target = regionFree(target_px, freeHalf(), -1);
      }
    }
    if (have_target) {
      out.target_x = toUnit(target_px.col, w.size_px);
      out.target_y = toUnit(target_px.row, w.size_px);
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
    out.succeeded = !(o.centre == target_px);
    o.centre = target_px;
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
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    WorldObject& o = objects_[i];
    if (o.present || w.objects[i].appears_at != step) continue;
    // A late object takes its configured place, or a free one if that is taken.
    if (step > 0 && !regionFree(o.centre, freeHalf(), static_cast<int>(i))) {
      const KeyedRng rng(config_.seed, step, Purpose::LatePlacement, i);
      for (int k = 0; k < w.max_target_draws; ++k) {
        const Pixel p = toPixel(rng.uniform(2 * k, w.table_min, w.table_max),
                                rng.uniform(2 * k + 1, w.table_min, w.table_max), w.size_px);
        if (regionFree(p, freeHalf(), static_cast<int>(i))) {
          o.centre = p;
          break;
        }
      }
    }
    o.present = true;
    any = true;
  }
  return any;
}

}  // namespace afford

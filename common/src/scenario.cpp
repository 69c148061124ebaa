// Geometric checks of extrinsic scenarios (config.hpp: validateScenario).
#include <algorithm>
#include <cstdlib>

#include "afford/config.hpp"
#include "afford/image.hpp"

namespace afford {
namespace {

// Smallest centre distance (in pixels, per axis) at which two objects and the
// focus window around either stay apart: the environment's free-window rule.
int clearance(const WorldConfig& w, int focus_side) {
  int half = focus_side / 2;
  for (Shape s : {Shape::Square, Shape::Circle, Shape::Rectangle})
    for (const Pixel& p : shapeFootprint(s, w)) half = std::max({half, std::abs(p.col), std::abs(p.row)});
  return half + 1;
}

bool overlap(Shape a, Pixel pa, Shape b, Pixel pb, const WorldConfig& w, int half) {
  // Any pixel of b inside the square of half-size `half` around a's centre, or the other way round.
  auto inside = [&](Shape s, Pixel ps, Pixel centre) {
    for (const Pixel& f : shapeFootprint(s, w))
      if (std::abs(ps.col + f.col - centre.col) <= half && std::abs(ps.row + f.row - centre.row) <= half) return true;
    return false;
  };
  return inside(b, pb, pa) || inside(a, pa, pb);
}

std::string key(std::size_t i, const char* rest) { return "objects[" + std::to_string(i) + "]." + rest; }

}  // namespace

void validateScenario(const Scenario& s, const WorldConfig& w) {
  const int half = clearance(w, 21);
  const int n = static_cast<int>(s.objects.size());
  auto px = [&](const ObjectState& st) { return toPixel(st.x, st.y, w.size_px); };
  for (int i = 0; i < n; ++i) {
    const ScenarioObject& a = s.objects[i];
    const bool moves = !(px(a.initial) == px(a.goal));
    if (moves && a.initial.colour != a.goal.colour && a.actions < 2)
      throw ConfigError("config key '" + key(i, "goal") +
                        "': differs from the initial state in both colour and position; one action changes one of "
                        "them (say `actions: 2` for a goal that needs two)");
    for (int j = i + 1; j < n; ++j) {
      const ScenarioObject& b = s.objects[j];
      if (overlap(a.shape, px(a.initial), b.shape, px(b.initial), w, half))
        throw ConfigError("config key '" + key(j, "initial.position") + "': overlaps objects[" + std::to_string(i) +
                          "] in the initial scene");
      if (overlap(a.shape, px(a.goal), b.shape, px(b.goal), w, half))
        throw ConfigError("config key '" + key(j, "goal.position") + "': overlaps objects[" + std::to_string(i) +
                          "] in the goal scene");
    }
    if (!moves) continue;
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      if (overlap(a.shape, px(a.goal), s.objects[j].shape, px(s.objects[j].initial), w, half))
        throw ConfigError("config key '" + key(i, "goal.position") + "': no action can get there: objects[" +
                          std::to_string(j) + "] starts there");
    }
  }
}

}  // namespace afford

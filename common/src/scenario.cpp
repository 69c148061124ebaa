// Geometric checks of extrinsic scenarios (config.hpp: validateScenario).
#include <algorithm>
#include <cmath>
#include <cstdio>
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

void validateScenario(const Scenario& s, const RunConfig& run) {
  if (run.world.kind != WorldKind::Table) return validateScenario(s, run.world);
  // The table: each place a point of the region objects are set up in, and the objects' footprints apart.
  const table::TableWorldConfig& t = run.table;
  struct Place {
    double x, y, radius;
  };
  const auto placeOf = [&](std::size_t i, const ObjectState& st, const char* which) {
    const ScenarioObject& o = s.objects[i];
    const double radius = t.spec.objects.at(static_cast<std::size_t>(o.object_index)).footprintRadius();
    const auto [x, y] = t.spec.camera.tableAt(st.x, st.y);
    const double rx = std::max(0.0, t.truth.region_x - radius), ry = std::max(0.0, t.truth.region_y - radius);
    if (std::abs(x) > rx + 1e-9 || std::abs(y) > ry + 1e-9) {
      char where[160];
      std::snprintf(where, sizeof where, "shows the table's point (%.3f, %.3f) m, outside the region '%s' may rest in "
                    "(|x| <= %.3f, |y| <= %.3f: table.truth.region less its footprint)", x, y, o.object.c_str(), rx, ry);
      throw ConfigError("config key '" + key(i, which) + "': " + where, key(i, which));
    }
    return Place{x, y, radius};
  };
  for (const char* which : {"initial.position", "goal.position"}) {
    const bool goal = which[0] == 'g';
    std::vector<Place> placed;
    for (std::size_t i = 0; i < s.objects.size(); ++i) {
      const Place p = placeOf(i, goal ? s.objects[i].goal : s.objects[i].initial, which);
      for (std::size_t j = 0; j < placed.size(); ++j)
        if (std::hypot(p.x - placed[j].x, p.y - placed[j].y) < p.radius + placed[j].radius + t.scene.gap)
          throw ConfigError("config key '" + key(i, which) + "': '" + s.objects[i].object + "' is within table.scene.gap (" +
                                std::to_string(t.scene.gap) + " m) of objects[" + std::to_string(j) + "] ('" +
                                s.objects[j].object + "') in the " + (goal ? "goal" : "initial") + " scene",
                            key(i, which));
      placed.push_back(p);
    }
  }
}

}  // namespace afford

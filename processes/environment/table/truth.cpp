#include "environment/table/truth.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "afford/rng.hpp"

namespace afford::table {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kZ95 = 1.959963984540054;  // the standard normal's 97.5% quantile

double wilson(const TruthCell& c, double sign) {
  if (c.trials == 0) return sign < 0 ? 0.0 : 1.0;
  const double n = c.trials, p = c.rate(), z2 = kZ95 * kZ95;
  const double centre = (p + z2 / (2 * n)) / (1 + z2 / n);
  const double half = kZ95 * std::sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n);
  return std::clamp(centre + sign * half, 0.0, 1.0);
}
}  // namespace

// At no success the interval starts at 0, at all successes it ends at 1, exactly (the formula's rounding left
// them a hair inside, and a rate of 0 then fell outside its own interval).
double TruthCell::low() const { return successes == 0 ? 0.0 : wilson(*this, -1); }
double TruthCell::high() const { return successes == trials ? 1.0 : wilson(*this, +1); }

void validate(const TruthSpec& t, const TableSpec& table) {
  if (!(t.region_x > 0 && t.region_y > 0 && t.region_x <= table.half_x && t.region_y <= table.half_y))
    throw std::invalid_argument("table.truth: region_x and region_y must be above 0 and within the table's half_x, half_y");
  if (!(t.place_min > 0 && t.place_max >= t.place_min))
    throw std::invalid_argument("table.truth: place_min must be above 0, place_max at least place_min");
  if (t.place_min > 2 * std::hypot(t.region_x, t.region_y))
    throw std::invalid_argument("table.truth: place_min is farther than the region allows");
}

TruthTable estimateTruth(const TableSpec& table, const PrimitiveSpec& primitives, const TruthSpec& truth,
                         std::int64_t seed, int trials, const std::vector<int>& only,
                         const std::function<void(int, int)>& progress) {
  validate(table);
  validate(primitives);
  validate(truth, table);
  if (trials < 1) throw std::invalid_argument("the truth needs at least one trial a cell");
  TruthTable out;
  for (const ObjectSpec& o : table.objects) out.objects.push_back(o.name);
  out.cells.resize(table.objects.size());
  std::vector<int> objects = only;
  if (objects.empty())
    for (int i = 0; i < static_cast<int>(table.objects.size()); ++i) objects.push_back(i);
  for (int i : objects) {
    if (i < 0 || i >= static_cast<int>(table.objects.size()))
      throw std::invalid_argument("no object " + std::to_string(i) + " on the table");
    // The object alone on the table, every trial from the same start (the hand parked).
    TableSpec alone = table;
    alone.objects = {table.objects[static_cast<std::size_t>(i)]};
    TablePhysics sim(alone);
    const std::vector<double> start = sim.state();
    for (int a = 0; a < kTableActions; ++a) {
      TruthCell& cell = out.cells[static_cast<std::size_t>(i)][static_cast<std::size_t>(a)];
      const KeyedRng rng(seed, i * kTableActions + a, Purpose::TableTruth);
      for (int k = 0; k < trials; ++k) {
        const std::uint64_t at = 32 * static_cast<std::uint64_t>(k);
        sim.setState(start);
        const double x = rng.uniform(at, -truth.region_x, truth.region_x);
        const double y = rng.uniform(at + 1, -truth.region_y, truth.region_y);
        sim.placeObject(0, x, y, rng.uniform(at + 2, -kPi, kPi));
        std::optional<std::pair<double, double>> place;
        if (tableActionTakesPlace(a)) {
          // A place in the region at a drawn distance: redrawn up to 8 times, then the nearest in the region.
          double px = 0, py = 0;
          for (std::uint64_t d = 0; d < 8; ++d) {
            const double angle = rng.uniform(at + 3 + d, -kPi, kPi);
            const double r = rng.uniform(at + 11 + d, truth.place_min, truth.place_max);
            px = x + r * std::cos(angle), py = y + r * std::sin(angle);
            if (std::abs(px) <= truth.region_x && std::abs(py) <= truth.region_y) break;
          }
          place = std::make_pair(std::clamp(px, -truth.region_x, truth.region_x),
                                 std::clamp(py, -truth.region_y, truth.region_y));
        }
        // The primitive's noise is keyed by the trial (of this object) as a run's is by its step.
        const std::int64_t step = static_cast<std::int64_t>(i) * trials + k;
        cell.successes += runPrimitive(sim, primitives, seed, step, a, 0, place).succeeded ? 1 : 0;
        ++cell.trials;
      }
      if (progress) progress(i, a);
    }
  }
  return out;
}

}  // namespace afford::table

#pragma once
// Generated extrinsic scenarios (issue 12): k sub-goals on n objects of a
// world's looks, m of the sub-goals needing two actions, drawn from a seed and
// always solvable with the world's true affordance table.
#include <cstdint>
#include <string>
#include <vector>

#include "afford/config.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {

struct ScenarioSpec {
  int objects = 0;     // n: objects in the scene
  int sub_goals = 0;   // k <= n: objects whose goal differs from their start (the rest stay as they are)
  int multi_step = 0;  // m <= k: sub-goals that need a colour change and a move
};

// One action of the true plan: `action` on the object at (x, y); a move goes to (target_x, target_y).
struct PlannedAction {
  int object = 0;
  int action = 0;
  double x = 0, y = 0, target_x = -1, target_y = -1;
};

struct GeneratedScenario {
  Scenario scenario;
  std::vector<PlannedAction> plan;  // the true plan, object by object, that reaches the goal
};

// The index-th scenario of `seed` for the world of `config` (its looks, table
// and geometry). Objects take the looks of world.objects; a one-action
// sub-goal is an afforded colour change or move, a two-action one a colour
// change and a move in an order the table affords (and no other object starts
// with the look it asks for, which one move would bring); only entries of 1 count.
// Places are apart and free as validateScenario and the environment require,
// and the true plan, played in the environment, reaches the goal image
// (goal distance below planner.success_distance); a draw that fails any of
// this is drawn again. Keyed by (seed, index, Purpose::ScenarioGeneration).
// Throws std::invalid_argument naming a bad spec value, std::runtime_error if
// the world has no room or no looks for it.
GeneratedScenario generateScenario(const RunConfig& config, const ScenarioSpec& spec, std::int64_t seed,
                                   std::int64_t index);

// The points of a design's `extrinsic.generate`: every k of sub_goals with
// every n of objects (n = k without objects), k slowest.
std::vector<ScenarioSpec> designPoints(const GenerateDesign& design);

// gen-k<k>-m<m>-n<n>-s<seed>-i<index>
std::string generatedName(const ScenarioSpec& spec, std::int64_t seed, std::int64_t index);

}  // namespace afford

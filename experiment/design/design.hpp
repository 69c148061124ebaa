// Extrinsic test designs (an experiment file's `extrinsic:` section): the
// planner conditions compared, their statistics per system and scenario, and
// the paper's comparisons: utility vs goal planner (Figure 12), forward models
// at 4000 actions (Figure 13), affordance-restricted search (Figure 14).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "afford/config.hpp"
#include "experiment/schema/summary.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {

// One combination of the design's `vary` values.
struct Condition {
  std::string label;                                         // "planner.kind=goal planner.max_attempts=1"
  std::vector<std::pair<std::string, std::string>> settings;  // key -> value (YAML text)
  // The value this condition gives `key`, or "" if it does not set it.
  std::string value(const std::string& key) const;
};

// Every combination, the first key varying slowest; one empty condition without `vary`.
std::vector<Condition> conditionsOf(const ExtrinsicDesign& d);

// Linear-interpolated quantile q in [0, 1] of sorted values (0 for none): the
// one used for every median and quartile of the summaries and figures.
double quantile(const std::vector<double>& sorted, double q);

// The least-squares fit y = a x^2 + b x (no intercept: no sub-goal, no step) of
// (x, y) points, as the paper fits completion steps against sub-goals
// (Figure 6); nullopt if the points do not determine it (fewer than two x).
struct QuadraticFit {
  double a = 0, b = 0;
};
std::optional<QuadraticFit> fitCompletion(const std::vector<std::pair<double, double>>& points);

// Welch's two-sided t-test of two samples with unequal variances.
struct WelchResult {
  double t = 0, df = 0, p = 1;
  double mean_a = 0, mean_b = 0;
};
// Throws std::invalid_argument if a sample has fewer than two values. Equal
// constant samples give t = 0, p = 1.
WelchResult welchTest(const std::vector<double>& a, const std::vector<double>& b);

// What one extrinsic test gave.
struct TestRecord {
  std::string system;
  std::size_t agent = 0;  // the intrinsic run (index in the plan)
  std::string scenario;
  int condition = 0;
  bool ok = false;         // the test ran to its end
  bool success = false;    // the scene matched the goal
  double utility = 0;      // summed value of the objects in their goal state
  int attempts = 0;        // actions executed
  int active_sub_goals = 0;  // sub-goals picked that were not already reached
  int actions_checked = 0;
  int completion = 0;        // the step at which the scene matched the goal (solved tests)
  int sub_goals = 0;         // the scenario's sub-goals (its objects)
  int objects = 0;           // the scenario's objects
  int multi_step = 0;        // its sub-goals that need two actions
};

// summary.systems[S].extrinsic->conditions: per condition and
// scenario, success, utility and actions checked per sub-goal (over tests and
// over agents' means); per condition and point (sub-goals, objects, two-action
// sub-goals), success and completion steps over the point's scenarios; then the design's analysis at the top level
// (docs/results-schema.md).
void summariseDesign(Summary& summary, const std::vector<TestRecord>& tests,
                     const std::vector<Condition>& conditions, const ExtrinsicDesign& design,
                     const std::vector<std::string>& systems, const std::vector<std::string>& scenarios);

}  // namespace afford

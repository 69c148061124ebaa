// The goals of GOALS agents (docs/model.md#goals-of-its-own), summarised over
// a system's runs: competence per module over the run, the modules chosen,
// the goals reached; and goals_<system>.csv, one row per run, curve interval
// and module, for pandas.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "experiment/run/driver.hpp"
#include "experiment/schema/summary.hpp"

namespace afford {

// `runs`: (run id, outcome) of the system's finished runs. Writes <out_dir>/goals_<system>.csv.
GoalsSummary summariseGoals(const std::string& system, const std::vector<std::pair<std::string, const RunOutcome*>>& runs,
                            std::int64_t steps, std::int64_t curve_interval, const std::string& out_dir);

}  // namespace afford

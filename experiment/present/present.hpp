// Presenting an experiment on the console: the tables of its summary.json.
#pragma once
#include <nlohmann/json.hpp>

#include <string>

#include "experiment/plan/plan.hpp"

namespace afford {

// `v` with `digits` decimals.
std::string fixed(double v, int digits);

// The mean learned table of each system beside the experiment's table.
void printTables(const nlohmann::json& summary, const Plan& plan, const std::string& out_dir);

}  // namespace afford

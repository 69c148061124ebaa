// Presenting an experiment on the console: the tables of its summary.
#pragma once

#include <string>

#include "experiment/plan/plan.hpp"
#include "experiment/schema/summary.hpp"

namespace afford {

// `v` with `digits` decimals.
std::string fixed(double v, int digits);

// A completion fit a x^2 + b x as a reader writes it: "1.364 x^2 - 0.808 x".
std::string fitText(double a, double b, int digits = 3);

// The tables of the console summary: each system's mean learned table beside the experiment's, a goals
// agent's modules, the extrinsic tests and the design's analysis.
std::string tablesText(const Summary& summary, const Plan& plan, const std::string& out_dir);
// tablesText on stdout.
void printTables(const Summary& summary, const Plan& plan, const std::string& out_dir);

}  // namespace afford

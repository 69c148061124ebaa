// Summarising an experiment: summary.json (docs/results-schema.md) and the
// CSV files beside it, from the finished runs of its plan.
#pragma once
#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

#include "experiment/design/design.hpp"
#include "experiment/execute/execute.hpp"
#include "experiment/plan/plan.hpp"
#include "experiment/schema/summary.hpp"

namespace afford {

// How the runs were hosted, as the summary says it.
struct Hosting {
  std::string transport;                         // udpm | memq
  std::string network;                           // "in-process memq://", a private namespace, "attached to URL", ...
  std::map<std::string, std::string> processes;  // --process: the commands run in place of the shipped processes
};

// The summary of the finished intrinsic runs; also writes the CSV files into out_dir.
Summary summarise(const Plan& plan, const Hosting& hosting, const PhaseRuns& phase, const std::string& out_dir);

// Per system: the paper's Table 2 metric, raw success, completion steps and
// their fit a x^2 + b x (Figure 6), actions checked per sub-goal; and a CSV.
// Only the finished tests count (all of them, unless a signal stopped the phase).
void summariseExtrinsic(Summary& summary, const Plan& plan, const std::vector<PlannedRun>& tests,
                        const PhaseRuns& phase, const std::string& out_dir);

// The finished tests as the design's summary takes them.
std::vector<TestRecord> testRecords(const Plan& plan, const std::vector<PlannedRun>& tests, const PhaseRuns& phase);

}  // namespace afford

// Summarising an experiment: summary.json (docs/results-schema.md) and the
// CSV files beside it, from the finished runs of its plan.
#pragma once
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "afford/design.hpp"
#include "afford/execute.hpp"
#include "afford/plan.hpp"

namespace afford {

// summary.json content of the finished intrinsic runs; also writes the CSV files.
nlohmann::json summarise(const Plan& plan, const ExperimentOptions& o, const PhaseRuns& phase, const std::string& network);

// Per system: the paper's Table 2 metric, raw success, completion steps and
// their fit a x^2 + b x (Figure 6), actions checked per sub-goal; and a CSV.
// Only the finished tests count (all of them, unless a signal stopped the phase).
void summariseExtrinsic(nlohmann::json& summary, const Plan& plan, const std::vector<PlannedRun>& tests,
                        const PhaseRuns& phase, const ExperimentOptions& o);

// The finished tests as the design's summary takes them.
std::vector<TestRecord> testRecords(const Plan& plan, const std::vector<PlannedRun>& tests, const PhaseRuns& phase);

}  // namespace afford

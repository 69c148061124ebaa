// What an experiment keeps of itself in its output folder, so that an
// interrupted one can be resumed: DIR/experiment.json (its request, the
// fingerprint of its plan, its state). The runs' outcomes beside it are
// run/outcome.hpp's.
#pragma once
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "experiment/experiment.hpp"
#include "experiment/plan/plan.hpp"

namespace afford {

std::filesystem::path statePath(const std::filesystem::path& out);

nlohmann::json requestToJson(const ExperimentRequest& o);
ExperimentRequest requestFromJson(const nlohmann::json& j);

nlohmann::json readState(const std::filesystem::path& out);

// Each run's id and the FNV-1a of its configuration: a resumed experiment
// must plan the very same runs.
nlohmann::json fingerprint(const std::vector<PlannedRun>& runs);
void refuseOtherPlan(const nlohmann::json& stored, const nlohmann::json& now, const std::string& what);

std::string shellQuoted(const std::string& s);
std::string resumeCommand(const ExperimentRequest& o);

// One runner per output folder, until it exits (closed on exec: the children do not hold it).
void lockOutDir(const std::filesystem::path& out);
// A fresh experiment never replaces one that did not finish.
void refuseUnfinished(const ExperimentRequest& o);
// The stored experiment's request, with the run options given now (--jobs, --transport, ...).
ExperimentRequest resumedRequest(const ExperimentRequest& given, const nlohmann::json& state);
// The stored experiment of DIR, if it did not finish.
nlohmann::json unfinishedState(const ExperimentRequest& given);

// With --resume, a plan option given again must say what the stored experiment
// says (`stored`: its request; `plan`: what they resolved to).
void refuseChangedPlan(const ExperimentRequest& given, const ExperimentRequest& stored, const Plan& plan);

}  // namespace afford

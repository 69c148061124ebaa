// What an experiment keeps in its output folder as it goes, so that an
// interrupted one can be resumed: DIR/experiment.json (its options, the
// fingerprint of its plan, its state) and DIR/runs/<run-id>.json (each
// finished run's outcome). Files are written whole or not at all.
#pragma once
#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "afford/driver.hpp"
#include "afford/experiment.hpp"
#include "afford/plan.hpp"

namespace afford {

// `text` into `path`, whole or not at all: written beside it, then renamed
// over it (an interruption leaves the previous version or the new one).
void writeWhole(const std::filesystem::path& path, const std::string& text);

std::filesystem::path statePath(const std::filesystem::path& out);

nlohmann::json optionsToJson(const ExperimentOptions& o);
ExperimentOptions optionsFromJson(const nlohmann::json& j);
nlohmann::json outcomeToJson(const RunOutcome& r);
RunOutcome outcomeFromJson(const nlohmann::json& j);

// A finished run's outcome, kept as it finishes: --resume does not run it again.
void keepOutcome(const std::filesystem::path& out, const std::string& run_id, const RunOutcome& r);
std::optional<RunOutcome> keptOutcome(const std::filesystem::path& out, const std::string& run_id);

nlohmann::json readState(const std::filesystem::path& out);

// Each run's id and the FNV-1a of its configuration: a resumed experiment
// must plan the very same runs.
nlohmann::json fingerprint(const std::vector<PlannedRun>& runs);
void refuseOtherPlan(const nlohmann::json& stored, const nlohmann::json& now, const std::string& what);

std::string shellQuoted(const std::string& s);
std::string resumeCommand(const ExperimentOptions& o);

// One runner per output folder, until it exits (closed on exec: the children do not hold it).
void lockOutDir(const std::filesystem::path& out);
// A fresh experiment never replaces one that did not finish.
void refuseUnfinished(const ExperimentOptions& o);
// The stored experiment's options, with the run options given now (--jobs, --transport, ...).
ExperimentOptions resumedOptions(const ExperimentOptions& given, const nlohmann::json& state);
// The stored experiment of DIR, if it did not finish.
nlohmann::json unfinishedState(const ExperimentOptions& given);

}  // namespace afford

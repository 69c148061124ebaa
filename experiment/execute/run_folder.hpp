// A run's folder in the log root (<log-root>/<run-id>/): claimed by one
// experiment before any process writes in it, and checked once the run is over
// for what the run had to leave there.
//
// The claim makes the folder (one that exists is never taken over) with
// run.json in it: the run's id, its experiment and the --out it writes (afford
// clean reads it). Two experiments given the same run ids never share a
// folder: whichever claims second is refused, naming the first.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "experiment/plan/plan.hpp"
#include "experiment/run/driver.hpp"

namespace afford {

// Whose the folder is, as its run.json (or its log's manifest) says: "run R of experiment E, writing to OUT",
// or that nothing in it says.
std::string runFolderHolder(const std::filesystem::path& run_dir);

// A fresh experiment's runs may not have a folder yet: ConfigError naming the first that has one and whose it is.
void refuseHeldRunFolders(const std::vector<const PlannedRun*>& runs, const std::string& log_root);

// Claims the folders of these runs for the experiment writing to out_dir, in the order of their ids: all of
// them, or none (those made here are removed again) and ConfigError naming the folder and whose it is, or why it
// cannot be made.
void claimRunFolders(std::vector<const PlannedRun*> runs, const std::string& log_root, const std::string& out_dir);

// An experiment folder moved from `was` (absolute, as its run folders' run.json name it) to out_dir, with its
// log root inside it: the run folders there that name `was` are this experiment's where it is now (their
// run.json says so from here on). A folder naming another experiment is left as it is.
void reclaimMovedRunFolders(const std::string& log_root, const std::string& was, const std::string& out_dir);

// As a run starts: its folder is this experiment's already (claimed), or is claimed now. "" or why the run cannot
// have it.
std::string takeRunFolder(const std::filesystem::path& run_dir, const PlannedRun& run, const std::string& out_dir);

// Whose the folder is if its run.json names another experiment than the one writing to out_dir; "" if it names
// that one, or there is none (a cut run's folder of an afford from before the claims).
std::string anotherHolder(const std::filesystem::path& run_dir, const std::string& out_dir);

// Is the folder this experiment's, holding nothing but its run.json (claimed, and nothing written in it)?
bool onlyClaimed(const std::filesystem::path& run_dir, const std::string& out_dir);
// ... then it goes (a run that wrote nothing there, or did not need it: an agent taken from the store).
void releaseUnused(const std::filesystem::path& run_dir, const std::string& out_dir);

// What a run that succeeded should have left and did not: its checkpoint (a learning run's configuration names
// one), and, when its log is kept in its folder, the log and its manifest. "" if nothing is missing, else what is
// missing and why, as far as this process can tell (`their_log`: where the processes' own output is, if known).
std::string missingOutputs(const PlannedRun& run, const RunOutcome& r, const std::string& their_log);

}  // namespace afford

// What an experiment keeps of itself in its output folder, so that an
// interrupted one can be resumed: DIR/experiment.json (its request, the
// fingerprint of its plan, its state). The runs' outcomes beside it are
// run/outcome.hpp's.
#pragma once
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "experiment/stored/request.hpp"
#include "experiment/stored/state_file.hpp"
#include "experiment/execute/execute.hpp"
#include "experiment/plan/plan.hpp"
#include "experiment/schema/summary.hpp"

namespace afford {

std::string shellQuoted(const std::string& s);
// The command that reaches the processes of the experiment `o` runs, as it runs now: $AFFORD_RESUME_WITH if set
// (scripts/procs.sh run says how it reaches its group), else `afford experiment` with the bus options given
// (--attach URL, the key file's path, never the key; in the named network namespace it runs in, if any).
std::string reachCommand(const ExperimentRequest& o);
// The command that resumes it: o.resume_with (else the runner's) with --resume --out DIR.
std::string resumeCommand(const ExperimentRequest& o);

// One runner per output folder, for as long as the lock lives (closed on exec: the children do not hold it;
// a host that goes on after the experiment, the Python package, lets it go).
class OutDirLock {
 public:
  OutDirLock() = default;
  explicit OutDirLock(const std::filesystem::path& out);  // throws ConfigError if another runner holds it
  ~OutDirLock();
  OutDirLock(OutDirLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  OutDirLock& operator=(OutDirLock&& other) noexcept;
  OutDirLock(const OutDirLock&) = delete;
  OutDirLock& operator=(const OutDirLock&) = delete;

 private:
  int fd_ = -1;
};
// A fresh experiment writes into a folder of its own: one that does not exist
// or is empty, or (with --replace) one holding a finished experiment and
// nothing but what afford writes. It never replaces one that did not finish,
// never mixes with another's files. Throws ConfigError naming the folder,
// what it holds and the ways on; nothing is written here.
void refuseUsedOutDir(const ExperimentRequest& o);
// With --replace: what the finished experiment of the folder wrote is removed
// (its log root, if inside, stays). After refuseUsedOutDir, under the lock.
void clearReplaced(const ExperimentRequest& o);
// The stored experiment's request, with the run options given now (--jobs, --transport, ...).
// A resumed experiment whose folder was moved (or is resumed from another folder): its log root and config dir
// as they are found now (inside the folder: where it is now; relative to the folder it was started in: there;
// a config dir that is gone: the --config-dir given, else this build's), recorded in state.moved; state.cwd
// and state.out are those of now. ConfigError if a path cannot be found.
struct FollowedFolder {
  std::vector<std::string> notes;  // what to tell the user
  std::string was;                 // where the folder was, absolute, if it moved since; else ""
  bool log_root_inside = false;    // its log root moved with it
};
FollowedFolder followMovedFolder(ExperimentState& state, const ExperimentRequest& given);
ExperimentRequest resumedRequest(const ExperimentRequest& given, const ExperimentState& state);
// The stored experiment of DIR, if it did not finish; NothingToResume if it did (a resume again, of a
// script or a requeued job, is no error: there is nothing left to do).
struct NothingToResume : ConfigError {
  using ConfigError::ConfigError;
};
ExperimentState unfinishedState(const ExperimentRequest& given);

// With --resume, a plan option given again must say what the stored experiment
// says (`stored`: its request; `plan`: what they resolved to).
void refuseChangedPlan(const ExperimentRequest& given, const ExperimentRequest& stored, const Plan& plan);

}  // namespace afford

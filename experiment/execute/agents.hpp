// Trained agents found by content (issue 13). An intrinsic run is decided by
// its effective configuration (seed included) and the code: the same ones
// give the same weights. A finished run's outcome and checkpoints are kept
// under <log-root>/agents/<key>/; a later intrinsic run with the same key,
// in this experiment or another, takes them instead of running again (its
// summary entry says which run it reuses). Experiments that share their
// intrinsic runs (stochastic, utility, forward-models, search-reduction; base,
// attention, multi-step) train each agent once.
#pragma once
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "experiment/execute/execute.hpp"
#include "experiment/plan/plan.hpp"
#include "experiment/run/driver.hpp"

namespace afford {

// A run's checkpoint files: `checkpoint` (predictors.ckpt) and those written
// after an action count beside it (predictors.after-N-actions.ckpt), as they exist.
std::vector<std::filesystem::path> checkpointFiles(const std::string& checkpoint);

// FNV-1a (hex) of the afford version, the code's fingerprint and the run's configuration without what
// does not change its intrinsic phase: the experiment's name, the planner's
// section (only the extrinsic phase reads it), where the checkpoint goes,
// whether the run is recorded, and after how many actions an extra checkpoint
// is written (a stored agent that lacks one is not taken).
std::string agentKey(const std::string& config_yaml);

class AgentStore {
 public:
  explicit AgentStore(std::string root);  // <log-root>/agents
  // The stored run of `key`, its checkpoint paths pointing into the store;
  // nullopt if there is none, or it lacks the checkpoint after `after_actions` (> 0).
  // max_bytes: what its outcome may take (mostOutcomeBytes of the run that would reuse it).
  std::optional<RunOutcome> find(const std::string& key, std::int64_t after_actions, std::uintmax_t max_bytes) const;
  // Keeps a finished intrinsic run (ok, with its checkpoint): the outcome, and
  // the checkpoint files hard-linked (copied where a link cannot be made).
  // `run_id` is named by the runs that reuse it. Written aside, then renamed:
  // an entry is whole or absent.
  void keep(const std::string& key, const std::string& run_id, const std::string& experiment, const RunOutcome& r) const;
  const std::string& root() const { return root_; }

 private:
  std::string root_;
};

// Intrinsic runs not finished (nor run by another shard) whose agent is
// stored take the stored outcome and checkpoints (kept in out_dir/runs/ as
// finished) instead of running. `watched`: a page follows the runs (--watch), and is told it will not see them.
void takeStoredAgents(const std::vector<PlannedRun>& runs, int after_actions, PhaseRuns& phase,
                      const AgentStore& agents, const std::string& out_dir, spdlog::logger& log, bool watched);

// An intrinsic run that finished here (not one taken from the store) is stored for reuse (p.index in phase).
void storeAgent(const PlannedRun& p, const PhaseRuns& phase, const AgentStore& agents, spdlog::logger& log);

// The agents under way in a queue of experiments run side by side: the first
// run to claim a key trains it; a run of another experiment with the same key
// waits for it (then takes it from the store) instead of training it again.
// A claim that would not write the after-N-actions checkpoint a run needs is
// not waited for.
class AgentClaims {
 public:
  struct Claim {
    std::string run_id;
    std::int64_t after_actions = 0;
    bool settled = false;  // its run ended: stored, failed or not run
  };
  // The claim of `key` this run must wait for, or nullptr: the key is now this run's (`mine` is set).
  std::shared_ptr<Claim> claim(const std::string& key, std::int64_t after_actions, const std::string& run_id,
                               std::shared_ptr<Claim>& mine);
  // The claim's run ended (its agent stored, or not): those waiting for it go on.
  void settle(const std::shared_ptr<Claim>& c);
  void wait(const std::shared_ptr<Claim>& c);

 private:
  std::mutex mutex_;
  std::condition_variable settled_;
  std::multimap<std::string, std::shared_ptr<Claim>> claims_;
};

}  // namespace afford

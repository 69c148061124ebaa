// The pipeline of an experiment, shared by the files that make it (not a
// public header): an experiment checked and planned (Experiment), how a
// phase's runs get their outcomes (an Executor: hosted on the job slots, or
// merged from shards' folders), what a queue's experiments share, the stop
// signals, and the summaries.
//   experiment.cpp  prepare, open the folder, each phase, summarise, present
//   hosted.cpp      the runs and tests run here, on the job slots
//   merge.cpp       afford merge: the outcomes gathered from the shards
//   queue.cpp       several experiments side by side in one queue
//   interrupt.cpp   SIGINT and SIGTERM: the runs stop, what finished is kept
//   summaries.cpp   the summaries of the parts, of a sweep, of the tests
#pragma once
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "experiment/execute/agents.hpp"
#include "experiment/execute/execute.hpp"
#include "experiment/experiment.hpp"
#include "experiment/plan/plan.hpp"
#include "experiment/plan/sweep.hpp"
#include "experiment/results/summary.hpp"
#include "experiment/schema/summary.hpp"
#include "experiment/state.hpp"

namespace afford {

// What an experiment is once checked and planned.
struct Experiment {
  ExperimentRequest o;           // as it runs: a resumed one's stored request, with the run options given now
  ExperimentState state;         // DIR/experiment.json
  Sweep sweep;
  std::vector<Part> parts;       // one, or one per sweep condition
  std::vector<PlannedRun> runs;  // every part's intrinsic runs, in one list
  Hosting hosting;
  std::string bin;               // the processes' executables (udpm)
  OutDirLock lock;               // its folder's, from openFolder until it is over
  FollowedFolder followed;       // a resumed folder that moved: what to say, where it was
  std::vector<PathMove> moves() const { return state.moved.value_or(std::vector<PathMove>{}); }
  // The release whose configurations its stored fingerprints are of (0.1.0 did not say).
  std::string plannedBy() const { return state.planned_by.value_or("0.1.0"); }
  bool merging() const { return !o.merged_from.empty(); }
  const Plan& plan() const { return parts.front().plan; }  // what every part shares
  std::filesystem::path out() const { return o.write.out_dir; }
  void saveState() { writeState(out(), state); }
};

// How a phase's runs get their outcomes.
class Executor {
 public:
  virtual ~Executor() = default;
  // Before the phase's kept outcomes are read: a merge keeps the shards' outcomes as its own.
  virtual void gather(const std::vector<PlannedRun>& runs, bool extrinsic) = 0;
  // The runs not finished yet: run them (or, for a merge, nothing is left).
  virtual void execute(const std::vector<PlannedRun>& runs, bool extrinsic, PhaseRuns& phase) = 0;
};

// The experiments of a queue claim their agents in the queue's order (see
// AgentClaims): entry k claims once every entry before it has claimed, or
// will claim nothing.
class Turns {
 public:
  void wait(std::size_t k) {
    std::unique_lock<std::mutex> lock(mutex_);
    moved_.wait(lock, [&] { return turn_ >= k; });
  }
  void pass(std::size_t k) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      passed_.insert(k);
      while (passed_.count(turn_)) ++turn_;
    }
    moved_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable moved_;
  std::set<std::size_t> passed_;
  std::size_t turn_ = 0;  // every entry before it has passed
};

// What an experiment shares with the others of its queue (none when it runs alone).
struct Shared {
  SlotPool* pool = nullptr;
  AgentClaims* claims = nullptr;
  Turns* turns = nullptr;
  std::size_t position = 0;  // in the queue
  std::string network;       // where the queue's slots run
};

// The executors of a phase's runs: run here on the job slots (hosted.cpp), or taken from the shards (merge.cpp).
std::unique_ptr<Executor> hostedExecutor(const Experiment& x, spdlog::logger& log, SlotPool& pool, const Shared& share);
std::unique_ptr<Executor> mergedExecutor(const Experiment& x, spdlog::logger& log);

// The request as it will run (a resumed one: as stored), checked and planned. Nothing is written or started.
Experiment prepare(const ExperimentRequest& request);
// A prepared experiment, run: alone (its own slots), or in a queue (`share`). Returns its exit code.
int runPrepared(Experiment& x, std::chrono::steady_clock::time_point began, spdlog::logger& log, const Shared& share);

// ---- stop signals (interrupt.cpp) ---------------------------------------------------------
// The first SIGINT or SIGTERM received (0: none).
int stopSignal();
// SIGINT and SIGTERM set stopRequested() (the drivers stop their runs) and are
// remembered for the exit status. `resume`: the command that goes on ("": none
// known yet); installed again, only what a second signal says changes.
void installInterruptHandlers(const std::string& resume);
// Why the experiment stops after a phase instead of going on: a stop signal (or the program's stop), the halt of
// its slots (a run that could not begin: SlotPool::halt), or runs of the phase neither finished nor another
// shard's; "" if it goes on.
std::string stoppedShort(const PhaseRuns& phase, const SlotPool* pool);
// Then, once the runs under way have stopped: the summary of what finished, where the others stopped, and the
// command that goes on. `phase_name` is "intrinsic" or "extrinsic"; `why`: stoppedShort's.
Interruption interruption(const std::string& phase_name, const std::vector<PlannedRun>& runs, const PhaseRuns& phase,
                          bool extrinsic_to_come, const ExperimentRequest& o, const std::string& why);
// Once `in` is in summary.json: the experiment's state says so (resumable), and the log what is kept and what
// comes. Returns the exit status: 128 + the signal, or 1 if the program stopped it.
int stopHere(const Interruption& in, const ExperimentRequest& o, ExperimentState& state, spdlog::logger& log);

// ---- summaries (summaries.cpp) -------------------------------------------------------------
// --keep-checkpoints first|none: the checkpoints of the intrinsic runs not kept go, once every test is done.
void removeCheckpoints(const Plan& plan, const PhaseRuns& phase, Summary& summary, spdlog::logger& log);
// The design's summary of a part's tests.
void summariseTests(Summary& summary, const Part& part, const std::vector<PlannedRun>& tests, const PhaseRuns& phase,
                    const std::vector<std::string>& untested);
// A sweep's summary.json: each condition's, and its CSV files in one.
SweepSummary sweepSummary(const std::vector<Part>& parts, std::vector<Summary>& summaries, const Sweep& sweep,
                          const std::string& out_dir);

// ---- afford merge (merge.cpp) --------------------------------------------------------------
// Every run's outcome, then every test's, from the shard that ran it; one that no shard finished is an
// error naming it (before anything is written).
PhaseRuns gatherShards(const std::vector<Part>& parts, const std::vector<PlannedRun>& runs,
                       const std::vector<std::string>& shards, PhaseRuns* tests_out);

}  // namespace afford

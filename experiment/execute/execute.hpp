// Hosting an experiment's runs: J at a time, each job slot on its own LCM URL
// with its own group of processes (udpm), or every process in this one
// (memq, experiment/run/host.hpp). Each finished run's outcome is kept as it comes.
#pragma once
#include <spdlog/spdlog.h>

#include <atomic>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiment/execute/progress.hpp"
#include "experiment/execute/request.hpp"
#include "experiment/plan/plan.hpp"
#include "experiment/run/driver.hpp"

namespace afford {

// The runs of one phase (intrinsic runs, or extrinsic tests), in plan order.
struct PhaseRuns {
  std::vector<RunOutcome> outcomes;
  std::vector<char> finished;              // its outcome is final (it succeeded or failed) and kept in DIR/runs/
  std::map<std::size_t, std::string> cut;  // run index -> where a signal stopped it
  std::vector<char> elsewhere;             // --shard: runs another shard runs (empty: none)
  std::size_t finishedCount() const { return static_cast<std::size_t>(std::count(finished.begin(), finished.end(), 1)); }
};


// A folder the experiment's paths named when it was started, and where it is now: the experiment folder was
// moved with its log root or config dir inside it, and resumed where it is now (a path stored as `from`, in a
// configuration or an outcome, is read as `to`).
struct PathMove {
  std::string from, to;
  template <class V>
  void visit(V& v) {
    v("from", from);
    v("to", to);
  }
};
// `path` as the moves say it is now (each in turn).
std::string movedPath(std::string path, const std::vector<PathMove>& moves);

// The outcomes kept by an earlier invocation (--resume); none on a fresh start.
// `moves`: folders moved since (their paths in the outcomes are read as they are now).
PhaseRuns keptRuns(const std::vector<PlannedRun>& runs, const std::filesystem::path& out,
                   const std::vector<PathMove>& moves);

// The `n` runs of `all` from `offset` on, as a phase of their own.
PhaseRuns slicePhase(const PhaseRuns& all, std::size_t offset, std::size_t n);

// A cut run's folder, moved aside when the experiment was resumed (kept in DIR/experiment.json).
struct MovedAside {
  std::string run_id, to;
  template <class V>
  void visit(V& v) {
    v("run_id", run_id);
    v("to", to);
  }
};
// A run that did not finish may have left its folder (an incomplete log): it
// is never reused nor deleted, but moved aside as <run-id>.cut-<k>, and the
// run starts afresh. A folder claimed and never begun stays the run's; one that
// is not this experiment's (out_dir) is refused (ConfigError), never moved.
// Returns what was moved where.
std::vector<MovedAside> moveUnfinishedAside(const std::vector<PlannedRun>& runs, const PhaseRuns& phase,
                                            const std::string& log_root, const std::string& out_dir,
                                            spdlog::logger& log);

struct Slot;

// The job slots: J worker threads, slot k on the LCM URL of port base_port + k
// (udpm) or its own in-process bus (memq). A slot keeps its process group (or
// its memq nodes) from run to run while they serve the same experiment folder,
// log root and transport. One pool serves every phase of an experiment, or
// every experiment of a queue run side by side (afford experiment A B ...,
// --plan FILE): their runs share the slots, first come first served.
class SlotPool {
 public:
  // `o`: jobs, base_port, attach and progress are read; `queue`: the board
  // shows every phase of every experiment in one count, under `label`.
  SlotPool(const HostRequest& o, bool queue, std::string label = "");
  ~SlotPool();  // the slots' processes stop
  SlotPool(const SlotPool&) = delete;
  SlotPool& operator=(const SlotPool&) = delete;

  using Work = std::function<void(Slot&)>;
  struct Batch;
  // Queues the works, to run each on a free slot, in order (after a SIGINT or
  // SIGTERM, or a halt, the works not begun are dropped) ...
  std::shared_ptr<Batch> submit(std::vector<Work> works);
  // ... and returns once each has run or was dropped.
  void wait(const std::shared_ptr<Batch>& batch);
  // No work starts from now on (those not begun are dropped, as after a stop signal): a run could not begin, and
  // the others would not either. The first `why` is kept.
  void halt(const std::string& why);
  std::string halted() const;  // why, or "" if the pool was not halted
  Progress& progress();
  bool queue() const;
  int slots() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Called on the slot's thread when run i finished (kept in DIR/runs/), before the next is taken.
using OnFinished = std::function<void(std::size_t i)>;

// Where a phase's runs go and what they are run with.
struct RunContext {
  HostRequest o;
  std::string log_root, out_dir;  // each run's folder is log_root/<run-id>; the outcomes go to out_dir/runs/
  ProtocolConfig protocol;
  std::string bin;                // the processes' executables (udpm)
  spdlog::logger* log = nullptr;
};

// Run every planned run not finished yet (nor run elsewhere) on the pool's
// slots, and keep each outcome in DIR/runs/ as it comes. After a SIGINT or
// SIGTERM no run starts; a run it stopped is cut, not finished. A run that
// could not begin (runOne) is neither: it stays to be run, and the pool halts.
void executeRuns(const std::vector<PlannedRun>& runs, PhaseRuns& phase, const RunContext& c, SlotPool& pool,
                 const OnFinished& on_finished = {});

// The runs finished of all those a phase will run, for its [k/N] lines: one
// count for every batch of runs started ahead of the phase.
struct Tally {
  std::atomic<std::size_t> done{0};
  std::size_t total = 0;
};

// Runs started ahead of their phase (an agent's tests as soon as it is
// trained): they run on the pool while the caller goes on; their outcomes are
// kept in DIR/runs/ like any run's, where their phase finds them. Each that
// finishes is counted in `tally`, shared with the other batches of the phase.
class RunsAhead {
 public:
  RunsAhead(std::vector<PlannedRun> runs, const RunContext& c, SlotPool& pool, std::shared_ptr<Tally> tally);
  ~RunsAhead();  // waits for them
  RunsAhead(const RunsAhead&) = delete;
  RunsAhead& operator=(const RunsAhead&) = delete;
  // Returns once every one has run (or was dropped after a stop signal); how many finished.
  std::size_t wait();
  // After wait(): the runs a stop signal cut, and where (run id -> where).
  std::map<std::string, std::string> cut() const;

 private:
  struct State;
  std::shared_ptr<State> state_;
  SlotPool& pool_;
  std::shared_ptr<SlotPool::Batch> batch_;
};

}  // namespace afford

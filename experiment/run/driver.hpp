// The runner's side of one run's choreography: it waits until the processes
// of the run are free, publishes RUN_CONFIG, publishes START as soon as every
// one has said READY, collects the affordance tables and the result, waits
// until the logger's log holds all that was published, then publishes STOP
// and waits for the logger to close the log. Every boundary is
// an event (a STATUS saying so); timers only recover lost datagrams: the
// configuration is said again (backing off) while someone has not taken it,
// and a process that says it is free, ready or still in the run when it
// should not be is told again at once. A process of the run that reports
// free again mid-run (killed and started anew) is given the run's RUN_CONFIG
// and START again: it catches up by asking for the run's messages
// (docs/operating.md, "Killing and restarting a process"). Stalls and
// silent processes fail the run, naming them and what each could not take.
// The waits of the stages are in experiment/run/waits.cpp.
// Each run() is a request of its own (run_config_t.request, drawn afresh):
// the runner takes only what concerns that request, whatever run id and
// configuration it shares with earlier ones, and a process that holds
// another request of the run id (a recording played back, an earlier
// runner's) is told to leave it. While it drives, the runner beats on STATUS
// as "runner", and refuses to drive a bus another runner drives
// (experiment/run/runners.hpp).
// Channels in:  STATUS, AFFORDANCE_TABLE, RESULT, EXTRINSIC_RESULT (in serial order, through the edge)
// Channels out: RUN_CONFIG, RUN_CONTROL, RESEND, STATUS (its beat)
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "afford/config.hpp"
#include "afford/edge.hpp"
#include "afford/process_main.hpp"
#include "experiment/run/runners.hpp"
#include "experiment/run/silence.hpp"

namespace afford {

struct RunSpec {
  std::string run_id;
  std::string experiment;
  std::string system;
  std::int64_t seed = 0;
  std::int64_t steps = 0;
  std::string config_yaml;
  std::vector<std::string> processes;  // names expected to take part
  Phase phase = Phase::Intrinsic;      // which processes take part (afford/processes.hpp)
  bool extrinsic = false;              // ends with EXTRINSIC_RESULT instead of RESULT
  double stall_seconds = 30;           // no progress for this long fails the run
  // Where the run's log and checkpoint go (<log_root>/<run_id>/): a folder or
  // file a message names elsewhere is not taken (a forged STATUS or RESULT).
  std::string log_root = "logs";
};

// The outcome of a run and its parts, each declaring its keys once (visit(): the kept outcome's JSON,
// experiment/run/outcome.hpp, and its reading come from it).
struct TableSnapshot {
  std::int64_t step = 0;
  std::vector<std::vector<double>> affordance;  // objects x actions
  template <class V>
  void visit(V& v) {
    v("step", step);
    v("affordance", affordance);
  }
};

struct SubGoalOutcome {
  double x = 0, y = 0;
  int iterations = 0, actions_checked = 0, actions_taken = 0;
  bool reached = false;
  template <class V>
  void visit(V& v) {
    v("x", x);
    v("y", y);
    v("iterations", iterations);
    v("actions_checked", actions_checked);
    v("actions_taken", actions_taken);
    v("reached", reached);
  }
};

struct ExtrinsicOutcome {
  std::string scenario;
  bool success = false;
  int completion = 0;  // iteration (from 1) at which the scene matched the goal
  int attempts = 0;
  double utility = 0;  // summed value of the objects in their goal state at the end
  std::vector<SubGoalOutcome> sub_goals;
  template <class V>
  void visit(V& v) {
    v("scenario", scenario);
    v("success", success);
    v("completion", completion);
    v("attempts", attempts);
    v("utility", utility);
    v("sub_goals", sub_goals);
  }
};

// The goals phase: what became of the goals that ended in one curve interval
// of steps ([step, step + run.curve_interval)), per module (goal_t's order:
// explore, colour, move, colour_place).
struct GoalBin {
  std::int64_t step = 0;
  // Goals ended, those reached, actions spent on them; those found reached when set (no action: they measure no
  // competence).
  std::vector<std::int64_t> set, reached, actions, found;
  template <class V>
  void visit(V& v) {
    v("step", step);
    v("set", set);
    v("reached", reached);
    v("actions", actions);
    v("found", found);
  }
};

struct RunOutcome {
  bool ok = false;
  bool interrupted = false;                   // SIGINT/SIGTERM cut it (error says at which step)
  bool unreached = false;                     // its processes never said they were free: it never began (not kept)
  std::string error;
  std::string weights_checksum;
  std::string checkpoint;                     // the predictors' saved weights, if any
  std::string reused_from;                    // a stored agent's run (experiment/execute/agents.hpp), not run again
  std::vector<TableSnapshot> curve;           // every curve_interval steps, and the end
  std::vector<std::int64_t> executed, successes;
  int looks = 0;                              // the predictors' memory at the end (issue 11), 0 without one
  std::int64_t replayed = 0, replayed_effects = 0, revisits = 0;
  std::string log_dir;                        // from the logger, if one took part
  double wall_seconds = 0;                    // whole run, set-up included
  double run_seconds = 0;                     // from START to RESULT: the steps themselves
  std::map<std::string, long> peak_rss_kb;    // per process (VmHWM), filled by the runner
  std::uintmax_t log_bytes = 0;               // size of the run's log, if any
  ExtrinsicOutcome extrinsic;                 // extrinsic runs
  std::vector<GoalBin> goals;                 // goals-phase runs: per curve interval, in step order
  // Kept (DIR/runs/<run-id>.json) but for `interrupted` and `unreached`: such a run is not kept.
  template <class V>
  void visit(V& v) {
    v("ok", ok);
    v("error", error);
    v("weights_checksum", weights_checksum);
    v("checkpoint", checkpoint);
    v.since("reused_from", reused_from);  // (outcomes kept before issue 13 have none)
    v("curve", curve);
    v("executed", executed);
    v("successes", successes);
    v.since("looks", looks);  // (nor these before issue 11)
    v.since("replayed", replayed);
    v.since("replayed_effects", replayed_effects);
    v.since("revisits", revisits);
    v("log_dir", log_dir);
    v("wall_seconds", wall_seconds);
    v("run_seconds", run_seconds);
    v("peak_rss_kb", peak_rss_kb);
    v("log_bytes", log_bytes);
    v("extrinsic", extrinsic);
    v.since("goals", goals);  // (nor this before issue 41)
  }
};

class RunDriver {
 public:
  // `protocol`: what the driver uses between runs (each run's configuration brings its own).
  RunDriver(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol);
  // `pump` handles pending messages (and ticks in-process nodes); `health`
  // returns "" or why a process is gone. A SIGINT or SIGTERM (stopRequested())
  // cuts the run: it is stopped, its log closed, and the outcome says so.
  RunOutcome run(const RunSpec& spec, const std::function<void()>& pump, const std::function<std::string()>& health);
  // Told the step each process of the run reports in its heartbeat, as it comes (progress display).
  void onStep(std::function<void(std::int64_t)> f) { on_step_ = std::move(f); }
  // Told each affordance table of the run as the driver takes it into the run's curve (afford.tune's pruning).
  void onTable(std::function<void(const TableSnapshot&)> f) { on_table_ = std::move(f); }
  // Told whom a run waits for, as that changes: processes not heard for a few heartbeats ("" once all are).
  void onWaiting(std::function<void(const std::string&)> f) { silence_.onWaiting(std::move(f)); }
  // A keyed bus (afford/auth.hpp): set before the first run.
  void useBusKey(std::shared_ptr<const BusKey> key) { edge_.useKey(std::move(key)); }

 private:
  using Clock = std::chrono::steady_clock;
  enum class Phase { Idle, Freeing, Configuring, Running, Stopping };
  struct Seen {
    std::string run_id;
    std::int64_t step = -1;
    int state = -1;
    int pid = 0;
    std::int64_t config_digest = 0;  // of the configuration its state is about
    std::string detail;
    std::string stuck;  // what it could not take, when it said so
    Clock::time_point at;
    std::string counts_run;          // the run (and configuration) of what it says it published
    std::int64_t counts_config = 0;
    std::int64_t taken = 0;          // the sum of its restart positions (the logger: what its log holds)
    std::int64_t moves = 0;          // STATUS that said it went further in one run (step, restart positions)
  };
  // What one run() waits with: the caller's pump and health.
  struct Waiting {
    const std::function<void()>& pump;
    const std::function<std::string()>& health;
  };
  // How a stage of run() ended: done, failed (why), or cut by a signal.
  struct Ending {
    bool interrupted = false;
    std::string why;  // "" and not interrupted: done
  };
  // The stages of run(), in order.
  Ending waitFree(const Waiting& w);   // every process present and free
  Ending configure(const Waiting& w);  // RUN_CONFIG until every one is READY
  Ending runSteps(const Waiting& w);   // START, then until the result, every table and the logger are in
  // STOP; the logger closes the log, if it opened one. `patient`: a silent logger (killed, paused) is waited
  // for as long as the run's stall bound, else (the run cut by a signal) close_timeout_ms.
  Ending stopAndWait(const Waiting& w, bool patient);
  std::string loggerBehind() const;    // where the logger's log stands against what was published
  RunOutcome& failed(const std::string& why);
  RunOutcome& interrupted(const Waiting& w);
  // Does this state concern our request (our run id and configuration)?
  bool ourRequest(const Seen& s) const;
  // The run's processes for which `pred` does not hold, by name.
  std::string missing(const std::function<bool(const Seen&)>& pred) const;
  // How many of the run's processes `pred` holds for, and how often they went further (Seen::moves), as one
  // mark that grows with both: a wait's progress.
  std::int64_t progressOf(const std::function<bool(const Seen&)>& pred) const;
  // Is a process of the run for which `pred` does not hold silent for less than the run's stall bound (heard
  // before, then killed and not started again yet, or paused)? The run waits for it, as it does mid-run.
  bool awaitingSilent(const std::function<bool(const Seen&)>& pred) const;
  std::string failedProcess() const;  // a process of the run that failed with our configuration, and why
  std::string foreign() const;        // the processes told to leave another configuration of this run, and how often
  std::string stuckProcesses() const; // what each process of the run could not take, as its STATUS said
  bool logged() const;                // the run is recorded: the logger is one of its processes
  bool loggerJoined() const;          // the logger took the run, as far as its STATUS says
  bool loggerHolds() const;           // ... and its log holds all that the run's publishers said they published
  Turn onStatus(const process_status_t& m);
  // Tell a process of the run what it missed (a lost datagram, or a restart).
  void nudge(const std::string& process, const Seen& s);
  void sendControl(const std::string& run_id, int8_t command, std::int64_t config_digest);
  void sendOurs(int8_t command) { sendControl(spec_->run_id, command, config_msg_.digest); }
  bool ours(const std::string& process) const;
  // Is `folder` the run's own (<log_root>/<run_id>)?
  bool isRunFolder(const std::string& folder) const;
  // What the runner's beat says it waits for (experiment/run/runners.hpp).
  RunnerBeat::Doing doing() const;

  lcm::LCM& lcm_;
  std::shared_ptr<spdlog::logger> log_;
  Edge edge_;
  RunnerBeat runners_;  // its beat; the other runners and the processes' copies heard
  std::map<std::string, Seen> seen_;
  std::map<std::string, Clock::time_point> nudged_;  // last time each process was told again
  std::map<std::string, int> foreign_;  // times each process was told to leave another request of this run id
  // Whom a warning was said of (process, pid): once each in a run, however often a recording says it again.
  std::set<std::pair<std::string, int>> warned_;
  const RunSpec* spec_ = nullptr;
  RunConfig config_;
  run_config_t config_msg_;
  Phase phase_ = Phase::Idle;
  Clock::time_point phase_at_{};  // when the current phase began
  RunOutcome* outcome_ = nullptr;
  Clock::time_point started_at_{};  // when run() was called
  bool have_result_ = false;
  bool goals_ended_ = false;  // goals phase: the last GOAL_RESULT (step run.steps) is in
  bool logger_done_ = false;
  bool closing_ = false;  // the logger opened the run's log: STOP waits for it to close it
  // Per run channel: the most its publisher said it published in our request, and what the logger's log holds.
  std::map<std::string, std::int64_t> published_, logged_;
  std::function<void(std::int64_t)> on_step_;
  std::function<void(const TableSnapshot&)> on_table_;
  Silence silence_;  // the run's processes gone silent mid-run, said at once
};

}  // namespace afford

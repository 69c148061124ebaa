// The runner's side of one run's choreography: waits for the processes,
// publishes RUN_CONFIG, waits for READY, publishes START, collects the
// affordance tables and the result, then STOP. It watches for stalls and for
// processes that stop reporting, so a run never hangs silently. A process of
// the run that reports free again (killed and started anew) is given the
// run's RUN_CONFIG and START again: it catches up by asking for the run's
// messages (docs/operating.md, "Killing and restarting a process").
// Channels in:  STATUS, AFFORDANCE_TABLE, RESULT, EXTRINSIC_RESULT (in serial order)
// Channels out: RUN_CONFIG, RUN_CONTROL, RESEND
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "afford/serials.hpp"

namespace afford {

struct RunSpec {
  std::string run_id;
  std::string experiment;
  std::string system;
  std::int64_t seed = 0;
  std::int64_t steps = 0;
  std::string config_yaml;
  std::vector<std::string> processes;  // names expected to take part
  bool extrinsic = false;              // ends with EXTRINSIC_RESULT instead of RESULT
  double stall_seconds = 30;           // no progress for this long fails the run
};

struct TableSnapshot {
  std::int64_t step = 0;
  std::vector<std::vector<double>> affordance;  // objects x actions
};

struct SubGoalOutcome {
  double x = 0, y = 0;
  int iterations = 0, actions_checked = 0, actions_taken = 0;
  bool reached = false;
};

struct ExtrinsicOutcome {
  std::string scenario;
  bool success = false;
  int completion = 0;  // iteration (from 1) at which the scene matched the goal
  int attempts = 0;
  double utility = 0;  // summed value of the objects in their goal state at the end
  std::vector<SubGoalOutcome> sub_goals;
};

struct RunOutcome {
  bool ok = false;
  std::string error;
  std::string weights_checksum;
  std::string checkpoint;                     // the predictors' saved weights, if any
  std::vector<TableSnapshot> curve;           // every curve_interval steps, and the end
  std::vector<std::int64_t> executed, successes;
  std::string log_dir;                        // from the logger, if one took part
  double wall_seconds = 0;                    // whole run, set-up included
  double run_seconds = 0;                     // from START to RESULT: the steps themselves
  std::map<std::string, long> peak_rss_kb;    // per process (VmHWM), filled by the runner
  std::uintmax_t log_bytes = 0;               // size of the run's log, if any
  ExtrinsicOutcome extrinsic;                 // extrinsic runs
};

class RunDriver {
 public:
  RunDriver(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log);
  // `pump` handles pending messages (and ticks in-process nodes); `health`
  // returns "" or why a process is gone.
  RunOutcome run(const RunSpec& spec, const std::function<void()>& pump, const std::function<std::string()>& health);

 private:
  struct Seen {
    std::string run_id;
    std::int64_t step = -1;
    int state = -1;
    std::string detail;
    std::chrono::steady_clock::time_point at;
  };
  struct Holder {
    std::function<void(const lcm::ReceiveBuffer*)> fn;
    void on(const lcm::ReceiveBuffer* b, const std::string&) { fn(b); }
  };
  void listen(const std::string& channel, std::function<void(const lcm::ReceiveBuffer*)> fn);
  // A run message in serial order? (asks for missing ones)
  bool inOrder(const std::string& channel, std::int64_t serial);
  void askMissing();

  lcm::LCM& lcm_;
  std::shared_ptr<spdlog::logger> log_;
  std::vector<std::unique_ptr<Holder>> holders_;
  std::map<std::string, Seen> seen_;
  std::string run_id_;
  RunOutcome* outcome_ = nullptr;
  bool have_result_ = false;
  bool logger_done_ = false;
  SerialTracker serials_;
};

}  // namespace afford

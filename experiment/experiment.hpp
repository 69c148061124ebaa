// `afford experiment NAME ...`: runs repetitions of an experiment's intrinsic
// phase for one or more systems, J runs at a time, each on its own LCM URL,
// and writes DIR/summary.json plus CSV files (schema: docs/results-schema.md).
// It keeps its options (DIR/experiment.json) and each finished run's outcome
// (DIR/runs/<run-id>.json) as it goes: SIGINT or SIGTERM stops the runs under
// way, writes the summary of those that finished and exits 128 + the signal;
// `--resume` runs the rest (docs/experiments.md).
#pragma once
#include <csignal>
#include <spdlog/spdlog.h>

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "experiment/stored/request.hpp"

namespace afford {

// --process NAME=CMD options (`option` names them in errors): NAME a process of the registry, CMD not empty,
// each NAME once.
std::map<std::string, std::string> parseProcessSwaps(const std::vector<std::string>& given, const std::string& option);

// Every check runExperiment makes before anything runs (options, config keys and values, the plan, the
// folders), with nothing written nor started: throws ConfigError naming what is wrong, or returns the
// intrinsic runs it would run (run id, system, steps), in plan order. Give a run prefix (without one, a
// fresh experiment's prefix would be reserved in the log root).
struct CheckedRun {
  std::string run_id, system;
  std::int64_t steps = 0;
};
std::vector<CheckedRun> checkExperiment(const ExperimentRequest& request);

// Returns the process exit code (0 when every run succeeded).
int runExperiment(const ExperimentRequest& request, spdlog::logger& log);

// Several experiments side by side, their runs and tests in one queue of job
// slots (the first request's --jobs, --transport, --base-port, --netns,
// --progress): each writes its own folder as it would alone; an agent two of
// them share is trained once, by the first in the queue's order that needs it,
// and taken by the others once it is stored. `resume`: the command that
// resumes the queue, said on SIGINT or SIGTERM. Returns the highest exit code.
int runQueue(const std::vector<ExperimentRequest>& requests, const std::string& resume, spdlog::logger& log);

// Stops the experiment under way in this process as a SIGINT does (the runs
// under way are cut, what finished is written, the folder resumes), asked by
// the program: `why` (e.g. "pruned") stands for the signal's name in its
// summary and state. Callable from any thread, before or during the run.
void stopExperiment(const std::string& why);

// For a host that goes on after an experiment (the Python package): from its
// construction a SIGINT or SIGTERM stops the experiment about to run; the
// handlers in place before are put back by restore() (else at its
// destruction), and the signal runExperiment received is forgotten at its
// destruction, so that the next experiment starts afresh.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
  // Puts the host's handlers back; returns SIGINT or SIGTERM if one came while the experiment's were in place (0
  // if none did), read once the host's are back: a signal that comes meanwhile goes to one or the other, never
  // to neither.
  int restore();
  // The reason given to stopExperiment, if the program stopped it ("" if not).
  std::string stoppedFor() const;

 private:
  struct sigaction int_{}, term_{};
};

}  // namespace afford

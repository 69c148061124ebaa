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

#include "afford/netns.hpp"

namespace afford {

struct ExperimentOptions {
  std::string experiment;
  std::vector<std::string> systems;        // FIX, IGN, IMP
  std::optional<int> reps;                 // default: the experiment file's repetitions
  std::optional<std::int64_t> steps;       // default: the experiment file's run.steps
  int jobs = 1;
  std::int64_t seed = 1;
  std::string out_dir = "out";
  std::string transport = "udpm";          // udpm | memq
  std::string keep_logs = "all";           // all | first | none
  std::string keep_checkpoints = "all";    // all | first | none: the intrinsic runs' checkpoints kept at the end
  bool reuse_agents = true;                // take stored agents of the same content key (afford/agents.hpp)
  std::string log_root = "logs";
  std::string run_prefix;                  // default: wall-clock stamp (names only)
  std::string config_dir;                  // default: the source tree's config/
  std::vector<std::string> settings;       // key.path=value overrides; key.path=v1,v2,... sweeps (afford/sweep.hpp)
  std::string sweep_file;                  // a YAML map of config keys to lists of values, swept too
  NetnsMode netns = NetnsMode::Auto;
  int base_port = 7700;
  std::string process_log_level = "info";  // for the processes (udpm) / in-process nodes (memq: warn)
  double stall_seconds = 30;
  bool quiet = false;                      // no table at the end
  std::string progress = "auto";           // auto | terminal | lines | none (afford/progress.hpp)
  double progress_every = -1;              // seconds between progress draws (< 0: by mode)
  int extrinsic_reps = 0;                  // tests per scenario from each intrinsic run (0: none)
  std::vector<std::string> scenarios;      // default: every config/scenarios/*.yaml
  std::optional<int> tables;               // random tables: how many (default: the experiment file's tables.count)
  std::optional<std::int64_t> table_seed;  // ... and the series they are drawn from (default: its tables.seed)
  std::string attach;                      // run on this bus with processes started by hand (no group, one job)
  // --process NAME=CMD: the runner starts CMD (a shell command, the standard arguments appended) in place of
  // the shipped afford-NAME (udpm only)
  std::map<std::string, std::string> processes;
  std::string bus_key;                     // key file of a keyed bus (afford/auth.hpp; "": $AFFORD_BUS_KEY, or none)
  int shard_index = 0, shard_count = 0;    // --shard i/n: run intrinsic run k (and its tests) iff k mod n == i
  std::vector<std::string> merged_from;    // afford merge: the shards' folders (nothing is run)
  std::string merged_network;              // ... and the network they ran over
  bool resume = false;                     // continue the unfinished experiment stored in out_dir
  std::set<std::string> given;             // options given on the command line ("--reps", "name", ...): with
                                           // resume, plan options must match the stored ones, run options override
  std::string program = "afford";          // how the command was called (in the resume command it prints)
};

// --process NAME=CMD options (`option` names them in errors): NAME a process of the registry, CMD not empty,
// each NAME once.
std::map<std::string, std::string> parseProcessSwaps(const std::vector<std::string>& given, const std::string& option);

// Returns the process exit code (0 when every run succeeded).
int runExperiment(const ExperimentOptions& options, spdlog::logger& log);

// For a host that goes on after an experiment (the Python package): the
// SIGINT and SIGTERM handlers in place at its construction are put back at its
// destruction, and the signal runExperiment received is forgotten, so that the
// next experiment starts afresh.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
  // SIGINT or SIGTERM if one stopped the experiment; 0 if none did.
  int signal() const;

 private:
  struct sigaction int_{}, term_{};
};

}  // namespace afford

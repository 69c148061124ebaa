// What plans an experiment: the experiment, its systems, seeds and settings,
// and what each run keeps. Two requests that agree here plan the very same
// runs (their ids and configurations), whoever hosts them and wherever the
// results are written.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "experiment/schema/codec.hpp"

namespace afford {

struct PlanRequest {
  std::string experiment;
  std::vector<std::string> systems;        // FIX, IGN, IMP (default: the experiment file's)
  std::optional<int> reps;                 // default: the experiment file's repetitions
  std::optional<std::int64_t> steps;       // default: the experiment file's run.steps
  std::int64_t seed = 1;
  std::string config_dir;                  // default: the installed or source config/
  std::vector<std::string> settings;       // key.path=value overrides; key.path=v1,v2,... sweeps (plan/sweep.hpp)
  std::string sweep_file;                  // a YAML map of config keys to lists of values, swept too
  std::optional<int> extrinsic_reps;       // tests per scenario from each intrinsic run (0: none); default: the design's
  std::optional<int> extrinsic_reps_010;   // as 0.1.0 and 0.2.0 kept it, 0 for "not given" (read, never written)
  std::vector<std::string> scenarios;      // default: the design's, or every config/scenarios/*.yaml
  std::optional<int> tables;               // random tables: how many (default: the experiment file's tables.count)
  std::optional<std::int64_t> table_seed;  // ... and the series they are drawn from (default: its tables.seed)
  std::string run_prefix;                  // the run ids' first part (default: a wall-clock stamp, names only)
  std::string keep_logs = "all";           // all | first | none: which runs are recorded
  std::string keep_checkpoints = "all";    // all | first | none: the intrinsic runs' checkpoints kept at the end
  std::string log_root = "logs";           // each run's folder (its log and checkpoints) is log_root/<run-id>
  std::string truth_dir;                   // a table world's truth is kept there (default: log_root/truth)
  bool with_truth = true;                  // false: planned without a table's truth, none estimated (a check
                                           // of the request, which runs nothing; not kept)
  // What an experiment keeps of it (DIR/experiment.json, experiment/state.hpp).
  template <class V>
  void visit(V& v) {
    v("experiment", experiment);
    v("systems", systems);
    visitNullable(v, "reps", reps);
    visitNullable(v, "steps", steps);
    v("seed", seed);
    v("keep_logs", keep_logs);
    v.since("keep_checkpoints", keep_checkpoints, std::string("all"));  // (stored before issue 13: all were kept)
    v("log_root", log_root);
    v("run_prefix", run_prefix);
    v("config_dir", config_dir);
    v("settings", settings);
    v.since("sweep_file", sweep_file, std::string());  // (before issue 13: no sweeps)
    v("extrinsic_tests", extrinsic_reps);         // absent when not given (0.3.0 on)
    v("extrinsic_reps", extrinsic_reps_010);      // (0.1.0 and 0.2.0)
    v("scenarios", scenarios);
    visitNullable(v, "tables", tables);
    visitNullable(v, "table_seed", table_seed);
    v.since("truth_dir", truth_dir, std::string());  // (before issue 58: log_root/truth, or no table)
  }
};

// The checks of a request that need no file: each names its option.
void checkPlanRequest(const PlanRequest& r);

}  // namespace afford

// What `afford experiment` is asked: an experiment request, as the command
// line, a --plan entry, the Python package or a resumed experiment's stored
// options give it (experiment/stored/state_file.hpp keeps it in DIR/experiment.json).
#pragma once
#include <set>
#include <string>
#include <vector>

#include "experiment/execute/request.hpp"
#include "experiment/plan/request.hpp"
#include "experiment/results/request.hpp"

namespace afford {

// An experiment request: what plans, what hosts and what writes, and how it
// is executed (afresh, resumed, or merged from shards' folders).
struct ExperimentRequest {
  PlanRequest plan;
  HostRequest host;
  WriteRequest write;
  bool resume = false;                     // continue the unfinished experiment stored in write.out_dir
  std::vector<std::string> merged_from;    // afford merge: the shards' folders (nothing is run)
  std::string merged_network;              // ... and the network they ran over
  std::set<std::string> given;             // options given on the command line ("--reps", "name", ...): with
                                           // resume, plan options must match the stored ones, run options override
  // The command, before `--resume --out DIR`, that reaches this experiment's processes again (state.hpp's
  // reachCommand): scripts/procs.sh's run of its group, or the runner with the bus options it was given.
  std::string resume_with;
  // What an experiment keeps of its request (the "options" of DIR/experiment.json, experiment/stored/state_file.hpp):
  // one map of the plan's keys, the host's and these.
  template <class V>
  void visit(V& v) {
    plan.visit(v);
    host.visit(v);
    v("quiet", write.quiet);
    v.since("merged_from", merged_from, std::vector<std::string>());  // a merge resumes as one: it gathers its shards again
    v.since("merged_network", merged_network, std::string());
    v.since("resume_with", resume_with, std::string());  // (before issue 55: the runner alone)
  }
};

}  // namespace afford

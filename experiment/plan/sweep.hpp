// Sweeps: `--set key=v1,v2,...` (repeatable) and `--sweep FILE` (a YAML map
// of config keys to lists of values) ask for the cross product of the values;
// each combination is a condition, run with every system and seed of the
// experiment. An experiment with a sweep is one part per condition, each part
// planned, run and summarised as an experiment of its own
// (DIR/conditions/<folder>/), all parts' runs sharing the job slots.
#pragma once
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "experiment/plan/plan.hpp"
#include "experiment/plan/request.hpp"

namespace afford {

struct SweepCondition {
  std::string name;                   // "key=v1,key2=w" (the swept keys only)
  std::string folder;                 // its folder under DIR/conditions/
  std::vector<std::string> settings;  // key=value, one per swept key
};

struct Sweep {
  std::vector<std::string> fixed;                                       // settings with one value
  std::vector<std::pair<std::string, std::vector<std::string>>> keys;  // swept keys and their values, in order
  std::vector<SweepCondition> conditions;                               // the cross product; empty: no sweep
};

// A value split at its top-level commas (not inside [], {} or quotes).
std::vector<std::string> sweepValues(const std::string& value);

// The sweep of `settings` (each key=value or key=v1,v2,...) and of the sweep
// file, if any. A key swept twice is an error naming it.
Sweep planSweep(const std::vector<std::string>& settings, const std::string& sweep_file);

// One part of an experiment: its plan and request (for a sweep condition:
// its settings and run prefix) and its output folder.
struct Part {
  Plan plan;
  PlanRequest request;
  std::string out_dir;
  std::string condition;  // "" without a sweep
  std::vector<std::string> condition_settings;
  std::size_t offset = 0;  // of its runs in the experiment's list
};

// The parts of an experiment (one without a sweep), planned and checked.
std::vector<Part> planParts(const PlanRequest& o, const std::string& out_dir, const Sweep& sweep);

// Every part's runs in one list (indices renumbered); `offsets[k]`: where part k's begin.
std::vector<PlannedRun> concatRuns(const std::vector<std::vector<PlannedRun>>& parts, std::vector<std::size_t>& offsets);

}  // namespace afford

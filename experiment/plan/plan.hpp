// Planning an experiment: the validated list of its runs (intrinsic runs,
// then the extrinsic tests of every trained agent), each with its effective
// configuration and run id. Everything that can be wrong with a request is
// found here, before any process starts.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "afford/config.hpp"
#include "experiment/run/driver.hpp"
#include "experiment/plan/request.hpp"
#include "experiment/design/design.hpp"
#include "experiment/design/generate.hpp"
#include "experiment/design/reference.hpp"
#include "experiment/design/tables.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {

struct PlannedRun {
  RunSpec spec;
  std::string system;
  std::vector<std::vector<double>> target;  // the world's affordance table (objects x actions)
  int table = -1;                            // random tables: which one
  std::string intrinsic_condition;           // random tables: the condition's name ("" without conditions)
  bool keep_log = false;
  bool keep_checkpoint = true;  // intrinsic runs: its checkpoints stay once the experiment is over
  std::size_t index = 0;
  // extrinsic tests: which intrinsic run trained the agent, which scenario, which repetition
  std::size_t intrinsic = 0;
  std::string scenario;
  int condition = 0;  // index into Plan::conditions
  int rep = 0;
};

// The validated list of runs of a request, with each system's config.
struct Plan {
  std::string config_dir;
  std::optional<Reference> reference;        // config/reference.yaml, read before anything runs
  ExperimentFile exp;
  int reps = 0;
  std::int64_t seed = 1;                     // the first repetition's (then seed + 1, ...)
  std::vector<PlannedRun> runs;
  std::map<std::string, RunConfig> configs;  // per system (of its first repetition)
  std::vector<std::string> systems;          // the systems run
  std::vector<std::string> scenarios;        // extrinsic tests, if any
  std::map<std::string, int> sub_goals;      // objects (sub-goals) per scenario
  std::map<std::string, Scenario> generated;  // scenarios drawn for the design (extrinsic.generate), by name
  std::map<std::string, ScenarioSpec> specs;  // ... and what each was drawn as
  int tests = 0;                             // extrinsic tests per agent, condition and scenario
  std::vector<Condition> conditions{Condition{}};  // planner settings compared (default: one, no settings)
  ExtrinsicDesign design;                    // the experiment file's extrinsic section, if any
  ProtocolConfig protocol;                   // the runner's between runs (each run's config has its own)
  std::optional<TablesDesign> tables;        // random tables (count and seed as run), if any
  std::vector<AffordanceTable> table_list;   // ... the tables drawn
  std::vector<std::pair<std::string, std::vector<std::string>>> conditions_run{{"", {}}};  // intrinsic conditions
};


// The run ids' first part when none is given: the wall clock (names only).
std::string defaultPrefix();

// A default prefix that no other experiment of `log_root` has or will take:
// the wall clock, then "-2", "-3", ... when an experiment of that second (in
// this process or another) took it. The name is reserved as a folder in
// <log_root>/.prefixes/ (made atomically, so two runners never take one).
std::string reservePrefix(const std::string& log_root);

Plan planExperiment(const PlanRequest& o);

// The tests of every condition and scenario from each intrinsic run that left
// a checkpoint. An agent without the checkpoint the design asks for (not
// written, or too few actions for extrinsic.after_actions) is not tested;
// `errors` says why.
std::vector<PlannedRun> planExtrinsic(const Plan& plan, const std::vector<RunOutcome>& trained,
                                      const PlanRequest& o, std::vector<std::string>& errors);

// Space-separated.
std::string joined(const std::vector<std::string>& v);

}  // namespace afford

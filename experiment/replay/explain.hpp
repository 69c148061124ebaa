// `afford explain LOG`: why an extrinsic test ended as it did, read from its
// log. The test's messages are replayed into a fresh planner (as `afford
// replay --into planner` does), whose core tells an observer
// (PlannerObserver) every sub-goal it picks, every comparison it makes with
// the run's thresholds and every action it decides: the explanation is the
// planner's own account, not a second derivation of it. What the replayed
// planner publishes is compared with the recorded messages, and its
// per-sub-goal figures with the test's EXTRINSIC_RESULT; any difference, and
// a message the replay waits for that the log lacks, is a warning. Given a
// folder of run logs (an experiment's --log-root), it summarises every
// extrinsic test in it.
#pragma once
#include <spdlog/spdlog.h>

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "experiment/replay/replay.hpp"
#include "planner/planner.hpp"

namespace afford {

// The log is of a run, but not of an extrinsic test (a summary skips it).
struct NotAnExtrinsicTest : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// One candidate action's predicted effect compared with the sub-goal, as the planner core compared it.
using ExplainedCheck = PlannerCheck;

// A look at the scene at the sub-goal's place: is the sub-goal reached?
struct ExplainedReachCheck {
  bool after_action = false;  // false: right after the sub-goal was picked
  double distance = 0;        // imageDistance(sub-goal image, scene there)
  bool reached = false;       // < planner.subgoal_match
};

// One planner iteration (a `step` of the test's messages, counted from 0).
struct ExplainedIteration {
  std::int64_t step = 0;
  int sub_goal = -1;    // index into Explanation::sub_goals (-1: none known)
  bool picked = false;  // the sub-goal was picked in this iteration
  std::vector<ExplainedReachCheck> reach_checks;
  bool scanned = false;  // the scene was scanned for an object
  double object_x = 0, object_y = 0;
  std::optional<std::array<double, kNumActions>> affordance;  // from the PREDICTION answering the scan
  std::vector<int> candidates;                                // actions the FORWARD_QUERY asked about
  std::vector<ExplainedCheck> checks;                         // the FORWARD_PREDICTION's, in order
  int executed = -1;                                          // the DECISION's action, -1: none
  double target_x = -1, target_y = -1;                        // its move target
  double goal_distance_after = -1;                            // the SCENE after it (-1: none)
  bool reached() const;
};

struct ExplainedSubGoal {
  double x = 0, y = 0;
  std::int64_t first_step = 0, last_step = 0;
  int iterations = 0;  // counted as the planner counts them: not the one it was found reached in
  int actions_checked = 0;
  int actions_taken = 0;
  bool reached = false;
  bool reached_when_picked = false;  // the scene showed it already: no iteration spent on it
  // How the planner left it, as its core told: "reached"; "timeout" (not
  // reached in planner.subgoal_timeout iterations: another was picked);
  // "left" (the utility planner moves on after each weighed action,
  // Algorithm 3); "not_actionable" (top-down attention: no remembered object
  // left to try for it); "open" (the test ended while it was the sub-goal).
  std::string ended;
  // The checked action that passed both tests; else, of those whose
  // predicted place matched, the one with the smallest what-distance; else
  // the smallest what-distance ("the closest miss"); and the step it was checked in.
  std::optional<ExplainedCheck> closest;
  std::int64_t closest_step = -1;
  // The object the test scanned at the sub-goal's place (within
  // planner.position_match) while the sub-goal was open, if it scanned one:
  // its affordances at the last such scan, and the colour action that would give it the sub-goal's
  // colour (the dominant channel of the sub-goal image). None for a move's
  // free target place: colour_action is then -1.
  std::optional<std::array<double, kNumActions>> place_affordance;
  int colour_action = -1;
  // The colour action's affordance is at most planner.affordance_threshold,
  // with planner.restrict_by_affordance: the planner never asks about it there.
  bool colourActionBlocked(const PlannerConfig& p) const;
};

struct Explanation {
  std::string log;  // where it was read
  std::string run_id, experiment, system, scenario;
  std::string agent;  // the trained agent: the folder of its checkpoint (its intrinsic run's id)
  std::int64_t seed = 0;
  PlannerConfig planner;  // the run's: thresholds, budget, action limit
  WorldKind world = WorldKind::Grid;  // the run's world (its actions' names)
  bool success = false;
  int completion = 0;  // EXTRINSIC_RESULT: the iteration, counted from 1, at which it was solved
  int attempts = 0;    // actions executed
  double utility = 0;
  std::int64_t iterations = 0;      // run, by the EXTRINSIC_RESULT
  double start_goal_distance = -1;  // the SCENE the test began with
  double final_goal_distance = -1;  // the last SCENE's
  // "solved" (goal distance below planner.success_distance), "budget"
  // (planner.budget iterations ran out), "attempts" (planner.max_attempts
  // actions executed), "unknown" (none of them: a warning says so).
  std::string end;
  bool also_out_of_attempts = false;  // "budget", and the action limit was reached too
  std::vector<ExplainedSubGoal> sub_goals;
  std::vector<ExplainedIteration> steps;
  std::vector<std::string> warnings;  // the rebuilt figures against the EXTRINSIC_RESULT, refused messages, gaps
};

// Explain the extrinsic test whose RUN_CONFIG starts `run.events` (as
// RunSelector takes them). `where` names the log in errors; `torn_bytes`,
// `incomplete` and `manifest_missing` are what the log file and its manifest
// say beyond the events. Throws NotAnExtrinsicTest, or std::runtime_error
// naming what is missing.
Explanation explainRunEvents(const RunEvents& run, const std::string& where, std::int64_t torn_bytes = 0,
                             const std::string& incomplete = "", const std::vector<LogGap>& manifest_missing = {});
// Read a run's log folder (or one .lcm file) and explain the test in it: the
// first run, or `run_id`'s. A log cut short (log_cut.hpp) is refused, saying
// what is missing. `key`: an lcm-logger recording of a keyed bus (its tags checked and taken off).
Explanation explainLog(const std::string& log_path, const std::string& run_id, spdlog::logger& log,
                       const BusKey* key = nullptr);

// ---- a folder of run logs ------------------------------------------------------------

struct ExplainSummary {
  std::string root;
  std::vector<Explanation> tests;                            // in folder-name order
  std::vector<std::pair<std::string, std::string>> skipped;  // folder, why (runs that are not extrinsic tests)
  std::vector<std::pair<std::string, std::string>> errors;   // folder, what was wrong
};

// True when `path` is a folder of run log folders rather than one run's log.
bool isLogRoot(const std::string& path);
// Every extrinsic test under `root` (one level down). Throws when there is none.
ExplainSummary explainLogRoot(const std::string& root, spdlog::logger& log, const BusKey* key = nullptr);

// ---- per agent and sub-goal (afford explain ROOT --by-agent) --------------------------

// One sub-goal of a scenario over every test of one trained agent that picked it.
struct AgentSubGoal {
  std::string experiment, system, agent, scenario;
  double x = 0, y = 0;
  PlannerConfig planner;  // the thresholds (of the first test)
  int tests = 0;          // tests that picked it (a test that picked it again counts once)
  int reached = 0;
  // Why it was not reached, test by test: no action was checked; the
  // closest check's what-distance was not below image_match; what passed and
  // where did not; an action passed both (it failed, or Algorithm 3 left it).
  int not_checked = 0, what_miss = 0, where_miss = 0, passed = 0;
  std::optional<ExplainedCheck> closest;  // the best over the tests, as ExplainedSubGoal::closest
  double closest_what_max = -1;           // the largest of the tests' closest what-distances
  std::optional<std::array<double, kNumActions>> place_affordance;  // the last test's that scanned the place
  int colour_action = -1;
  int colour_blocked = 0;  // tests not reaching it in which the colour action's affordance kept it from being asked about
};

// The same sub-goal of the same scenario over all agents of a system.
struct SystemSubGoal {
  std::string experiment, system, scenario;
  double x = 0, y = 0;
  PlannerConfig planner;
  int agents = 0;
  int agents_always = 0;          // reached it in every test
  int agents_never_checked = 0;   // checked no action for it in any test
  int agents_what_miss = 0;       // whose closest what-distance over all tests is not below image_match
  int agents_where_miss = 0;      // whose closest check matched what but not where
  int agents_colour_blocked = 0;  // whose colour action was not afforded at the place in some test
  std::vector<double> closest_what;  // each agent's closest what-distance, ascending (agents with a check)
};

// Keyed and ordered by experiment, system, scenario, sub-goal place, agent.
std::vector<AgentSubGoal> subGoalsByAgent(const ExplainSummary& s);
std::vector<SystemSubGoal> subGoalsBySystem(const std::vector<AgentSubGoal>& agents);

}  // namespace afford

// Planner process node: Algorithm 2 (paper 2.4.3) in the extrinsic phase, as
// a choreography: each request of the planner core becomes a message, and the
// answer it waits for feeds the core.
// Channels in:  RUN_CONFIG, RUN_CONTROL, SCENE (goal distance), FOCUS (answers
//               to LOOK), PREDICTION (affordances of the scanned object),
//               FORWARD_PREDICTION
// Channels out: LOOK, FORWARD_QUERY, DECISION (the chosen action), EXTRINSIC_RESULT, STATUS
// A test ends when the environment's scene matches the goal image
// (planner.success_distance), or after planner.budget iterations or
// planner.max_attempts actions. In the intrinsic phase the planner is idle.
// Goals phase (docs/model.md#goals-of-its-own): it pursues each GOAL the
// motivation sets, one step at a time (a look at the goal place, one at the
// goal's object, forward queries, one DECISION: an action or a pass), and
// publishes GOAL_RESULT when the goal is reached, its budget spent, or nothing
// is left to try.
#pragma once
#include <array>
#include <memory>
#include <optional>

#include "afford/decision_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/goal_t.hpp"
#include "afford/node.hpp"
#include "afford/prediction_t.hpp"
#include "afford/scene_t.hpp"
#include "planner/planner.hpp"

namespace afford {

class PlannerNode : public NodeBase {
 public:
  // `observer` (not owned; nullptr: none) is told what the core checks and decides in each test.
  PlannerNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol,
              PlannerObserver* observer = nullptr);

 private:
  void onConfigured(const RunConfig& config) override;
  void takeGoalsAndJoin();  // the GOAL input, and the object join (the constructor states the others)
  void onStop() override;
  void onScene(const scene_t& m);       // the test's start, or an action's scene
  void onFocus(const focus_t& m);       // the answer to a LOOK
  void onForward(const forward_prediction_t& m);  // the answer to a FORWARD_QUERY
  // Carry out a request of the core (until it needs an answer).
  void follow(PlannerRequest r);
  void look(int8_t kind, double x = -1, double y = -1);
  void onObject(const focus_t& f, const prediction_t& p);  // the scanned or attended object, with its affordances
  void endIteration();
  void finish(bool success);
  bool active() const { return core_ && state() == process_status_t::RUNNING && !finished_; }
  // Goals phase.
  bool goals() const { return config().phase == Phase::Goals; }
  // Snapshots (goals phase): taken between two goals, when the planner holds only its counts.
  bool snapshots() const override { return core_ && goals(); }
  bool atRest() const override { return !goal_ && awaiting_ == 0 && step_ >= 0; }
  void saveState(SnapshotWriter& w) override;
  void loadState(SnapshotReader& r) override;
  void onGoal(const goal_t& g);
  void onGoalScene(const scene_t& s);
  void decide(decision_t d);         // this step's DECISION; then the scenes it brings, if any
  void stepped();                    // the next step: what the decision did to the goal
  void goalIterationDone();
  void endGoal(bool reached);
  int scenesAfter(bool acted) const;  // the SCENEs of the step after a decision

  std::unique_ptr<Planner> core_;
  PlannerObserver* observer_;
  std::int64_t step_ = -1;          // the current iteration
  std::int32_t seq_ = 0;            // last request sent
  double goal_distance_ = -1;       // the environment's last word on it
  double goal_utility_ = -1;        // and on the value of what is in place
  bool waiting_scene_ = false;      // an action was sent; its scene is awaited
  std::int64_t scene_ = -1;         // serial of the last SCENE taken: each LOOK names it
  bool finished_ = false;
  PlannerRequest last_;             // the request being answered
  Both<focus_t, prediction_t> object_;  // the scanned object of this iteration and its affordances
  // Goals phase.
  std::optional<goal_t> goal_;       // the goal under way
  std::int32_t next_goal_id_ = 0;
  int goal_actions_ = 0;             // actions spent on it
  std::int64_t actions_ = 0;         // actions in the run
  int awaiting_ = 0;                 // SCENEs still to come for step_ + 1
  bool acted_ = false;               // the last decision was an action
  bool after_action_ = false;        // the iteration under way began with the scene of an action
  std::int64_t focus_serial_ = -1, forward_serial_ = -1;  // the last taken
  double object_x_ = -1, object_y_ = -1;  // this step's object, as the eye showed it
};

}  // namespace afford

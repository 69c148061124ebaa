// Motivation process node.
// Channels in:  RUN_CONFIG, RUN_CONTROL, PREDICTION (intrinsic phase);
//               FOCUS, EFFECT, FORWARD_PREDICTION, GOAL_RESULT (goals phase)
// Channels out: DECISION (intrinsic phase), GOAL (goals phase), STATUS
// In the goals phase its goal chooser (goals.kind, motivation/goals.hpp) sets
// the goals the planner pursues: the next once the last has ended and
// everything published before its end has been given to the chooser.
// Its one input, PREDICTION, is stated in the constructor (NodeBase::takes):
// predictions are decided in step order, so the decisions are a pure function
// of the run.
#pragma once
#include <memory>

#include <map>

#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/goal_result_t.hpp"
#include "afford/node.hpp"
#include "afford/prediction_t.hpp"
#include "motivation/component.hpp"
#include "motivation/goal_inputs.hpp"
#include "motivation/goals.hpp"

namespace afford {

class MotivationNode : public NodeBase {
 public:
  MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol);

 private:
  void onConfigured(const RunConfig& config) override;
  void onStart() override;
  void onStop() override;
  bool snapshots() const override { return goals_ ? goals_->snapshots() : core_ && core_->snapshots(); }
  void saveState(SnapshotWriter& w) override;
  void loadState(SnapshotReader& r) override;
  void decide(const prediction_t& m);
  // Goals phase.
  void sawFocus(const focus_t& m);
  void sawEffect(const effect_t& m);
  void sawForward(const forward_prediction_t& m);
  void ended(const goal_result_t& m);
  void setGoal(std::int64_t step);

  std::unique_ptr<MotivationComponent> core_;
  std::int64_t last_ = -1;  // last decided step
  // Goals phase.
  std::unique_ptr<GoalChooser> goals_;
  std::int32_t next_goal_ = 0;             // the id of the next goal set
  std::int64_t effects_ = 0;               // EFFECTs taken
  std::int64_t focus_serial_ = -1, forward_serial_ = -1;  // the last taken
  GoalInputs inputs_;                      // taken, for the chooser at the end of the goal they came before
                                           // (goals.held of each kind at most)
  std::int64_t last_result_step_ = -1;     // the step of the last GOAL_RESULT
  int unmoved_ = 0;                        // goals ended in a row at that step without an action
};

}  // namespace afford

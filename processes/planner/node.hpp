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
#pragma once
#include <array>
#include <memory>
#include <optional>

#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
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
};

}  // namespace afford

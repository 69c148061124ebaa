#include "motivation/node.hpp"

#include <algorithm>

#include "afford/protocol.hpp"
#include "motivation/messages.hpp"

namespace afford {

MotivationNode::MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol)
    : NodeBase(lcm, "motivation", std::move(log), protocol) {
  takes(ch::prediction,
        "intrinsic phase: the PREDICTION of each step, in step order, one decision each (paper Algorithm 1); "
        "when the motivation needs the predictors' memory (motivation.revisit; novelty), it says which look is in "
        "focus and what was tried on it; with IMP's observed_change threshold, it carries the report of the previous step's update")
      .in(Phase::Intrinsic)
      .withinRun([this] { return config().steps; })
      .stepInOrder([this] { return last_ + 1; })
      .refuse([this](const prediction_t& m) {
        return core_->needsMemory() && m.n_tried != kNumActions
                   ? "step " + std::to_string(m.step) +
                         " says nothing of the look in focus (n_tried = 0), which motivation '" +
                         config().motivation.kind + "' needs: do the predictors keep a memory?"
                   : "";
      })
      .refuse([this](const prediction_t& m) {
        return core_->needsLastChange() && (m.n_trained != 1 || m.trained[0].step != m.step - 1)
                   ? "step " + std::to_string(m.step) + " lacks the report of step " + std::to_string(m.step - 1) +
                         "'s update"
                   : "";
      })
      .then([this](const prediction_t& m) { decide(m); });
  // Taken as they come (a process catching up gets them ahead of the results), given to the chooser at the end
  // of the goal they came before (motivation/goal_inputs.hpp).
  // Each kind held is capped apart: a channel far ahead (catching up, the FOCUS of thousands of steps) waits,
  // and the others still bring what the next GOAL_RESULT waits for.
  const auto room = [this](GoalInputs::Kind k) {
    return [this, k](const auto&) { return inputs_.held(k) < static_cast<std::size_t>(config().goals.held); };
  };
  takes(ch::focus,
        "goals phase: every FOCUS, in order: an object's (a scan, an attended object) is what the agent saw of it, "
        "for the goal chooser at the end of the goal it came in")
      .in(Phase::Goals)
      .waitFor(room(GoalInputs::Object))
      .then([this](const focus_t& m) { sawFocus(m); });
  takes(ch::effect,
        "goals phase: every EFFECT: what the action did to the object, for the goal chooser at the end of the goal it "
        "came in")
      .in(Phase::Goals)
      .waitFor(room(GoalInputs::Effect))
      .then([this](const effect_t& m) { sawEffect(m); });
  takes(ch::forwardPrediction,
        "goals phase: every FORWARD_PREDICTION: what the forward models predict for the object of its step, for the "
        "goal chooser at the end of the goal it came in")
      .in(Phase::Goals)
      .waitFor(room(GoalInputs::Forward))
      .then([this](const forward_prediction_t& m) { sawForward(m); });
  takes(ch::goalResult,
        "goals phase: each GOAL_RESULT once, in order, when every EFFECT, FOCUS and FORWARD_PREDICTION out before "
        "it has been taken (its counts say which): the chooser is given them, then the goal's end; then the next "
        "GOAL")
      .in(Phase::Goals)
      .refuse([this](const goal_result_t& m) {
        return m.id != next_goal_ - 1 ? "goal " + std::to_string(m.id) + " is not the goal under way (" +
                                            std::to_string(next_goal_ - 1) + ")"
                                      : std::string();
      })
      .waitFor([this](const goal_result_t& m) {
        return effects_ >= m.effects && focus_serial_ >= m.focus_serial && forward_serial_ >= m.forward_serial;
      })
      .then([this](const goal_result_t& m) { ended(m); });
}

void MotivationNode::onConfigured(const RunConfig& config) {
  core_.reset();
  goals_.reset();
  if (config.phase == Phase::Goals)
    goals_ = makeGoalChooser(config);
  else
    core_ = makeMotivation(config);
  last_ = -1;
  next_goal_ = 0;
  effects_ = 0;
  focus_serial_ = forward_serial_ = -1;
  inputs_.clear();
  last_result_step_ = -1;
  unmoved_ = 0;
}

void MotivationNode::onStart() {
  if (goals_) setGoal(0);
}

void MotivationNode::onStop() {
  core_.reset();
  goals_.reset();
  inputs_.clear();
}

void MotivationNode::saveState(SnapshotWriter& w) {
  w.i64(last_);
  if (!goals_) return core_->save(w);
  w.i64(next_goal_);
  w.i64(effects_);
  w.i64(focus_serial_);
  w.i64(forward_serial_);
  w.i64(last_result_step_);
  w.i64(unmoved_);
  inputs_.save(w);
  goals_->save(w);
}

void MotivationNode::loadState(SnapshotReader& r) {
  last_ = r.within("last step decided", -1, config().steps);
  if (!goals_) return core_->load(r);
  next_goal_ = static_cast<std::int32_t>(r.within("next goal", 0, INT32_MAX));
  effects_ = r.within("effects taken", 0, config().steps);
  focus_serial_ = r.within("last focus serial", -1, INT64_MAX);
  forward_serial_ = r.within("last forward prediction serial", -1, INT64_MAX);
  last_result_step_ = r.within("last goal result step", -1, config().steps);
  unmoved_ = static_cast<int>(r.within("goals ended without an action", 0, INT32_MAX));
  inputs_.load(r, config().steps, 3 * static_cast<std::size_t>(config().eye.focus_side * config().eye.focus_side),
               GoalInputs::kKinds * static_cast<std::size_t>(config().goals.held));
  goals_->load(r);
}

void MotivationNode::sawFocus(const focus_t& m) {
  focus_serial_ = m.serial;
  if (m.kind == focus_t::SCENE_SCAN || m.kind == focus_t::SCENE_OBJECT) inputs_.object(m.step, m.seq, seenOf(m));
}

void MotivationNode::sawEffect(const effect_t& m) {
  ++effects_;
  inputs_.effect(seenEffectOf(m));
}

void MotivationNode::sawForward(const forward_prediction_t& m) {
  forward_serial_ = m.serial;
  if (m.n_input == 0) inputs_.forward(m.step, m.seq, imaginedOf(m));  // about an object seen, not imagined
}

void MotivationNode::ended(const goal_result_t& m) {
  inputs_.feed(*goals_, m.step, m.seq);
  goals_->attempted(attemptOf(m));
  handled(m.step);
  unmoved_ = m.actions == 0 && m.step == last_result_step_ ? unmoved_ + 1 : (m.actions == 0 ? 1 : 0);
  last_result_step_ = m.step;
  if (m.step >= config().steps) return setState(process_status_t::DONE);
  setGoal(m.step);
}

void MotivationNode::setGoal(std::int64_t step) {
  Goal g = goals_->next(step, next_goal_);
  // Goals found reached as they are set take no step: after two at one step, an exploration (every step acts).
  if (unmoved_ >= 2 && g.module != GoalModule::Explore) g = explorationGoal(config().seed, step, next_goal_);
  publish(ch::goal, goalMessage(runId(), step, next_goal_, g, config().goals.budget));
  ++next_goal_;
}

void MotivationNode::decide(const prediction_t& m) {
  publish(ch::decision, decisionMessage(runId(), m, core_->decide(perceptOf(m))));
  last_ = m.step;
  handled(m.step);
  if (m.step == config().steps - 1) setState(process_status_t::DONE);
}

}  // namespace afford

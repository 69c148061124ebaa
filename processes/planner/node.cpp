#include "planner/node.hpp"

#include "planner/messages.hpp"

#include "afford/protocol.hpp"
#include "afford/decision_t.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/look_t.hpp"

namespace afford {

PlannerNode::PlannerNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol,
                         PlannerObserver* observer)
    : NodeBase(lcm, "planner", std::move(log), protocol),
      observer_(observer),
      object_([this](const focus_t& f, const prediction_t& p) { onObject(f, p); }) {
  // Every input: only while a test goes on (the extrinsic phase, until its result).
  const auto idle = [this](const auto&) { return !core_ || finished_; };
  takes(ch::scene,
        "the SCENE that starts the test (once), then the scene of each action it decided, after the action "
        "(the goal scene is the eye's)")
      .ignoreIf(idle)
      .ignoreIf([](const scene_t& s) { return s.cause != scene_t::CAUSE_START && s.cause != scene_t::CAUSE_ACTION; })
      .refuse([this](const scene_t& s) {
        return s.cause == scene_t::CAUSE_START && step_ >= 0 ? "the test has begun already" : "";
      })
      .refuse([this](const scene_t& s) {
        return s.cause == scene_t::CAUSE_ACTION && s.step < step_
                   ? "the scene of step " + std::to_string(s.step) + " is in the past"
                   : std::string();
      })
      .waitFor([this](const scene_t& s) {
        return s.cause != scene_t::CAUSE_ACTION || (step_ >= 0 && s.step <= step_ && waiting_scene_);
      })
      .then([this](const scene_t& s) { onScene(s); });
  takes(ch::focus,
        "the FOCUS that answers the last request (its seq), of the kind asked for: a look, the differences, or "
        "the object of a scan or of an attention")
      .ignoreIf(idle)
      .waitFor([this](const focus_t& f) { return f.seq <= seq_; })
      .refuse([this](const focus_t& f) {
        return f.seq < seq_ ? "request " + std::to_string(f.seq) + " was answered already" : std::string();
      })
      .refuse([this](const focus_t& f) {
        const bool object = f.kind == focus_t::SCENE_SCAN || f.kind == focus_t::SCENE_OBJECT;
        const auto asked = f.kind == focus_t::SCENE_SCAN ? PlannerRequest::ScanScene : PlannerRequest::AttendObject;
        return object && (last_.kind != asked || object_.hasFirst()) ? "an object the planner did not ask for" : "";
      })
      .refuse([this](const focus_t& f) {
        return f.kind == focus_t::GOAL_DIFF && last_.kind != PlannerRequest::LookAtDifferences
                   ? "differences the planner did not ask for"
                   : "";
      })
      .refuse([this](const focus_t& f) {
        return (f.kind == focus_t::GOAL_SCAN && last_.kind != PlannerRequest::LookAtGoal) ||
                       (f.kind == focus_t::SCENE_AT && last_.kind != PlannerRequest::LookAtSceneAt)
                   ? "a look the planner did not ask for"
                   : "";
      })
      .then([this](const focus_t& f) { onFocus(f); });
  takes(ch::prediction,
        "the PREDICTION of the object the current iteration scanned or attended, once (it may come before or "
        "after that object's FOCUS)")
      .ignoreIf(idle)
      .refuse([this](const prediction_t& p) {
        return p.step < step_ ? "step " + std::to_string(p.step) + " is in the past" : std::string();
      })
      .waitFor([this](const prediction_t& p) {
        const bool asked = last_.kind == PlannerRequest::ScanScene || last_.kind == PlannerRequest::AttendObject;
        return asked && p.step == step_ && !object_.hasSecond();
      })
      .then([this](const prediction_t& p) { object_.second(p); });
  takes(ch::forwardPrediction,
        "the FORWARD_PREDICTION that answers the last request, a forward query (its seq); for an imagined "
        "object, with that object's affordances")
      .ignoreIf(idle)
      .waitFor([this](const forward_prediction_t& m) {
        return !(m.seq > seq_ || (m.seq == seq_ && last_.kind != PlannerRequest::Forward));
      })
      .refuse([this](const forward_prediction_t& m) {
        return m.seq < seq_ ? "query " + std::to_string(m.seq) + " was answered already" : std::string();
      })
      .refuse([this](const forward_prediction_t& m) {
        return !last_.prefix.empty() && m.n_input != kNumActions
                   ? "query " + std::to_string(m.seq) + " asked about an imagined object, and the answer has " +
                         std::to_string(m.n_input) + " input_affordance values, not " + std::to_string(kNumActions)
                   : std::string();
      })
      .then([this](const forward_prediction_t& m) { onForward(m); });
  joins(object_, ch::focus, ch::prediction,
        "the object the current iteration scanned or attended: its FOCUS and the PREDICTION of its affordances, "
        "in either order, go to the planner once both have come");
}

void PlannerNode::onConfigured(const RunConfig& config) {
  core_.reset();
  if (config.phase == Phase::Extrinsic) {
    core_ = std::make_unique<Planner>(config.planner, goalValues(*config.scenario));
    core_->observe(observer_);
  }
  step_ = -1;
  seq_ = 0;
  goal_distance_ = goal_utility_ = -1;
  waiting_scene_ = finished_ = false;
  scene_ = -1;
}

void PlannerNode::onStop() { core_.reset(); }


void PlannerNode::onScene(const scene_t& s) {
  if (s.cause == scene_t::CAUSE_START) {
    scene_ = s.serial;
    goal_distance_ = s.goal_distance;
    goal_utility_ = s.goal_utility;
    step_ = 0;  // the test begins
    return follow(core_->startIteration());
  }
  goal_distance_ = s.goal_distance;  // the scene of the action decided
  goal_utility_ = s.goal_utility;
  waiting_scene_ = false;
  scene_ = s.serial;
  follow(core_->onActed());
}

void PlannerNode::look(int8_t kind, double x, double y) {
  look_t l;
  l.run_id = runId();
  l.step = step_;
  l.seq = ++seq_;
  l.kind = kind;
  l.scene = scene_;
  l.x = x;
  l.y = y;
  publish(ch::look, l);
}

void PlannerNode::follow(PlannerRequest r) {
  last_ = r;
  switch (r.kind) {
    case PlannerRequest::LookAtGoal:
      return look(focus_t::GOAL_SCAN);
    case PlannerRequest::LookAtSceneAt:
      return look(focus_t::SCENE_AT, r.x, r.y);
    case PlannerRequest::ScanScene:
      object_.clear();
      return look(focus_t::SCENE_SCAN);
    case PlannerRequest::AttendObject:
      object_.clear();
      return look(focus_t::SCENE_OBJECT, r.x, r.y);
    case PlannerRequest::LookAtDifferences:
      return look(focus_t::GOAL_DIFF);
    case PlannerRequest::Forward:
      return publish(ch::forwardQuery, forwardQueryMessage(runId(), step_, ++seq_, r));
    case PlannerRequest::Act:
      waiting_scene_ = true;
      return publish(ch::decision, actionMessage(runId(), step_, r));
    case PlannerRequest::IterationDone:
      return endIteration();
  }
}

void PlannerNode::onFocus(const focus_t& f) {
  handled(f.step);
  if (f.kind == focus_t::SCENE_SCAN || f.kind == focus_t::SCENE_OBJECT) return object_.first(f);
  if (f.kind == focus_t::GOAL_DIFF) return follow(core_->onDifferences(differencesOf(f)));
  follow(core_->onView(viewOf(f)));
}

void PlannerNode::onObject(const focus_t& f, const prediction_t& p) {
  follow(core_->onObject(viewOf(f), affordancesOf(p.affordance)));
}

void PlannerNode::onForward(const forward_prediction_t& m) {
  std::optional<std::array<double, kNumActions>> input;
  if (!last_.prefix.empty()) input = affordancesOf(m.input_affordance);  // the query imagined its object
  follow(core_->onForward(forwardPredictionsOf(m), input));
}

void PlannerNode::endIteration() {
  handled(step_);
  if (goal_distance_ >= 0 && goal_distance_ < config().planner.success_distance) return finish(true);
  if (step_ + 1 >= config().planner.budget || core_->attempts() >= config().planner.max_attempts) return finish(false);
  ++step_;
  follow(core_->startIteration());
}

void PlannerNode::finish(bool success) {
  finished_ = true;
  extrinsic_result_t r;
  r.run_id = runId();
  r.step = step_ + 1;
  r.scenario = config().scenario->name;
  r.success = success;
  r.completion = success ? static_cast<int32_t>(step_ + 1) : 0;
  r.attempts = core_->attempts();
  r.utility = goal_utility_;
  for (const SubGoalRecord& g : core_->subGoals()) r.sub_goals.push_back(subGoalMessage(g));
  r.n_sub_goals = static_cast<int32_t>(r.sub_goals.size());
  publish(ch::extrinsicResult, r);
  log_->info("test '{}' on {}: {} after {} iterations, {} actions", runId(), r.scenario,
             success ? "solved" : "not solved", r.step, r.attempts);
  setState(process_status_t::DONE);
}

}  // namespace afford

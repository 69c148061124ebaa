#include "planner/node.hpp"

#include <algorithm>
#include <climits>

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
        "extrinsic phase: the SCENE that starts the test (once), then the scene of each action it decided, after "
        "the action (the goal scene is the eye's); goals phase: the SCENE that starts the run, then the scenes of "
        "the step after each decision (its action's, and one when objects appear), in step order")
      .in(Phase::Goals)
      .ignoreIf(idle)
      .refuse([this](const scene_t& s) {
        return s.cause == scene_t::CAUSE_START && step_ >= 0 ? "the run has begun already" : "";
      })
      .refuse([this](const scene_t& s) {
        return s.cause != scene_t::CAUSE_START && s.step <= step_
                   ? "the scene of step " + std::to_string(s.step) + " is in the past (now at " + std::to_string(step_) + ")"
                   : std::string();
      })
      .waitFor([this](const scene_t& s) {
        return s.cause == scene_t::CAUSE_START || (s.step == step_ + 1 && awaiting_ > 0);
      })
      .then([this](const scene_t& s) { onGoalScene(s); })
      .in(Phase::Extrinsic)
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
  takeGoalsAndJoin();
}

void PlannerNode::takeGoalsAndJoin() {
  const auto idle = [this](const auto&) { return !core_ || finished_; };
  takes(ch::goal,
        "goals phase: each GOAL once, in order, when the goal before it has ended (its GOAL_RESULT is out) and "
        "the step's scenes are in")
      .in({Phase::Intrinsic, Phase::Extrinsic})
      .refuse([](const goal_t&) { return "goals are set in the goals phase only"; })
      .in(Phase::Goals)
      .ignoreIf(idle)
      .refuse([this](const goal_t& g) {
        return g.id < next_goal_id_ ? "goal " + std::to_string(g.id) + " was pursued already" : std::string();
      })
      .waitFor([this](const goal_t& g) { return g.id == next_goal_id_ && !goal_ && step_ >= 0 && awaiting_ == 0; })
      .refuse([this](const goal_t& g) {
        return g.step != step_ ? "goal " + std::to_string(g.id) + " is for step " + std::to_string(g.step) +
                                     ", and the run is at step " + std::to_string(step_)
                               : std::string();
      })
      .then([this](const goal_t& g) { onGoal(g); });
  joins(object_, ch::focus, ch::prediction,
        "the object the current iteration scanned or attended: its FOCUS and the PREDICTION of its affordances, "
        "in either order, go to the planner once both have come");
}

void PlannerNode::onConfigured(const RunConfig& config) {
  core_.reset();
  if (config.phase == Phase::Extrinsic) {
    core_ = std::make_unique<Planner>(config.planner, goalValues(*config.scenario));
    core_->observe(observer_);
  } else if (config.phase == Phase::Goals) {
    PlannerConfig goal_planner = config.planner;
    goal_planner.kind = PlannerKind::Goal;  // its own goals are pursued by Algorithm 2; planner.kind is the tests'
    core_ = std::make_unique<Planner>(goal_planner);
    core_->observe(observer_);
  }
  goal_.reset();
  next_goal_id_ = 0;
  goal_actions_ = 0;
  actions_ = 0;
  awaiting_ = 0;
  acted_ = after_action_ = false;
  focus_serial_ = forward_serial_ = -1;
  object_x_ = object_y_ = -1;
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
      if (goals()) return decide(actionMessage(runId(), step_, seq_, r));
      waiting_scene_ = true;
      return publish(ch::decision, actionMessage(runId(), step_, seq_, r));
    case PlannerRequest::IterationDone:
      return goals() ? goalIterationDone() : endIteration();
  }
}

void PlannerNode::onFocus(const focus_t& f) {
  handled(f.step);
  focus_serial_ = f.serial;
  if (f.kind == focus_t::SCENE_SCAN || f.kind == focus_t::SCENE_OBJECT) return object_.first(f);
  if (f.kind == focus_t::GOAL_DIFF) return follow(core_->onDifferences(differencesOf(f)));
  follow(core_->onView(viewOf(f)));
}

void PlannerNode::onObject(const focus_t& f, const prediction_t& p) {
  object_x_ = f.x;
  object_y_ = f.y;
  if (goal_ && goal_->module == goal_t::EXPLORE) {  // motor babbling: the goal's action on the scanned object
    PlannerRequest r;
    r.action = goal_->action;
    r.object_x = f.x;
    r.object_y = f.y;
    return decide(actionMessage(runId(), step_, seq_, r));
  }
  follow(core_->onObject(viewOf(f), affordancesOf(p.affordance)));
}

void PlannerNode::onForward(const forward_prediction_t& m) {
  forward_serial_ = m.serial;
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
  extrinsic_result_t r{};
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

// ---- goals phase ----------------------------------------------------------------

namespace afford {

void PlannerNode::saveState(SnapshotWriter& w) {
  for (std::int64_t v : {step_, static_cast<std::int64_t>(seq_), scene_, static_cast<std::int64_t>(next_goal_id_), actions_,
                         focus_serial_, forward_serial_})
    w.i64(v);
  w.f64(object_x_);
  w.f64(object_y_);
}

void PlannerNode::loadState(SnapshotReader& r) {
  step_ = r.within("step", 0, config().steps);
  seq_ = static_cast<std::int32_t>(r.within("last request", 0, INT32_MAX));
  scene_ = r.within("last scene", -1, INT64_MAX);
  next_goal_id_ = static_cast<std::int32_t>(r.within("next goal", 0, INT32_MAX));
  actions_ = r.within("actions", 0, config().steps);
  focus_serial_ = r.within("last focus serial", -1, INT64_MAX);
  forward_serial_ = r.within("last forward prediction serial", -1, INT64_MAX);
  object_x_ = r.f64("object x");
  object_y_ = r.f64("object y");
  goal_.reset();
  awaiting_ = 0;
  acted_ = after_action_ = false;
}

int PlannerNode::scenesAfter(bool acted) const {
  const std::int64_t next = step_ + 1;
  const bool appear = next < config().steps && config().world.lateObjectsAt(next);
  return (acted ? 1 : 0) + (appear ? 1 : 0);
}

void PlannerNode::onGoalScene(const scene_t& s) {
  scene_ = s.serial;
  if (s.cause == scene_t::CAUSE_START) {
    step_ = 0;
    return;  // the first GOAL starts the run
  }
  if (--awaiting_ == 0) stepped();
}

void PlannerNode::onGoal(const goal_t& g) {
  goal_ = g;
  next_goal_id_ = g.id + 1;
  goal_actions_ = 0;
  after_action_ = false;
  handled(step_);
  if (g.module == goal_t::EXPLORE) {
    last_ = PlannerRequest{};
    last_.kind = PlannerRequest::ScanScene;
    object_.clear();
    return look(focus_t::SCENE_SCAN);
  }
  follow(core_->pursue(View{g.image, g.x, g.y}, g.object_x, g.object_y));
}

void PlannerNode::decide(decision_t d) {
  acted_ = d.acted;
  if (d.acted) {
    ++goal_actions_;
    ++actions_;
  }
  publish(ch::decision, d);
  awaiting_ = scenesAfter(d.acted);
  if (awaiting_ == 0) stepped();
}

void PlannerNode::stepped() {
  ++step_;
  handled(step_ - 1);
  if (goal_->module == goal_t::EXPLORE) return endGoal(false);
  if (!acted_) return endGoal(false);  // nothing to try for it: given up
  after_action_ = true;
  follow(core_->onActed());  // the reach test: a look at the goal place
}

void PlannerNode::goalIterationDone() {
  const bool after_action = after_action_;
  after_action_ = false;
  if (!core_->subGoalActive()) return endGoal(true);
  if (!after_action) {  // the object affords nothing to try: a pass
    decision_t d{};
    d.run_id = runId();
    d.step = step_;
    d.acted = false;
    d.action = decision_t::NONE;
    d.x = object_x_;
    d.y = object_y_;
    d.target_x = d.target_y = -1;
    d.motivation = d.threshold = 0;
    d.revisit = false;
    d.seq = seq_;
    return decide(d);
  }
  if (goal_actions_ >= goal_->budget || step_ >= config().steps) return endGoal(false);
  follow(core_->startIteration());  // the same goal, another step
}

void PlannerNode::endGoal(bool reached) {
  goal_result_t r{};
  r.run_id = runId();
  r.step = step_;
  r.id = goal_->id;
  r.module = goal_->module;
  r.reached = reached;
  const double distance = core_->lastReachDistance();  // -1: not looked at (an exploration)
  r.distance = goal_->module == goal_t::EXPLORE || distance < 0 ? -1.0 : std::min(distance, 1.0);
  r.actions = goal_actions_;
  r.planned = goal_->module != goal_t::EXPLORE && goal_actions_ > 0 && core_->lastActionPlanned();
  r.effects = actions_;
  r.focus_serial = focus_serial_;
  r.forward_serial = forward_serial_;
  r.seq = seq_;
  goal_.reset();
  publish(ch::goalResult, r);
  if (step_ >= config().steps) {
    finished_ = true;
    setState(process_status_t::DONE);
  }
}

}  // namespace afford

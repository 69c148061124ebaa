#include "planner/planner.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace afford {

double imageDistance(const std::vector<double>& predicted, const std::vector<std::uint8_t>& b) {
  if (predicted.size() != b.size() || b.empty()) return 1.0;
  double sum = 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const double d = predicted[i] - b[i] / 255.0;
    sum += d * d;
  }
  return std::sqrt(sum) / static_cast<double>(b.size());
}

double positionDistance(double px, double py, double qx, double qy, PositionMetric metric) {
  const double d = std::hypot(px - qx, py - qy);
  return metric == PositionMetric::HalfEuclidean ? d / 2.0 : d;
}

std::vector<GoalValue> goalValues(const Scenario& s) {
  std::vector<GoalValue> out;
  for (const ScenarioObject& o : s.objects) out.push_back({o.goal.x, o.goal.y, o.value});
  return out;
}

Planner::Planner(const PlannerConfig& config, std::vector<GoalValue> values)
    : config_(config), values_(std::move(values)) {}

double Planner::subGoalValue(double x, double y) const {
  const GoalValue* best = nullptr;
  for (const GoalValue& v : values_)
    if (!best || std::hypot(v.x - x, v.y - y) < std::hypot(best->x - x, best->y - y)) best = &v;
  return best ? best->value : 0.0;
}

PlannerRequest Planner::request(PlannerRequest::Kind kind, double x, double y) const {
  PlannerRequest r;
  r.kind = kind;
  r.x = x;
  r.y = y;
  return r;
}

PlannerRequest Planner::told(PlannerRequest r) const {
  if (observer_) observer_->requested(iteration(), r);
  return r;
}

PlannerCheck Planner::check(const ForwardPrediction& p) const {
  PlannerCheck c;
  c.action = p.action;
  c.what_distance = imageDistance(p.what, sub_goal_.image);
  c.what_ok = c.what_distance < config_.image_match;
  c.where_distance = positionDistance(p.where_x, p.where_y, sub_goal_.x, sub_goal_.y, config_.position_metric);
  c.where_ok = c.where_distance <= config_.position_match;
  return c;
}

void Planner::left(SubGoalExit why) const {
  if (observer_ && !records_.empty()) observer_->subGoalLeft(iteration(), records_.size() - 1, why);
}

PlannerRequest Planner::done() {
  wait_ = Wait::Nothing;
  if (active_ && !records_.empty()) {
    ++records_.back().iterations;
    ++iterations_on_sub_goal_;
  }
  if (observer_) observer_->iterationEnded(iteration(), records_);
  return request(PlannerRequest::IterationDone);
}

PlannerRequest Planner::startIteration() { return told(begin()); }
PlannerRequest Planner::onDifferences(const std::vector<Difference>& differences) {
  return told(differencesSeen(differences));
}
PlannerRequest Planner::onView(const View& v) { return told(viewed(v)); }
PlannerRequest Planner::onObject(const View& object, const std::array<double, kNumActions>& affordance) {
  return told(objectSeen(object, affordance));
}
PlannerRequest Planner::onForward(const std::vector<ForwardPrediction>& predictions,
                                  const std::optional<std::array<double, kNumActions>>& input_affordance) {
  return told(predicted(predictions, input_affordance));
}
PlannerRequest Planner::onActed() { return told(acted()); }

PlannerRequest Planner::pursue(const View& goal, double object_x, double object_y) {
  if (wait_ != Wait::Nothing) throw std::logic_error("Planner: an iteration is already under way");
  ++iterations_;
  queries_ = 0;
  pursuing_ = true;
  sub_goal_ = goal;
  goal_object_ = View{{}, object_x, object_y};
  continue_at_.reset();
  iterations_on_sub_goal_ = 0;
  active_ = true;
  reach_distance_ = -1;
  records_.assign(1, SubGoalRecord{goal.x, goal.y, 0, 0, 0, false});
  if (observer_) observer_->subGoalPicked(iteration(), sub_goal_);
  wait_ = Wait::SceneAtSubGoal;
  return told(request(PlannerRequest::LookAtSceneAt, goal.x, goal.y));
}

PlannerRequest Planner::attendGoalObject() {
  const View at = continue_at_ ? *continue_at_ : goal_object_;
  continue_at_.reset();
  best_guess_.reset();
  wait_ = Wait::Object;
  return request(PlannerRequest::AttendObject, at.x, at.y);
}

PlannerRequest Planner::begin() {
  if (wait_ != Wait::Nothing) throw std::logic_error("Planner: an iteration is already under way");
  ++iterations_;
  queries_ = 0;
  if (pursuing_) {
    if (!active_) throw std::logic_error("Planner: the goal is reached; pursue() another");
    return attendGoalObject();
  }
  const bool timed_out = iterations_on_sub_goal_ >= config_.subgoal_timeout;
  if (active_ && !timed_out && continue_at_) {  // a plan under way: the same object, where it should be now
    const View at = *continue_at_;
    continue_at_.reset();
    wait_ = Wait::Object;
    return request(PlannerRequest::AttendObject, at.x, at.y);
  }
  continue_at_.reset();
  if (config_.attention == Attention::TopDown) {
    if (!differences_known_) {
      wait_ = Wait::Differences;
      return request(PlannerRequest::LookAtDifferences);
    }
    if (active_ && timed_out) {  // too long on this one: not actionable until the differences are looked at again
      targets_[static_cast<std::size_t>(target_)].status = Status::NotActionable;
      active_ = false;
      left(SubGoalExit::Timeout);
    }
    return active_ ? attendCandidate() : nextTarget();
  }
  if (!active_ || timed_out) {  // Algorithm 2: select a non-achieved sub-goal
    if (active_) left(SubGoalExit::Timeout);
    wait_ = Wait::SubGoal;
    return request(PlannerRequest::LookAtGoal);
  }
  wait_ = Wait::Object;
  return request(PlannerRequest::ScanScene);
}

PlannerRequest Planner::differencesSeen(const std::vector<Difference>& differences) {
  if (wait_ != Wait::Differences) throw std::logic_error("Planner: differences it did not ask for");
  targets_.clear();
  objects_.clear();
  for (const Difference& d : differences)
    (d.in_goal ? targets_ : objects_).push_back({d.x, d.y, d.image, Status::Pending, {}});
  differences_known_ = true;
  active_ = false;
  if (targets_.empty()) {  // the goal shows nothing the scene does not: look again next iteration
    differences_known_ = false;
    return done();
  }
  return nextTarget();
}

PlannerRequest Planner::nextTarget() {
  for (std::size_t i = 0; i < targets_.size(); ++i) {
    if (targets_[i].status != Status::Pending) continue;  // inhibition of return
    target_ = static_cast<int>(i);
    sub_goal_ = {targets_[i].image, targets_[i].x, targets_[i].y};
    iterations_on_sub_goal_ = 0;
    records_.push_back({sub_goal_.x, sub_goal_.y, 0, 0, 0, false});
    if (observer_) observer_->subGoalPicked(iteration(), sub_goal_);
    wait_ = Wait::SceneAtSubGoal;
    return request(PlannerRequest::LookAtSceneAt, sub_goal_.x, sub_goal_.y);
  }
  // Every remembered sub-goal is done or not actionable: look at the differences again.
  differences_known_ = false;
  wait_ = Wait::Differences;
  return request(PlannerRequest::LookAtDifferences);
}

PlannerRequest Planner::attendCandidate() {
  Remembered& t = targets_[static_cast<std::size_t>(target_)];
  const auto at = [&](const Remembered& a, const Remembered& b) {
    return positionDistance(a.x, a.y, b.x, b.y, PositionMetric::Euclidean) <= config_.position_match;
  };
  // The object where the sub-goal is first (a colour to change); then objects
  // no other pending sub-goal waits for in place; then the ones it does (an
  // object taken from there would leave that sub-goal without its object);
  // within each, the most alike in shape, then memory order.
  int best = -1, best_rank = 0;
  double best_shape = 0;
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    const Remembered& o = objects_[i];
    if (o.status == Status::Done || std::count(t.tried.begin(), t.tried.end(), static_cast<int>(i))) continue;
    const bool wanted_elsewhere = std::any_of(targets_.begin(), targets_.end(), [&](const Remembered& other) {
      return &other != &t && other.status == Status::Pending && at(o, other);
    });
    const int rank = at(o, t) ? 0 : wanted_elsewhere ? 2 : 1;
    const double shape = silhouetteDistance(o.image, t.image);
    if (best < 0 || rank < best_rank || (rank == best_rank && shape < best_shape)) {
      best = static_cast<int>(i);
      best_rank = rank;
      best_shape = shape;
    }
  }
  if (best < 0) {  // no object left to try: not actionable
    t.status = Status::NotActionable;
    return leaveSubGoal(SubGoalExit::NotActionable);
  }
  candidate_ = best;
  t.tried.push_back(best);
  wait_ = Wait::Object;
  return request(PlannerRequest::AttendObject, objects_[static_cast<std::size_t>(best)].x,
                 objects_[static_cast<std::size_t>(best)].y);
}

PlannerRequest Planner::viewed(const View& v) {
  // GoalNotAchievedCheck: the scene at the sub-goal's place against the sub-goal.
  const auto reach = [&](bool after_action) {
    const double distance = imageDistance(sub_goal_.image, v.image);
    reach_distance_ = distance;
    active_ = distance >= config_.subgoal_match;
    if (observer_) observer_->reachChecked(iteration(), after_action, distance, !active_);
  };
  switch (wait_) {
    case Wait::SubGoal:
      sub_goal_ = v;
      iterations_on_sub_goal_ = 0;
      records_.push_back({v.x, v.y, 0, 0, 0, false});
      if (observer_) observer_->subGoalPicked(iteration(), sub_goal_);
      wait_ = Wait::SceneAtSubGoal;
      return request(PlannerRequest::LookAtSceneAt, v.x, v.y);
    case Wait::SceneAtSubGoal:
      reach(false);
      if (!active_) {
        records_.back().reached = true;
        if (target_ >= 0) targets_[static_cast<std::size_t>(target_)].status = Status::Done;
        return done();
      }
      if (pursuing_) return attendGoalObject();
      if (config_.attention == Attention::TopDown) return attendCandidate();
      wait_ = Wait::Object;
      return request(PlannerRequest::ScanScene);
    case Wait::SceneAfterAction:
      reach(true);
      // Goals phase: a move that was carried out left the object at the goal place (its silhouette is there).
      if (pursuing_ && active_ && takesPlace(config_.world, last_action_) && !continue_at_ &&
          silhouetteDistance(v.image, object_.image) == 0)
        goal_object_ = View{{}, sub_goal_.x, sub_goal_.y};
      if (!active_) {
        records_.back().reached = true;
        continue_at_.reset();
        if (target_ >= 0) {  // the sub-goal and the object that reached it: done, not looked at again
          targets_[static_cast<std::size_t>(target_)].status = Status::Done;
          objects_[static_cast<std::size_t>(candidate_)].status = Status::Done;
        }
      } else if (continue_at_ && target_ >= 0) {  // the plan goes on with this object, wherever it went
        Remembered& o = objects_[static_cast<std::size_t>(candidate_)];
        o.x = continue_at_->x;
        o.y = continue_at_->y;
      }
      return done();
    default:
      throw std::logic_error("Planner: a view it did not ask for");
  }
}

PlannerRequest Planner::forward(const std::vector<std::uint8_t>& image, double x, double y, std::vector<int> actions,
                                std::vector<int> prefix) {
  PlannerRequest r = request(PlannerRequest::Forward, sub_goal_.x, sub_goal_.y);
  r.object_x = x;
  r.object_y = y;
  r.image = image;
  r.actions = std::move(actions);
  r.prefix = std::move(prefix);
  ++queries_;
  wait_ = Wait::Forward;
  return r;
}

PlannerRequest Planner::objectSeen(const View& object, const std::array<double, kNumActions>& affordance) {
  if (wait_ != Wait::Object) throw std::logic_error("Planner: an object it did not ask for");
  object_ = object;
  affordance_ = affordance;
  if (observer_) observer_->objectTaken(iteration(), object, affordance);
  std::vector<int> actions;
  for (int a = 0; a < kNumActions; ++a)
    if (!config_.restrict_by_affordance || affordance[a] > config_.affordance_threshold) actions.push_back(a);
  if (actions.empty()) return done();  // nothing this object affords
  frontier_.clear();
  frontier_next_ = 0;
  querying_ = SearchNode{{}, object.image, object.x, object.y, {}};
  return forward(object.image, object.x, object.y, std::move(actions), {});
}

PlannerRequest Planner::predicted(const std::vector<ForwardPrediction>& predictions,
                                  const std::optional<std::array<double, kNumActions>>& input_affordance) {
  if (wait_ != Wait::Forward) throw std::logic_error("Planner: predictions it did not ask for");
  const SearchNode node = querying_;
  const bool imagined = !node.actions.empty();
  if (imagined && !input_affordance) throw std::logic_error("Planner: predictions for an imagined object without its affordances");
  // ActionPlanning: the first candidate whose predicted effect is the sub-goal;
  // breadth first, so the first plan found is a shortest one.
  const ForwardPrediction* plan = nullptr;
  std::vector<PlannerCheck> checks;  // for the observer: the ones after the plan too, not compared
  for (const ForwardPrediction& p : predictions) {
    // An imagined object is restricted by what it would afford (the first step by the PREDICTION).
    if (imagined && config_.restrict_by_affordance && (*input_affordance)[p.action] <= config_.affordance_threshold)
      continue;
    if (plan) {
      if (observer_) checks.push_back(check(p));
      continue;
    }
    ++records_.back().actions_checked;
    PlannerCheck c = check(p);
    c.checked = true;
    if (observer_) checks.push_back(c);
    // Goals phase, the best guess: nearest the goal, each distance in units of its threshold; not a move onto
    // the place the object stands on (it changes nothing).
    const bool stays = takesPlace(config_.world, p.action) &&
                       positionDistance(object_.x, object_.y, sub_goal_.x, sub_goal_.y, config_.position_metric) <=
                           config_.position_match;
    if (pursuing_ && !imagined && !stays) {
      const double score = c.what_distance / config_.image_match + c.where_distance / std::max(config_.position_match, 1e-9);
      if (!best_guess_ || score < best_score_) {
        best_guess_ = p;
        best_score_ = score;
      }
    }
    if (c.passes()) {
      plan = &p;
      continue;
    }
    if (static_cast<int>(node.actions.size()) + 1 < config_.max_depth) {
      SearchNode child{node.actions, quantiseImage(p.what), std::clamp(p.where_x, 0.0, 1.0),
                       std::clamp(p.where_y, 0.0, 1.0), imagined ? node.first : p};
      child.actions.push_back(p.action);
      frontier_.push_back(std::move(child));
    }
  }
  if (observer_) observer_->predictionsChecked(iteration(), node.actions, checks);
  if (plan) return actOnPlan(imagined ? node.first : *plan, node.actions.size() + 1);
  if (frontier_next_ < frontier_.size() && queries_ < config_.max_queries) {
    querying_ = frontier_[frontier_next_++];
    std::vector<int> all(kNumActions);
    for (int a = 0; a < kNumActions; ++a) all[static_cast<std::size_t>(a)] = a;
    return forward(querying_.image, querying_.x, querying_.y, std::move(all), querying_.actions);
  }
  if (pursuing_ && best_guess_) {  // goals phase: no plan; the forward models' best guess is tried
    const ForwardPrediction guess = *best_guess_;
    best_guess_.reset();
    PlannerRequest r = act(guess);
    planned_ = false;
    return r;
  }
  return done();
}

PlannerRequest Planner::actOnPlan(const ForwardPrediction& first, std::size_t length) {
  planned_ = true;
  // More to do after this action: next iteration, the object where the first action should leave it.
  if (length > 1) continue_at_ = View{{}, std::clamp(first.where_x, 0.0, 1.0), std::clamp(first.where_y, 0.0, 1.0)};
  return config_.kind == PlannerKind::Utility ? weighUtility(first) : act(first);
}

PlannerRequest Planner::act(const ForwardPrediction& p) {
  const bool place = takesPlace(config_.world, p.action);
  PlannerRequest r = request(PlannerRequest::Act, place ? sub_goal_.x : -1.0, place ? sub_goal_.y : -1.0);
  r.action = p.action;
  r.object_x = object_.x;
  r.object_y = object_.y;
  last_action_ = p.action;
  ++attempts_;
  ++records_.back().actions_taken;
  wait_ = Wait::Acted;
  return r;
}

PlannerRequest Planner::weighUtility(const ForwardPrediction& p) {
  // Equation 3: U = affordance x value of the sub-goal.
  const double utility = affordance_[p.action] * subGoalValue(sub_goal_.x, sub_goal_.y);
  const double potential = potential_utility_;
  if (evaluating()) {  // raise the estimate of the attainable utility
    if (utility >= potential) potential_utility_ += config_.raise_leak * (utility - potential);
    return leaveSubGoal(SubGoalExit::Weighed);
  }
  // Acting: lower the estimate for each chosen action, whether or not its
  // utility reaches the estimate (docs/model.md says why), and act if it does.
  potential_utility_ += config_.lower_leak * (0.0 - potential);
  if (utility >= potential) return act(p);
  return leaveSubGoal(SubGoalExit::Weighed);
}

PlannerRequest Planner::leaveSubGoal(SubGoalExit why) {
  left(why);
  active_ = false;  // Algorithm 3: another sub-goal next iteration
  ++records_.back().iterations;
  return done();
}

PlannerRequest Planner::acted() {
  if (wait_ != Wait::Acted) throw std::logic_error("Planner: an action it did not ask for");
  if (config_.kind == PlannerKind::Utility) return leaveSubGoal(SubGoalExit::Weighed);  // Algorithm 3: no check of the sub-goal
  wait_ = Wait::SceneAfterAction;
  return request(PlannerRequest::LookAtSceneAt, sub_goal_.x, sub_goal_.y);
}

}  // namespace afford

#include "planner/planner.hpp"

#include <cmath>
#include <stdexcept>

namespace afford {

double imageDistance(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  if (a.size() != b.size() || a.empty()) return 1.0;
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = (static_cast<int>(a[i]) - static_cast<int>(b[i])) / 255.0;
    sum += d * d;
  }
  return std::sqrt(sum) / static_cast<double>(a.size());
}

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

PlannerRequest Planner::done() {
  wait_ = Wait::Nothing;
  if (active_ && !records_.empty()) {
    ++records_.back().iterations;
    ++iterations_on_sub_goal_;
  }
  return request(PlannerRequest::IterationDone);
}

PlannerRequest Planner::startIteration() {
  if (wait_ != Wait::Nothing) throw std::logic_error("Planner: an iteration is already under way");
  ++iterations_;
  const bool timed_out = iterations_on_sub_goal_ >= config_.subgoal_timeout;
  if (!active_ || timed_out) {  // Algorithm 2: select a non-achieved sub-goal
    wait_ = Wait::SubGoal;
    return request(PlannerRequest::LookAtGoal);
  }
  wait_ = Wait::Object;
  return request(PlannerRequest::ScanScene);
}

PlannerRequest Planner::onView(const View& v) {
  switch (wait_) {
    case Wait::SubGoal:
      sub_goal_ = v;
      iterations_on_sub_goal_ = 0;
      records_.push_back({v.x, v.y, 0, 0, 0, false});
      wait_ = Wait::SceneAtSubGoal;
      return request(PlannerRequest::LookAtSceneAt, v.x, v.y);
    case Wait::SceneAtSubGoal:
      // GoalNotAchievedCheck
      active_ = imageDistance(sub_goal_.image, v.image) >= config_.subgoal_match;
      if (!active_) {
        records_.back().reached = true;
        return done();
      }
      wait_ = Wait::Object;
      return request(PlannerRequest::ScanScene);
    case Wait::SceneAfterAction:
      active_ = imageDistance(sub_goal_.image, v.image) >= config_.subgoal_match;
      if (!active_) records_.back().reached = true;
      return done();
    default:
      throw std::logic_error("Planner: a view it did not ask for");
  }
}

PlannerRequest Planner::onObject(const View& object, const std::array<double, kNumActions>& affordance) {
  if (wait_ != Wait::Object) throw std::logic_error("Planner: an object it did not ask for");
  object_ = object;
  affordance_ = affordance;
  PlannerRequest r = request(PlannerRequest::Forward, sub_goal_.x, sub_goal_.y);
  r.object_x = object.x;
  r.object_y = object.y;
  for (int a = 0; a < kNumActions; ++a)
    if (!config_.restrict_by_affordance || affordance[a] > config_.affordance_threshold) r.actions.push_back(a);
  if (r.actions.empty()) return done();  // nothing this object affords
  wait_ = Wait::Forward;
  return r;
}

PlannerRequest Planner::onForward(const std::vector<ForwardPrediction>& predictions) {
  if (wait_ != Wait::Forward) throw std::logic_error("Planner: predictions it did not ask for");
  // ActionPlanning: the first candidate whose predicted effect is the sub-goal.
  for (const ForwardPrediction& p : predictions) {
    ++records_.back().actions_checked;
    const bool image_ok = imageDistance(p.what, sub_goal_.image) < config_.image_match;
    const bool place_ok = positionDistance(p.where_x, p.where_y, sub_goal_.x, sub_goal_.y, config_.position_metric) <=
                          config_.position_match;
    if (image_ok && place_ok) return config_.kind == PlannerKind::Utility ? weighUtility(p) : act(p);
  }
  return done();
}

PlannerRequest Planner::act(const ForwardPrediction& p) {
  PlannerRequest r = request(PlannerRequest::Act, p.action == kMove ? sub_goal_.x : -1.0,
                             p.action == kMove ? sub_goal_.y : -1.0);
  r.action = p.action;
  r.object_x = object_.x;
  r.object_y = object_.y;
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
    return leaveSubGoal();
  }
  // Acting: lower the estimate for each chosen action, whether or not its
  // utility reaches the estimate (docs/model.md says why), and act if it does.
  potential_utility_ += config_.lower_leak * (0.0 - potential);
  if (utility >= potential) return act(p);
  return leaveSubGoal();
}

PlannerRequest Planner::leaveSubGoal() {
  active_ = false;  // Algorithm 3: another sub-goal next iteration
  ++records_.back().iterations;
  return done();
}

PlannerRequest Planner::onActed() {
  if (wait_ != Wait::Acted) throw std::logic_error("Planner: an action it did not ask for");
  if (config_.kind == PlannerKind::Utility) return leaveSubGoal();  // Algorithm 3: no check of the sub-goal
  wait_ = Wait::SceneAfterAction;
  return request(PlannerRequest::LookAtSceneAt, sub_goal_.x, sub_goal_.y);
}

}  // namespace afford

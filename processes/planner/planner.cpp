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

double positionDistance(double px, double py, double qx, double qy) {
  return std::hypot(px - qx, py - qy) / 2.0;
}

GoalPlanner::GoalPlanner(const PlannerConfig& config) : config_(config) {}

PlannerRequest GoalPlanner::request(PlannerRequest::Kind kind, double x, double y) const {
  PlannerRequest r;
  r.kind = kind;
  r.x = x;
  r.y = y;
  return r;
}

PlannerRequest GoalPlanner::done() {
  wait_ = Wait::Nothing;
  if (active_ && !records_.empty()) {
    ++records_.back().iterations;
    ++iterations_on_sub_goal_;
  }
  return request(PlannerRequest::IterationDone);
}

PlannerRequest GoalPlanner::startIteration() {
  if (wait_ != Wait::Nothing) throw std::logic_error("GoalPlanner: an iteration is already under way");
  const bool timed_out = iterations_on_sub_goal_ >= config_.subgoal_timeout;
  if (!active_ || timed_out) {  // Algorithm 2: select a non-achieved sub-goal
    wait_ = Wait::SubGoal;
    return request(PlannerRequest::LookAtGoal);
  }
  wait_ = Wait::Object;
  return request(PlannerRequest::ScanScene);
}

PlannerRequest GoalPlanner::onView(const View& v) {
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
      throw std::logic_error("GoalPlanner: a view it did not ask for");
  }
}

PlannerRequest GoalPlanner::onObject(const View& object, const std::array<double, kNumActions>& affordance) {
  if (wait_ != Wait::Object) throw std::logic_error("GoalPlanner: an object it did not ask for");
  object_ = object;
  PlannerRequest r = request(PlannerRequest::Forward, sub_goal_.x, sub_goal_.y);
  r.object_x = object.x;
  r.object_y = object.y;
  for (int a = 0; a < kNumActions; ++a)
    if (!config_.restrict_by_affordance || affordance[a] > config_.affordance_threshold) r.actions.push_back(a);
  if (r.actions.empty()) return done();  // nothing this object affords
  wait_ = Wait::Forward;
  return r;
}

PlannerRequest GoalPlanner::onForward(const std::vector<ForwardPrediction>& predictions) {
  if (wait_ != Wait::Forward) throw std::logic_error("GoalPlanner: predictions it did not ask for");
  // ActionPlanning: the first candidate whose predicted effect is the sub-goal.
  for (const ForwardPrediction& p : predictions) {
    ++records_.back().actions_checked;
    const bool image_ok = imageDistance(p.what, sub_goal_.image) < config_.image_match;
    const bool place_ok = positionDistance(p.where_x, p.where_y, sub_goal_.x, sub_goal_.y) < config_.position_match;
    if (image_ok && place_ok) {
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
  }
  return done();
}

PlannerRequest GoalPlanner::onActed() {
  if (wait_ != Wait::Acted) throw std::logic_error("GoalPlanner: an action it did not ask for");
  wait_ = Wait::SceneAfterAction;
  return request(PlannerRequest::LookAtSceneAt, sub_goal_.x, sub_goal_.y);
}

}  // namespace afford

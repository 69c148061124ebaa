// Where the planner's messages meet its core's structs: one converter per
// pair, so a field added to either is added here once. (The core,
// planner.hpp, holds no LCM type.)
//   FOCUS                      -> View                     a look's image and place
//   FOCUS (GOAL_DIFF)          -> Difference               where goal and scene differ
//   PREDICTION                 -> affordances              of the object in focus
//   FORWARD_PREDICTION         -> ForwardPrediction        each action's predicted effect
//   PlannerRequest (Forward)   -> FORWARD_QUERY
//   PlannerRequest (Act)       -> DECISION
//   SubGoalRecord              -> EXTRINSIC_RESULT sub_goal_t
#pragma once
#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include "afford/decision_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/prediction_t.hpp"
#include "afford/sub_goal_t.hpp"
#include "planner/planner.hpp"

namespace afford {

inline View viewOf(const focus_t& f) { return {f.image, f.x, f.y}; }

inline std::vector<Difference> differencesOf(const focus_t& f) {
  std::vector<Difference> diffs;
  for (int i = 0; i < f.n_diffs; ++i)
    diffs.push_back({f.diff_x[i], f.diff_y[i], f.diff_in[i] == focus_t::DIFF_GOAL, f.diff_image[i]});
  return diffs;
}

inline std::array<double, kNumActions> affordancesOf(const std::vector<double>& values) {
  std::array<double, kNumActions> out{};
  std::copy_n(values.begin(), std::min<std::size_t>(values.size(), kNumActions), out.begin());
  return out;
}

inline std::vector<ForwardPrediction> forwardPredictionsOf(const forward_prediction_t& m) {
  std::vector<ForwardPrediction> preds;
  for (int i = 0; i < m.n_actions; ++i)
    preds.push_back({m.actions[i], std::vector<double>(m.what[i].begin(), m.what[i].end()), m.where_x[i], m.where_y[i]});
  return preds;
}

inline forward_query_t forwardQueryMessage(const std::string& run_id, std::int64_t step, std::int32_t seq,
                                           const PlannerRequest& r) {
  forward_query_t q;
  q.run_id = run_id;
  q.step = step;
  q.seq = seq;
  q.x = r.object_x;
  q.y = r.object_y;
  q.target_x = r.x;
  q.target_y = r.y;
  q.image = r.image;
  q.size = static_cast<int32_t>(q.image.size());
  for (int a : r.actions) q.actions.push_back(static_cast<int8_t>(a));
  q.n_actions = static_cast<int32_t>(q.actions.size());
  for (int a : r.prefix) q.prefix.push_back(static_cast<int8_t>(a));
  q.n_prefix = static_cast<int8_t>(q.prefix.size());
  return q;
}

inline decision_t actionMessage(const std::string& run_id, std::int64_t step, std::int32_t seq, const PlannerRequest& r) {
  decision_t d;
  d.run_id = run_id;
  d.step = step;
  d.seq = seq;
  d.acted = true;
  d.action = static_cast<int8_t>(r.action);
  d.x = r.object_x;
  d.y = r.object_y;
  d.target_x = r.x;
  d.target_y = r.y;
  d.revisit = false;
  d.motivation = d.threshold = 0.0;  // the planner decides by its goal, not by a motivation
  return d;
}

inline sub_goal_t subGoalMessage(const SubGoalRecord& g) {
  return {g.x, g.y, g.iterations, g.actions_checked, g.actions_taken, g.reached};
}

}  // namespace afford

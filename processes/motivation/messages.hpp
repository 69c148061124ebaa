// Where the motivation's messages meet its core's structs: one converter per
// pair, both directions side by side, so a field added to either is added here
// once. (The core, component.hpp, holds no LCM type.)
//   PREDICTION -> Percept     what the motivation perceives of a step
//   Decision   -> DECISION    what it decided, on the object it was told of
//   FOCUS      -> Seen        an object the eye showed (goals phase)
//   EFFECT     -> SeenEffect  an action's effect, with the object as it was before
//   FORWARD_PREDICTION -> Imagined   what the forward models predict for an object
//   GOAL_RESULT -> GoalAttempt what became of a goal
//   Goal       -> GOAL        the goal set next
#pragma once
#include <algorithm>
#include <cmath>
#include <string>

#include "afford/decision_t.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/goal_result_t.hpp"
#include "afford/goal_t.hpp"
#include "afford/image.hpp"
#include "afford/prediction_t.hpp"
#include "motivation/component.hpp"
#include "motivation/goals.hpp"

namespace afford {

inline Percept perceptOf(const prediction_t& m) {
  Percept p;
  p.step = m.step;
  std::copy(m.affordance.begin(), m.affordance.end(), p.affordance.begin());
  std::copy(m.learning_progress.begin(), m.learning_progress.end(), p.learning_progress.begin());
  if (m.n_tried == kNumActions) {  // the predictors keep a memory: which look, and what was tried on it
    p.look = m.look;
    p.tried_ago.emplace();
    std::copy(m.tried_ago.begin(), m.tried_ago.end(), p.tried_ago->begin());
  }
  if (m.n_trained == 1 && m.trained[0].step == m.step - 1)
    p.last_change = std::abs(m.trained[0].affordance_after - m.trained[0].affordance_before);
  return p;
}

inline decision_t decisionMessage(const std::string& run_id, const prediction_t& m, const Decision& d) {
  decision_t out;
  out.run_id = run_id;
  out.step = m.step;
  out.acted = d.act;
  out.action = static_cast<int8_t>(d.act ? d.action : decision_t::NONE);
  out.x = m.x;  // on the object in focus
  out.y = m.y;
  out.target_x = out.target_y = -1.0;  // a move's target is the environment's draw
  out.seq = 0;                         // (the planner's requests: none here)
  out.motivation = d.motivation;
  out.threshold = d.threshold;
  out.revisit = d.revisit;
  return out;
}

inline Seen seenOf(const focus_t& f) { return {f.image, f.x, f.y}; }

// The object before is the step's object FOCUS: GoalInputs fills it in when it gives the effect to the chooser.
inline SeenEffect seenEffectOf(const effect_t& m) {
  SeenEffect e;
  e.step = m.step;
  e.action = m.action;
  e.after = {m.image, m.after_x, m.after_y};
  e.target_x = m.target_x;
  e.target_y = m.target_y;
  e.affordance = m.affordance;
  return e;
}

// The outcomes a FORWARD_PREDICTION about a seen object (not an imagined one) predicts for it (the object's image:
// GoalInputs fills it in from the step's object FOCUS).
inline std::vector<Imagined> imaginedOf(const forward_prediction_t& m) {
  std::vector<Imagined> out;
  if (m.n_input != 0) return out;  // a multi-step search's imagined object
  for (int i = 0; i < m.n_actions; ++i)
    out.push_back({m.step, m.actions[i], {},
                   quantiseImage(std::vector<double>(m.what[i].begin(), m.what[i].end())), m.where_x[i], m.where_y[i]});
  return out;
}

inline GoalAttempt attemptOf(const goal_result_t& m) {
  return {m.id, static_cast<GoalModule>(m.module), m.reached != 0, m.distance, m.actions};
}

inline goal_t goalMessage(const std::string& run_id, std::int64_t step, std::int32_t id, const Goal& g, int budget) {
  goal_t out;
  out.run_id = run_id;
  out.step = step;
  out.id = id;
  out.module = static_cast<int8_t>(g.module);
  out.object_x = g.object_x;
  out.object_y = g.object_y;
  out.x = g.x;
  out.y = g.y;
  out.image = g.image;
  out.size = static_cast<int32_t>(out.image.size());
  out.action = static_cast<int8_t>(g.module == GoalModule::Explore ? g.action : -1);
  out.budget = budget;
  return out;
}

}  // namespace afford

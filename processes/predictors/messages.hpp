// Where the predictors' messages meet their core's structs: one converter per
// pair, both directions side by side, so a field added to either is added here
// once. (The core, predictors.hpp, holds no LCM type.)
//   FOCUS + EFFECT   -> Experience   what one action on the focused object did
//   TrainingReport   -> trained_t    the update it caused (carried by the next PREDICTION)
//   Prediction       -> PREDICTION   what the focused object affords, and how learning goes
#pragma once
#include <optional>
#include <string>

#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/prediction_t.hpp"
#include "afford/trained_t.hpp"
#include "predictors/predictors.hpp"

namespace afford {

inline Experience experienceOf(const focus_t& before, const effect_t& m) {
  Experience e;
  e.action = m.action;
  e.before_image = before.image;
  e.before_x = before.x;
  e.before_y = before.y;
  e.target_x = m.target_x;
  e.target_y = m.target_y;
  e.affordance = m.affordance;
  e.after_image = m.image;
  e.after_x = m.after_x;
  e.after_y = m.after_y;
  return e;
}

inline trained_t trainedMessage(const std::string& run_id, std::int64_t step, const TrainingReport& r) {
  trained_t t;
  t.run_id = run_id;
  t.step = step;
  t.action = static_cast<int8_t>(r.action);
  t.affordance = r.affordance;
  t.affordance_before = r.affordance_before;
  t.affordance_after = r.affordance_after;
  t.learning_progress = r.learning_progress;
  t.effect_trained = r.effect_trained;
  return t;
}

// `focus`: the FOCUS predicted on; `trained`: the update since the last prediction, if any.
inline prediction_t predictionMessage(const std::string& run_id, const focus_t& focus, const Prediction& p,
                                      const std::optional<trained_t>& trained) {
  prediction_t out;
  out.run_id = run_id;
  out.step = focus.step;
  out.x = focus.x;
  out.y = focus.y;
  out.n_actions = kNumActions;
  out.affordance.assign(p.affordance.begin(), p.affordance.end());
  out.learning_progress.assign(p.learning_progress.begin(), p.learning_progress.end());
  out.look = p.remembered ? p.look : -1;
  if (p.remembered) out.tried_ago.assign(p.tried_ago.begin(), p.tried_ago.end());
  out.n_tried = static_cast<int8_t>(out.tried_ago.size());
  if (trained) out.trained.push_back(*trained);
  out.n_trained = static_cast<int8_t>(out.trained.size());
  return out;
}

}  // namespace afford

// Where the motivation's messages meet its core's structs: one converter per
// pair, both directions side by side, so a field added to either is added here
// once. (The core, component.hpp, holds no LCM type.)
//   PREDICTION -> Percept     what the motivation perceives of a step
//   Decision   -> DECISION    what it decided, on the object it was told of
#pragma once
#include <algorithm>
#include <cmath>
#include <string>

#include "afford/decision_t.hpp"
#include "afford/prediction_t.hpp"
#include "motivation/component.hpp"

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
  out.motivation = d.motivation;
  out.threshold = d.threshold;
  out.revisit = d.revisit;
  return out;
}

}  // namespace afford

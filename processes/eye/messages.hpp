// Where the eye's messages meet its core's structs: one converter per pair, so
// a field added to either is added here once. (The core, eye.hpp, holds no LCM
// type.)
//   Focus              -> FOCUS    what the eye looks at (focusMessage)
//   SCENE + Effect     -> EFFECT   what the action of the step before did
#pragma once
#include <string>

#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/scene_t.hpp"
#include "eye/eye.hpp"

namespace afford {

inline focus_t focusMessage(const std::string& run_id, std::int64_t step, const Focus& f, int8_t kind, int32_t seq,
                            int side) {
  focus_t m;
  m.run_id = run_id;
  m.step = step;
  m.kind = kind;
  m.seq = seq;
  m.x = f.x;
  m.y = f.y;
  m.side = side;
  m.image = f.image;
  m.size = static_cast<int32_t>(f.image.size());
  m.n_diffs = 0;
  return m;
}

// `s`: the scene the action caused (its step is the one after the action's).
inline effect_t effectMessage(const std::string& run_id, const scene_t& s, const Effect& e, int side) {
  effect_t m;
  m.run_id = run_id;
  m.step = s.step - 1;
  m.action = s.action;
  m.target_x = s.action_target_x;
  m.target_y = s.action_target_y;
  m.before_x = e.before.x;
  m.before_y = e.before.y;
  m.after_x = e.after.x;
  m.after_y = e.after.y;
  m.image_change = e.image_change;
  m.position_change = e.position_change;
  m.affordance = e.affordance;
  m.side = side;
  m.image = e.after.image;
  m.size = static_cast<int32_t>(m.image.size());
  return m;
}

}  // namespace afford

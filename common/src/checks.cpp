#include "afford/checks.hpp"

#include <cmath>
#include <initializer_list>
#include <sstream>

#include "afford/actions.hpp"

namespace afford {

std::string checkFinite(const char* field, double v) {
  return std::isfinite(v) ? "" : std::string("field ") + field + " is not finite";
}
std::string checkRange(const char* field, double v, double lo, double hi) {
  if (!std::isfinite(v)) return checkFinite(field, v);
  if (v < lo || v > hi) {
    std::ostringstream s;
    s << "field " << field << " = " << v << " is out of range [" << lo << ", " << hi << "]";
    return s.str();
  }
  return "";
}
std::string checkSize(const char* field, long got, long want) {
  if (got == want) return "";
  return std::string("field ") + field + " has size " + std::to_string(got) + ", expected " + std::to_string(want);
}

namespace {

std::string first(std::initializer_list<std::string> reasons) {
  for (const auto& r : reasons)
    if (!r.empty()) return r;
  return "";
}
std::string checkStep(std::int64_t step, const RunConfig& c) {
  if (step < 0 || step > c.steps)
    return "field step = " + std::to_string(step) + " is out of range [0, " + std::to_string(c.steps) + "]";
  return "";
}
std::string checkAction(const char* field, int action, bool required) {
  if (!required && action == -1) return "";
  if (!validAction(action)) return std::string("field ") + field + ": action id " + std::to_string(action) + " is out of range [0, 3]";
  return "";
}
// A move target: a position, or -1 for "none / draw one".
std::string checkTarget(const char* field, double v) { return v == -1.0 ? "" : checkRange(field, v, 0.0, 1.0); }
long focusSize(const RunConfig& c) { return 3L * c.eye.focus_side * c.eye.focus_side; }
std::string checkKind(int kind) {
  return kind == focus_t::SCENE_SCAN || kind == focus_t::GOAL_SCAN || kind == focus_t::SCENE_AT
             ? ""
             : "field kind = " + std::to_string(kind) + " is unknown";
}

}  // namespace

std::string checkMessage(const scene_t& m, const RunConfig& c) {
  return first({checkStep(m.step, c),
                checkSize("width", m.width, c.world.size_px), checkSize("height", m.height, c.world.size_px),
                m.cause == scene_t::CAUSE_START || m.cause == scene_t::CAUSE_ACTION ||
                        m.cause == scene_t::CAUSE_OBJECTS_APPEARED || m.cause == scene_t::CAUSE_GOAL
                    ? ""
                    : "field cause = " + std::to_string(m.cause) + " is unknown",
                checkAction("action", m.action, m.cause == scene_t::CAUSE_ACTION),
                checkTarget("action_target_x", m.action_target_x), checkTarget("action_target_y", m.action_target_y),
                m.goal_distance == -1.0 ? "" : checkRange("goal_distance", m.goal_distance, 0.0, 1.0),
                m.goal_utility == -1.0 ? "" : checkRange("goal_utility", m.goal_utility, 0.0, 1e12),
                m.encoding == scene_t::ENCODING_ZLIB_RGB8 ? "" : "field encoding = " + std::to_string(m.encoding) + " is unknown"});
}

std::string checkMessage(const focus_t& m, const RunConfig& c) {
  return first({checkStep(m.step, c), checkKind(m.kind), checkSize("side", m.side, c.eye.focus_side),
                checkSize("size", m.size, focusSize(c)),
                checkRange("x", m.x, 0.0, 1.0), checkRange("y", m.y, 0.0, 1.0)});
}

std::string checkMessage(const prediction_t& m, const RunConfig& c) {
  if (auto why = first({checkStep(m.step, c), checkSize("n_actions", m.n_actions, kNumActions),
                        checkRange("x", m.x, 0.0, 1.0), checkRange("y", m.y, 0.0, 1.0)});
      !why.empty())
    return why;
  for (int a = 0; a < kNumActions; ++a) {
    const std::string fa = "affordance[" + std::to_string(a) + "]", fl = "learning_progress[" + std::to_string(a) + "]";
    if (auto why = first({checkRange(fa.c_str(), m.affordance[a], 0.0, 1.0), checkFinite(fl.c_str(), m.learning_progress[a])});
        !why.empty())
      return why;
  }
  if (m.n_trained < 0 || m.n_trained > 1) return "field n_trained = " + std::to_string(m.n_trained) + " is out of range [0, 1]";
  for (const auto& t : m.trained)
    if (auto why = checkMessage(t, c); !why.empty()) return "trained[0]: " + why;
  return "";
}

std::string checkMessage(const decision_t& m, const RunConfig& c) {
  return first({checkStep(m.step, c), checkAction("action", m.action, m.acted),
                m.acted || m.action == decision_t::NONE ? "" : "field action must be -1 when acted is false",
                checkRange("x", m.x, 0.0, 1.0), checkRange("y", m.y, 0.0, 1.0), checkTarget("target_x", m.target_x),
                checkTarget("target_y", m.target_y), checkFinite("motivation", m.motivation),
                checkFinite("threshold", m.threshold)});
}

std::string checkMessage(const effect_t& m, const RunConfig& c) {
  return first({checkStep(m.step, c), checkAction("action", m.action, true), checkSize("side", m.side, c.eye.focus_side),
                checkSize("size", m.size, focusSize(c)), checkTarget("target_x", m.target_x),
                checkTarget("target_y", m.target_y), checkRange("before_x", m.before_x, 0.0, 1.0),
                checkRange("before_y", m.before_y, 0.0, 1.0), checkRange("after_x", m.after_x, 0.0, 1.0),
                checkRange("after_y", m.after_y, 0.0, 1.0), checkRange("image_change", m.image_change, 0.0, 1.0),
                checkRange("position_change", m.position_change, 0.0, 1.0)});
}

std::string checkMessage(const trained_t& m, const RunConfig& c) {
  return first({checkStep(m.step, c), checkAction("action", m.action, true),
                checkRange("affordance_before", m.affordance_before, 0.0, 1.0),
                checkRange("affordance_after", m.affordance_after, 0.0, 1.0),
                checkFinite("learning_progress", m.learning_progress)});
}

std::string checkMessage(const object_probe_t& m, const RunConfig& c) {
  return first({m.n_objects >= 1 && m.n_objects <= 1000 ? "" : "field n_objects = " + std::to_string(m.n_objects) + " is out of range [1, 1000]",
                checkSize("size", m.size, focusSize(c))});
}

std::string checkMessage(const look_t& m, const RunConfig& c) {
  return first({checkStep(m.step, c), checkKind(m.kind), std::string(m.seq >= 0 ? "" : "field seq is negative"),
                m.kind != focus_t::SCENE_AT ? "" : checkRange("x", m.x, 0.0, 1.0),
                m.kind != focus_t::SCENE_AT ? "" : checkRange("y", m.y, 0.0, 1.0)});
}

std::string checkMessage(const forward_query_t& m, const RunConfig& c) {
  if (auto why = first({checkStep(m.step, c), checkSize("size", m.size, focusSize(c)), checkRange("x", m.x, 0.0, 1.0),
                        checkRange("y", m.y, 0.0, 1.0), checkTarget("target_x", m.target_x),
                        checkTarget("target_y", m.target_y),
                        m.n_actions >= 0 && m.n_actions <= kNumActions ? "" : "field n_actions is out of range [0, 4]"});
      !why.empty())
    return why;
  for (int a : m.actions)
    if (auto why = checkAction("actions", a, true); !why.empty()) return why;
  return "";
}

std::string checkMessage(const forward_prediction_t& m, const RunConfig& c) {
  if (auto why = first({checkStep(m.step, c), checkSize("size", m.size, focusSize(c)),
                        m.n_actions >= 0 && m.n_actions <= kNumActions ? "" : "field n_actions is out of range [0, 4]"});
      !why.empty())
    return why;
  for (int i = 0; i < m.n_actions; ++i) {
    if (auto why = first({checkAction("actions", m.actions[i], true), checkFinite("where_x", m.where_x[i]),
                          checkFinite("where_y", m.where_y[i])});
        !why.empty())
      return why;
    for (float v : m.what[i])
      if (!(v >= 0.0f && v <= 1.0f)) return "field what holds a value outside [0, 1]";
  }
  return "";
}

}  // namespace afford

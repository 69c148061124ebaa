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
std::string checkInt(const char* field, std::int64_t v, std::int64_t lo, std::int64_t hi) {
  if (v >= lo && v <= hi) return "";
  return std::string("field ") + field + " = " + std::to_string(v) + " is out of range [" + std::to_string(lo) + ", " +
         std::to_string(hi) + "]";
}
// A step of the run: [0, steps] with the run's configuration, else not negative.
std::string checkStep(std::int64_t step, const BoundsContext& c) {
  return checkInt("step", step, 0, c.run ? c.run->steps : INT64_MAX);
}
std::string checkSerial(std::int64_t serial) { return checkInt("serial", serial, 0, INT64_MAX); }
std::string checkAction(const char* field, int action, bool required) {
  if (!required && action == -1) return "";
  if (!validAction(action)) return std::string("field ") + field + ": action id " + std::to_string(action) + " is out of range [0, 3]";
  return "";
}
// A move target: a position, or -1 for "none / draw one".
std::string checkTarget(const char* field, double v) { return v == -1.0 ? "" : checkRange(field, v, 0.0, 1.0); }
// The focus image size of the run (3 x side^2), or any the protocol accepts.
std::string checkFocus(const char* side_field, int side, const char* size_field, long size, const BoundsContext& c) {
  if (c.run)
    return first({checkSize(side_field, side, c.run->eye.focus_side),
                  checkSize(size_field, size, 3L * c.run->eye.focus_side * c.run->eye.focus_side)});
  // The side first: 3 * side * side of any int would overflow.
  if (auto why = checkInt(side_field, side, 1, c.protocol->limits.focus_side); !why.empty()) return why;
  return checkSize(size_field, size, 3L * side * side);
}
std::string checkFocusSize(const char* field, long size, const BoundsContext& c) {
  if (c.run) return checkSize(field, size, 3L * c.run->eye.focus_side * c.run->eye.focus_side);
  return checkInt(field, size, 3, 3L * c.protocol->limits.focus_side * c.protocol->limits.focus_side);
}
std::string checkKind(int kind) {
  return kind == focus_t::SCENE_SCAN || kind == focus_t::GOAL_SCAN || kind == focus_t::SCENE_AT ||
                 kind == focus_t::GOAL_DIFF || kind == focus_t::SCENE_OBJECT
             ? ""
             : "field kind = " + std::to_string(kind) + " is unknown";
}
std::string checkActions(const std::vector<std::int8_t>& actions) {
  for (int a : actions)
    if (auto why = checkAction("actions", a, true); !why.empty()) return why;
  return "";
}
std::string checkProbability(const std::string& field, double v) { return checkRange(field.c_str(), v, 0.0, 1.0); }

}  // namespace

std::string checkMessage(const scene_t& m, const BoundsContext& c) {
  const int side = c.run ? c.run->world.size_px : 0, height = c.run ? c.run->world.rows() : 0;
  const std::string why = first({checkStep(m.step, c), checkSerial(m.serial),
                c.run ? checkSize("width", m.width, side) : checkInt("width", m.width, 1, c.protocol->limits.scene_side),
                c.run ? checkSize("height", m.height, height) : checkInt("height", m.height, 1, c.protocol->limits.scene_side),
                m.cause == scene_t::CAUSE_START || m.cause == scene_t::CAUSE_ACTION ||
                        m.cause == scene_t::CAUSE_OBJECTS_APPEARED || m.cause == scene_t::CAUSE_GOAL
                    ? ""
                    : "field cause = " + std::to_string(m.cause) + " is unknown",
                checkAction("action", m.action, m.cause == scene_t::CAUSE_ACTION),
                checkTarget("action_target_x", m.action_target_x), checkTarget("action_target_y", m.action_target_y),
                m.goal_distance == -1.0 ? "" : checkRange("goal_distance", m.goal_distance, 0.0, 1.0),
                m.goal_utility == -1.0 ? "" : checkRange("goal_utility", m.goal_utility, 0.0, 1e12),
                m.encoding == scene_t::ENCODING_ZLIB_RGB8 ? "" : "field encoding = " + std::to_string(m.encoding) + " is unknown",
                checkInt("n_objects", m.n_objects, 0, INT16_MAX)});
  if (!why.empty()) return why;
  for (int i = 0; i < m.n_objects; ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    if (auto w = first({checkRange(("object_x" + at).c_str(), m.object_x[i], 0.0, 1.0),
                        checkRange(("object_y" + at).c_str(), m.object_y[i], 0.0, 1.0)});
        !w.empty())
      return w;
  }
  return "";
}

std::string checkMessage(const focus_t& m, const BoundsContext& c) {
  if (auto why = first({checkStep(m.step, c), checkSerial(m.serial), checkKind(m.kind),
                        checkInt("seq", m.seq, 0, INT32_MAX), checkFocus("side", m.side, "size", m.size, c),
                        checkRange("x", m.x, 0.0, 1.0), checkRange("y", m.y, 0.0, 1.0),
                        m.n_diffs == 0 || m.kind == focus_t::GOAL_DIFF ? ""
                                                                       : "field n_diffs must be 0 for a focus of kind " +
                                                                             std::to_string(m.kind)});
      !why.empty())
    return why;
  for (int i = 0; i < m.n_diffs; ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    if (auto why = first({checkRange(("diff_x" + at).c_str(), m.diff_x[i], 0.0, 1.0),
                          checkRange(("diff_y" + at).c_str(), m.diff_y[i], 0.0, 1.0),
                          m.diff_in[i] == focus_t::DIFF_GOAL || m.diff_in[i] == focus_t::DIFF_SCENE
                              ? ""
                              : "field diff_in" + at + " = " + std::to_string(m.diff_in[i]) + " is unknown"});
        !why.empty())
      return why;
  }
  return "";
}

std::string checkMessage(const prediction_t& m, const BoundsContext& c) {
  if (auto why = first({checkStep(m.step, c), checkSerial(m.serial), checkSize("n_actions", m.n_actions, kNumActions),
                        checkRange("x", m.x, 0.0, 1.0), checkRange("y", m.y, 0.0, 1.0)});
      !why.empty())
    return why;
  for (int a = 0; a < kNumActions; ++a) {
    const std::string fa = "affordance[" + std::to_string(a) + "]", fl = "learning_progress[" + std::to_string(a) + "]";
    if (auto why = first({checkRange(fa.c_str(), m.affordance[a], 0.0, 1.0), checkFinite(fl.c_str(), m.learning_progress[a])});
        !why.empty())
      return why;
  }
  if (auto why = first({m.n_tried == 0 || m.n_tried == kNumActions
                            ? ""
                            : "field n_tried = " + std::to_string(m.n_tried) + " must be 0 or " + std::to_string(kNumActions),
                        m.n_tried == 0 ? (m.look == -1 ? "" : "field look must be -1 without tried_ago")
                                       : checkInt("look", m.look, 0, INT32_MAX)});
      !why.empty())
    return why;
  for (int a = 0; a < m.n_tried; ++a)
    if (auto why = checkInt(("tried_ago[" + std::to_string(a) + "]").c_str(), m.tried_ago[a], -1, c.run ? c.run->steps : INT64_MAX);
        !why.empty())
      return why;
  if (auto why = checkInt("n_trained", m.n_trained, 0, 1); !why.empty()) return why;
  for (const auto& t : m.trained)
    if (auto why = checkMessage(t, c); !why.empty()) return "trained[0]: " + why;
  return "";
}

std::string checkMessage(const decision_t& m, const BoundsContext& c) {
  return first({checkStep(m.step, c), checkSerial(m.serial), checkAction("action", m.action, m.acted),
                m.acted || m.action == decision_t::NONE ? "" : "field action must be -1 when acted is false",
                checkRange("x", m.x, 0.0, 1.0), checkRange("y", m.y, 0.0, 1.0), checkTarget("target_x", m.target_x),
                checkTarget("target_y", m.target_y), checkFinite("motivation", m.motivation),
                checkFinite("threshold", m.threshold), checkInt("seq", m.seq, 0, INT32_MAX),
                m.revisit == 0 || (m.revisit == 1 && m.acted) ? ""
                : m.revisit == 1 ? "field revisit must be false when acted is false"
                                 : "field revisit = " + std::to_string(m.revisit) + " is not a boolean"});
}

std::string checkMessage(const effect_t& m, const BoundsContext& c) {
  return first({checkStep(m.step, c), checkSerial(m.serial), checkAction("action", m.action, true),
                checkFocus("side", m.side, "size", m.size, c), checkTarget("target_x", m.target_x),
                checkTarget("target_y", m.target_y), checkRange("before_x", m.before_x, 0.0, 1.0),
                checkRange("before_y", m.before_y, 0.0, 1.0), checkRange("after_x", m.after_x, 0.0, 1.0),
                checkRange("after_y", m.after_y, 0.0, 1.0), checkRange("image_change", m.image_change, 0.0, 1.0),
                checkRange("position_change", m.position_change, 0.0, 1.0)});
}

std::string checkMessage(const trained_t& m, const BoundsContext& c) {
  return first({checkStep(m.step, c), checkAction("action", m.action, true),
                checkRange("affordance_before", m.affordance_before, 0.0, 1.0),
                checkRange("affordance_after", m.affordance_after, 0.0, 1.0),
                checkFinite("learning_progress", m.learning_progress)});
}

std::string checkMessage(const object_probe_t& m, const BoundsContext& c) {
  const long objects = c.run ? static_cast<long>(c.run->world.objects.size()) : c.protocol->limits.objects;
  return first({checkStep(m.step, c), checkSerial(m.serial),
                c.run ? checkSize("n_objects", m.n_objects, objects) : checkInt("n_objects", m.n_objects, 1, objects),
                checkFocusSize("size", m.size, c)});
}

std::string checkMessage(const look_t& m, const BoundsContext& c) {
  return first({checkStep(m.step, c), checkSerial(m.serial), checkKind(m.kind), checkInt("seq", m.seq, 0, INT32_MAX),
                checkInt("scene", m.scene, 0, INT64_MAX),
                m.kind != focus_t::SCENE_AT && m.kind != focus_t::SCENE_OBJECT ? "" : checkRange("x", m.x, 0.0, 1.0),
                m.kind != focus_t::SCENE_AT && m.kind != focus_t::SCENE_OBJECT ? "" : checkRange("y", m.y, 0.0, 1.0)});
}

std::string checkMessage(const forward_query_t& m, const BoundsContext& c) {
  return first({checkStep(m.step, c), checkSerial(m.serial), checkInt("seq", m.seq, 0, INT32_MAX),
                checkFocusSize("size", m.size, c), checkRange("x", m.x, 0.0, 1.0), checkRange("y", m.y, 0.0, 1.0),
                checkTarget("target_x", m.target_x), checkTarget("target_y", m.target_y),
                checkInt("n_actions", m.n_actions, 0, kNumActions), checkActions(m.actions),
                checkInt("n_prefix", m.n_prefix, 0, c.run ? c.run->planner.max_depth - 1 : 3),
                checkActions(m.prefix)});
}

std::string checkMessage(const forward_prediction_t& m, const BoundsContext& c) {
  if (auto why = first({checkStep(m.step, c), checkSerial(m.serial), checkInt("seq", m.seq, 0, INT32_MAX),
                        checkFocusSize("size", m.size, c), checkInt("n_actions", m.n_actions, 0, kNumActions),
                        checkActions(m.actions),
                        m.n_input == 0 || m.n_input == kNumActions
                            ? ""
                            : "field n_input = " + std::to_string(m.n_input) + " must be 0 or " + std::to_string(kNumActions)});
      !why.empty())
    return why;
  for (int a = 0; a < m.n_input; ++a)
    if (auto why = checkRange(("input_affordance[" + std::to_string(a) + "]").c_str(), m.input_affordance[a], 0.0, 1.0);
        !why.empty())
      return why;
  for (int i = 0; i < m.n_actions; ++i) {
    if (auto why = first({checkFinite("where_x", m.where_x[i]), checkFinite("where_y", m.where_y[i])}); !why.empty())
      return why;
    for (float v : m.what[i])
      if (!(v >= 0.0f && v <= 1.0f)) return "field what holds a value outside [0, 1]";
  }
  return "";
}

std::string checkMessage(const goal_t& m, const BoundsContext& c) {
  const bool explore = m.module == goal_t::EXPLORE;
  return first({checkStep(m.step, c), checkSerial(m.serial), checkInt("id", m.id, 0, INT32_MAX),
                checkInt("module", m.module, goal_t::EXPLORE, goal_t::COLOUR_PLACE),
                explore ? checkTarget("object_x", m.object_x) : checkRange("object_x", m.object_x, 0.0, 1.0),
                explore ? checkTarget("object_y", m.object_y) : checkRange("object_y", m.object_y, 0.0, 1.0),
                explore ? checkTarget("x", m.x) : checkRange("x", m.x, 0.0, 1.0),
                explore ? checkTarget("y", m.y) : checkRange("y", m.y, 0.0, 1.0),
                explore && m.size == 0 ? "" : checkFocusSize("size", m.size, c),
                checkAction("action", m.action, explore),
                explore || m.action == -1 ? "" : "field action must be -1 unless module is EXPLORE",
                checkInt("budget", m.budget, 1, c.run ? c.run->steps : INT32_MAX)});
}

std::string checkMessage(const goal_result_t& m, const BoundsContext& c) {
  return first({checkStep(m.step, c), checkSerial(m.serial), checkInt("id", m.id, 0, INT32_MAX),
                checkInt("module", m.module, goal_t::EXPLORE, goal_t::COLOUR_PLACE),
                m.distance == -1.0 ? "" : checkRange("distance", m.distance, 0.0, 1.0),
                checkInt("actions", m.actions, 0, c.run ? c.run->steps : INT32_MAX),
                checkInt("effects", m.effects, 0, c.run ? c.run->steps : INT64_MAX),
                checkInt("focus_serial", m.focus_serial, -1, INT64_MAX),
                checkInt("forward_serial", m.forward_serial, -1, INT64_MAX), checkInt("seq", m.seq, 0, INT32_MAX)});
}

std::string checkMessage(const affordance_table_t& m, const BoundsContext& c) {
  const long objects = c.run ? static_cast<long>(c.run->world.objects.size()) : c.protocol->limits.objects;
  if (auto why = first({checkStep(m.step, c), checkSerial(m.serial),
                        c.run ? checkSize("n_objects", m.n_objects, objects) : checkInt("n_objects", m.n_objects, 0, objects),
                        checkSize("n_actions", m.n_actions, kNumActions)});
      !why.empty())
    return why;
  for (int i = 0; i < m.n_objects; ++i)
    for (int a = 0; a < kNumActions; ++a)
      if (auto why = checkProbability("affordance[" + std::to_string(i) + "][" + std::to_string(a) + "]", m.affordance[i][a]);
          !why.empty())
        return why;
  return "";
}

std::string checkMessage(const run_result_t& m, const BoundsContext& c) {
  if (auto why = first({checkStep(m.step, c), checkSerial(m.serial), checkSize("n_actions", m.n_actions, kNumActions),
                        checkInt("n_trained", m.n_trained, 0, 1),
                        m.weights_checksum.size() == 16 &&
                                m.weights_checksum.find_first_not_of("0123456789abcdef") == std::string::npos
                            ? ""
                            : "field weights_checksum is not 16 hex digits"});
      !why.empty())
    return why;
  for (int a = 0; a < kNumActions; ++a) {
    if (auto why = first({checkInt("actions_executed", m.actions_executed[a], 0, INT64_MAX),
                          checkInt("successes", m.successes[a], 0, m.actions_executed[a])});
        !why.empty())
      return why;
  }
  if (auto why = first({checkInt("looks", m.looks, 0, INT32_MAX), checkInt("replayed", m.replayed, 0, INT64_MAX),
                        checkInt("replayed_effects", m.replayed_effects, 0, INT64_MAX),
                        checkInt("revisits", m.revisits, 0, INT64_MAX)});
      !why.empty())
    return why;
  for (const auto& t : m.trained)
    if (auto why = checkMessage(t, c); !why.empty()) return "trained[0]: " + why;
  return "";
}

std::string checkMessage(const sub_goal_t& m, const BoundsContext& c) {
  const int budget = c.run ? c.run->planner.budget : INT32_MAX;
  return first({checkRange("x", m.x, 0.0, 1.0), checkRange("y", m.y, 0.0, 1.0),
                checkInt("iterations", m.iterations, 0, budget), checkInt("actions_checked", m.actions_checked, 0, INT32_MAX),
                checkInt("actions_taken", m.actions_taken, 0, budget)});
}

std::string checkMessage(const extrinsic_result_t& m, const BoundsContext& c) {
  const int budget = c.run ? c.run->planner.budget : INT32_MAX;
  if (auto why = first({checkStep(m.step, c), checkSerial(m.serial), checkInt("completion", m.completion, 0, budget),
                        m.success || m.completion == 0 ? "" : "field completion must be 0 when success is false",
                        checkInt("attempts", m.attempts, 0, budget), checkRange("utility", m.utility, -1.0, 1e12),
                        checkInt("n_sub_goals", m.n_sub_goals, 0, budget)});
      !why.empty())
    return why;
  for (std::size_t i = 0; i < m.sub_goals.size(); ++i)
    if (auto why = checkMessage(m.sub_goals[i], c); !why.empty()) return "sub_goals[" + std::to_string(i) + "]: " + why;
  return "";
}

std::string checkMessage(const process_status_t& m, const BoundsContext&) {
  if (auto why = first({checkInt("step", m.step, -1, INT64_MAX), m.process.empty() ? "field process is empty" : "",
                        checkInt("pid", m.pid, 0, INT32_MAX),
                        checkInt("state", m.state, process_status_t::WAITING, process_status_t::FAILED),
                        checkInt("started", m.started, 0, INT64_MAX)});
      !why.empty())
    return why;
  for (int i = 0; i < m.n_channels; ++i) {
    if (m.counts[i] < 0) return "field counts[" + std::to_string(i) + "] is negative";
    if (m.held_from[i] < 0 || m.held_from[i] > m.counts[i])
      return "field held_from[" + std::to_string(i) + "] = " + std::to_string(m.held_from[i]) + " is outside [0, counts[" +
             std::to_string(i) + "]]";
  }
  for (int i = 0; i < m.n_takes; ++i)
    if (m.takes_from[i] < 0) return "field takes_from[" + std::to_string(i) + "] is negative";
  return "";
}

std::string checkMessage(const resend_t& m, const BoundsContext&) {
  return first({m.run_id.empty() ? "field run_id is empty" : "", m.channel.empty() ? "field channel is empty" : "",
                checkInt("first", m.first, 0, INT64_MAX), checkInt("last", m.last, m.first, INT64_MAX)});
}

std::string checkMessage(const run_config_t& m, const BoundsContext&) {
  return first({m.run_id.empty() ? "field run_id is empty" : "", checkInt("step", m.step, 0, 0),
                checkInt("seed", m.seed, 0, INT64_MAX), m.config_yaml.empty() ? "field config_yaml is empty" : ""});
}

std::string checkMessage(const run_control_t& m, const BoundsContext&) {
  return first({m.run_id.empty() ? "field run_id is empty" : "", checkInt("step", m.step, 0, INT64_MAX),
                m.command == run_control_t::START || m.command == run_control_t::STOP
                    ? ""
                    : "field command = " + std::to_string(m.command) + " is unknown"});
}

}  // namespace afford

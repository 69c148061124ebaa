#include "eye/node.hpp"

#include "afford/actions.hpp"
#include "afford/protocol.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"

namespace afford {

EyeNode::EyeNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol, bool speculate)
    : NodeBase(lcm, "eye", std::move(log), protocol), speculate_(speculate) {
  subscribe(ch::scene, [this](const scene_t& m) { return onScene(m); });
  subscribe(ch::decision, [this](const decision_t& m) { return onDecision(m); });
  subscribe(ch::look, [this](const look_t& m) { return onLook(m); });
}

void EyeNode::onConfigured(const RunConfig& config) {
  eye_ = std::make_unique<Eye>(config);
  last_scanned_ = last_effect_ = -1;
  guess_.reset();
  last_look_ = -1;
  last_scene_ = -1;
  outer_scene_ = -1;
  scenes_.clear();
}

void EyeNode::onStop() {
  eye_.reset();
  scenes_.clear();
}

void EyeNode::publishFocus(std::int64_t step, const Focus& f, int8_t kind, int32_t seq) {
  publish(ch::focus, focusMessage(step, f, kind, seq));
}

focus_t EyeNode::focusMessage(std::int64_t step, const Focus& f, int8_t kind, int32_t seq) const {
  focus_t m;
  m.run_id = runId();
  m.step = step;
  m.kind = kind;
  m.seq = seq;
  m.x = f.x;
  m.y = f.y;
  m.side = config().eye.focus_side;
  m.image = f.image;
  m.size = static_cast<int32_t>(f.image.size());
  m.n_diffs = 0;
  return m;
}

Turn EyeNode::onExtrinsicScene(const scene_t& s) {
  if (s.step < last_scene_)
    return Turn::refuse("step " + std::to_string(s.step) + " is in the past (now at " + std::to_string(last_scene_) + ")");
  cv::Mat image;
  try {
    image = decodeScene(s.data, s.width, s.height);
  } catch (const std::exception& e) {
    return Turn::refuse(e.what());
  }
  last_scene_ = s.step;
  if (s.cause == scene_t::CAUSE_GOAL)
    eye_->setGoal(std::move(image));  // memorised: the inner eye's image
  else
    scenes_[s.serial] = std::move(image);  // the outer eye's, once a LOOK names it
  return Turn::take();
}

Turn EyeNode::onLook(const look_t& l) {
  if (config().phase != Phase::Extrinsic) return Turn::refuse("no LOOK requests in the intrinsic phase");
  if (l.seq <= last_look_) return Turn::refuse("request " + std::to_string(l.seq) + " was answered already");
  // The scene the planner looked on when it asked (a LOOK can overtake its scene).
  if (l.scene != outer_scene_) {
    auto it = scenes_.find(l.scene);
    if (it == scenes_.end()) {
      if (l.scene < outer_scene_)
        return Turn::refuse("it names scene " + std::to_string(l.scene) + ", before the one looked at (" +
                            std::to_string(outer_scene_) + ")");
      return Turn::later();  // that scene is still to come
    }
    eye_->setScene(std::move(it->second));
    outer_scene_ = l.scene;
    scenes_.erase(scenes_.begin(), std::next(it));  // LOOKs come in order: no later one names these
  }
  if (!eye_->hasScene() || !eye_->hasGoal()) return Turn::later();  // the goal and the scene come first
  // Top-down attention looks at the differences and attends objects; a
  // multi-step plan attends its object again after the plan's first action.
  if (l.kind == focus_t::GOAL_DIFF && config().eye.attention != Attention::TopDown)
    return Turn::refuse("a look at the differences is top-down attention, and this run has eye.attention: bottom_up");
  if (l.kind == focus_t::SCENE_OBJECT && config().eye.attention != Attention::TopDown && config().planner.max_depth < 2)
    return Turn::refuse("a look at an object is top-down attention or multi-step planning, and this run has "
                        "eye.attention: bottom_up and planner.search.max_depth: 1");
  last_look_ = l.seq;
  handled(l.step);
  switch (l.kind) {
    case focus_t::GOAL_DIFF: {
      focus_t m = focusMessage(l.step, eye_->atGaze(), l.kind, l.seq);
      for (Difference& d : eye_->goalDifferences(config().planner.subgoal_match)) {
        m.diff_x.push_back(d.x);
        m.diff_y.push_back(d.y);
        m.diff_in.push_back(d.in_goal ? int8_t{focus_t::DIFF_GOAL} : int8_t{focus_t::DIFF_SCENE});
        m.diff_image.push_back(std::move(d.image));
      }
      m.n_diffs = static_cast<int32_t>(m.diff_x.size());
      publish(ch::focus, m);
      break;
    }
    case focus_t::SCENE_OBJECT:
      publishFocus(l.step, eye_->attend(l.x, l.y), l.kind, l.seq);
      break;
    case focus_t::GOAL_SCAN:
      publishFocus(l.step, eye_->scanGoal(l.step), l.kind, l.seq);
      break;
    case focus_t::SCENE_AT:
      publishFocus(l.step, eye_->lookAt(l.x, l.y), l.kind, l.seq);
      break;
    default:
      publishFocus(l.step, eye_->scan(l.step), l.kind, l.seq);
  }
  return Turn::take();
}

Turn EyeNode::onScene(const scene_t& s) {
  if (config().phase == Phase::Extrinsic) return onExtrinsicScene(s);
  if (s.step <= last_scanned_)
    return Turn::refuse("step " + std::to_string(s.step) + " is in the past (already scanned step " +
                        std::to_string(last_scanned_) + ")");
  const bool is_action = s.cause == scene_t::CAUSE_ACTION;
  if (is_action && s.step - 1 <= last_effect_)
    return Turn::refuse("the effect of step " + std::to_string(s.step - 1) + " was seen already");
  // A scene for step t follows the eye's focus of step t-1 (a late message
  // of another channel, e.g. a decision, is still to come): wait for it.
  if (s.step - 1 > last_scanned_) return Turn::later();

  cv::Mat image;
  try {
    image = decodeScene(s.data, s.width, s.height);
  } catch (const std::exception& e) {
    return Turn::refuse(e.what());
  }
  guess_.reset();  // the scene changes: a guess made on the old one is void

  if (is_action) {
    const Effect e = eye_->scanEffect(s.step - 1, image, s.action);
    effect_t m;
    m.run_id = runId();
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
    m.side = config().eye.focus_side;
    m.image = e.after.image;
    m.size = static_cast<int32_t>(m.image.size());
    log_->debug("effect of step {}: action {} image change {:.5f} position change {:.4f} -> affordance {}", m.step,
                m.action, m.image_change, m.position_change, m.affordance);
    publish(ch::effect, m);
    last_effect_ = s.step - 1;
    handled(s.step - 1);
  } else {
    eye_->setScene(image);
  }
  if (s.changes_next != objectsAppearAt(s.step + 1))
    log_->warn("SCENE of step {} says objects appear at the next step: {}, the run's world.objects: {}", s.step,
               s.changes_next, objectsAppearAt(s.step + 1));
  if (s.scan) scanStep(s.step);
  return Turn::take();
}

Turn EyeNode::onDecision(const decision_t& d) {
  // Only a pass without an announced scene starts the next step here; after an
  // action, the action's scene does. (The planner's decisions are not steps of the eye's.)
  if (config().phase == Phase::Extrinsic) return Turn::take();
  if (d.step > last_scanned_) return Turn::later();  // the focus of that step is still to come
  if (d.acted || objectsAppearAt(d.step + 1) || d.step != last_scanned_) return Turn::take();
  scanStep(d.step + 1);
  return Turn::take();
}

bool EyeNode::objectsAppearAt(std::int64_t step) const {
  if (step <= 0 || step >= config().steps) return false;
  for (const auto& o : config().world.objects)
    if (o.appears_at == step) return true;
  return false;
}

void EyeNode::scanStep(std::int64_t step) {
  if (step >= config().steps || step <= last_scanned_) return;
  if (guess_ && guess_->first == step)
    publishFocus(step, eye_->look(std::move(guess_->second)));
  else
    publishFocus(step, eye_->scan(step));
  guess_.reset();
  last_scanned_ = step;
  handled(step);
  // While motivation decides, prepare the scan a pass would ask for.
  if (speculate_ && !objectsAppearAt(step + 1) && step + 1 < config().steps)
    guess_.emplace(step + 1, eye_->peekScan(step + 1));
}

}  // namespace afford

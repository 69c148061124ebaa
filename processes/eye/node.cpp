#include "eye/node.hpp"

#include <algorithm>

#include "eye/messages.hpp"

#include "afford/actions.hpp"
#include "afford/protocol.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"

namespace afford {

EyeNode::EyeNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol, bool speculate)
    : NodeBase(lcm, "eye", std::move(log), protocol), speculate_(speculate) {
  takes(ch::scene,
        "intrinsic phase: the SCENE of each step after the FOCUS of the step before, once: a scene an action "
        "caused gives that action's EFFECT (once per step), a scene that says scan starts its step; extrinsic "
        "phase: the goal scene (memorised) and each scene after it, in step order; goals phase: each SCENE once "
        "the object of the step before is looked at: an action's gives its EFFECT, and LOOKs look on the last")
      .in({Phase::Goals, Phase::Extrinsic})
      .refuse([this](const scene_t& s) {
        return s.step < last_scene_ ? "step " + std::to_string(s.step) + " is in the past (now at " +
                                          std::to_string(last_scene_) + ")"
                                    : std::string();
      })
      .in(Phase::Intrinsic)
      .refuse([this](const scene_t& s) {
        return s.step <= last_scanned_ ? "step " + std::to_string(s.step) + " is in the past (already scanned step " +
                                             std::to_string(last_scanned_) + ")"
                                       : std::string();
      })
      .in({Phase::Intrinsic, Phase::Goals})
      .refuse([this](const scene_t& s) {
        return s.cause == scene_t::CAUSE_ACTION && s.step - 1 <= last_effect_
                   ? "the effect of step " + std::to_string(s.step - 1) + " was seen already"
                   : std::string();
      })
      .waitFor([this](const scene_t& s) { return s.step - 1 <= last_scanned_; })
      .in(Phase::Goals)
      .then([this](const scene_t& s) {
        see(s);
        outer_scene_ = s.serial;
        last_scene_ = s.step;
      })
      .in(Phase::Intrinsic)
      .then([this](const scene_t& s) { see(s); })
      .in(Phase::Extrinsic)
      .then([this](const scene_t& s) { keep(s); });
  takes(ch::decision,
        "intrinsic phase: each DECISION once the FOCUS of its step is out; a pass that no scene follows (no "
        "objects appear at the next step) starts the next step")
      .in(Phase::Intrinsic)
      .waitFor([this](const decision_t& d) { return d.step <= last_scanned_; })
      .ignoreIf([this](const decision_t& d) { return d.acted || objectsAppearAt(d.step + 1); })  // a SCENE follows
      .refuse([this](const decision_t& d) {
        return d.step < last_scanned_ ? "the pass of step " + std::to_string(d.step) +
                                            " is in the past (already scanned step " + std::to_string(last_scanned_) + ")"
                                      : std::string();
      })
      .then([this](const decision_t& d) { next_step_ = d.step + 1; });
  takeLooks();
}

void EyeNode::takeLooks() {
  takes(ch::look,
        "extrinsic phase: each LOOK once, in request order, answered with one FOCUS on the scene it names (the "
        "serial of the last SCENE the planner took): a LOOK that overtakes its scene, or the goal, waits for it; "
        "a look at the differences or at an object needs top-down attention (or, for an object, multi-step "
        "planning)")
      .in(Phase::Intrinsic)
      .refuse([](const look_t&) { return "no LOOK requests in the intrinsic phase"; })
      .in(Phase::Goals)
      .refuse([this](const look_t& l) {
        return l.seq <= last_look_ ? "request " + std::to_string(l.seq) + " was answered already" : std::string();
      })
      .refuse([this](const look_t& l) {
        return l.scene < outer_scene_ ? "it names scene " + std::to_string(l.scene) + ", before the one looked at (" +
                                            std::to_string(outer_scene_) + ")"
                                      : std::string();
      })
      .waitFor([this](const look_t& l) { return l.scene == outer_scene_; })
      .refuse([](const look_t& l) {
        return l.kind == focus_t::GOAL_SCAN || l.kind == focus_t::GOAL_DIFF ? "the goals phase has no goal image"
                                                                            : "";
      })
      .then([this](const look_t& l) { lookHere(l); })
      .in(Phase::Extrinsic)
      .refuse([this](const look_t& l) {
        return l.seq <= last_look_ ? "request " + std::to_string(l.seq) + " was answered already" : std::string();
      })
      .refuse([this](const look_t& l) {
        return l.scene != outer_scene_ && !scenes_.count(l.scene) && l.scene < outer_scene_
                   ? "it names scene " + std::to_string(l.scene) + ", before the one looked at (" +
                         std::to_string(outer_scene_) + ")"
                   : std::string();
      })
      .waitFor([this](const look_t& l) { return l.scene == outer_scene_ || scenes_.count(l.scene) > 0; })
      .waitFor([this](const look_t& l) { return eye_->hasGoal() && (l.scene != outer_scene_ || eye_->hasScene()); })
      .refuse([this](const look_t& l) {
        return l.kind == focus_t::GOAL_DIFF && config().eye.attention != Attention::TopDown
                   ? "a look at the differences is top-down attention, and this run has eye.attention: bottom_up"
                   : std::string();
      })
      .refuse([this](const look_t& l) {
        return l.kind == focus_t::SCENE_OBJECT && config().eye.attention != Attention::TopDown &&
                       config().planner.max_depth < 2
                   ? "a look at an object is top-down attention or multi-step planning, and this run has "
                     "eye.attention: bottom_up and planner.search.max_depth: 1"
                   : std::string();
      })
      .then([this](const look_t& l) { answer(l); });
}

void EyeNode::onConfigured(const RunConfig& config) {
  eye_ = std::make_unique<Eye>(config);
  last_scanned_ = last_effect_ = -1;
  guess_.reset();
  next_step_.reset();
  last_look_ = -1;
  last_scene_ = -1;
  outer_scene_ = -1;
  scenes_.clear();
  seen_data_.clear();
}

void EyeNode::onStop() {
  eye_.reset();
  scenes_.clear();
  seen_data_.clear();
}

void EyeNode::publishFocus(std::int64_t step, const Focus& f, int8_t kind, int32_t seq) {
  publish(ch::focus, focusMessage(runId(), step, f, kind, seq, config().eye.focus_side));
}

namespace {
// The objects' true centres a SCENE lists (eye.fovea = true_centre).
std::vector<cv::Point2d> listedObjects(const scene_t& s) {
  std::vector<cv::Point2d> out;
  out.reserve(static_cast<std::size_t>(s.n_objects));
  for (int i = 0; i < s.n_objects; ++i) out.emplace_back(s.object_x[i], s.object_y[i]);
  return out;
}
}  // namespace

void EyeNode::keep(const scene_t& s) {
  cv::Mat image;
  try {
    image = decodeScene(s.data, s.width, s.height);
    if (s.cause == scene_t::CAUSE_GOAL) {
      eye_->setGoal(std::move(image), listedObjects(s));  // memorised: the inner eye's image
    } else {
      if (config().eye.fovea == Fovea::TrueCentre) eye_->checkScene(image, listedObjects(s));  // refused now, not at its LOOK
      scenes_[s.serial] = {std::move(image), listedObjects(s)};  // the outer eye's, once a LOOK names it
    }
  } catch (const std::exception& e) {
    throw Refusal(e.what());
  }
  last_scene_ = s.step;
}

void EyeNode::answer(const look_t& l) {
  // The scene the planner looked on when it asked (a LOOK can overtake its scene).
  if (l.scene != outer_scene_) {
    auto it = scenes_.find(l.scene);
    eye_->setScene(std::move(it->second.first), std::move(it->second.second));  // checked when kept
    seen_data_.clear();
    outer_scene_ = l.scene;
    scenes_.erase(scenes_.begin(), std::next(it));  // LOOKs come in order: no later one names these
  }
  // Top-down attention looks at the differences and attends objects; a
  // multi-step plan attends its object again after the plan's first action.
  last_look_ = l.seq;
  handled(l.step);
  switch (l.kind) {
    case focus_t::GOAL_DIFF: {
      focus_t m = focusMessage(runId(), l.step, eye_->atGaze(), l.kind, l.seq, config().eye.focus_side);
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
}

void EyeNode::lookHere(const look_t& l) {
  last_look_ = l.seq;
  handled(l.step);
  switch (l.kind) {
    case focus_t::SCENE_OBJECT:
      publishFocus(l.step, eye_->attend(l.x, l.y), l.kind, l.seq);
      break;
    case focus_t::SCENE_AT:
      return publishFocus(l.step, eye_->lookAt(l.x, l.y), l.kind, l.seq);
    default:
      publishFocus(l.step, eye_->scan(l.step), l.kind, l.seq);
  }
  last_scanned_ = std::max(last_scanned_, l.step);  // the step's object: its action's scene may come
}

void EyeNode::see(const scene_t& s) {
  const bool is_action = s.cause == scene_t::CAUSE_ACTION;
  cv::Mat image;
  const bool same = eye_->hasScene() && s.data == seen_data_ && s.width == eye_->scene().cols && s.height == eye_->scene().rows;
  if (same) {
    image = eye_->scene();
  } else {
    try {
      image = decodeScene(s.data, s.width, s.height);
    } catch (const std::exception& e) {
      throw Refusal(e.what());
    }
  }
  std::optional<Effect> effect;
  try {  // a list of objects that does not fit the image (eye.fovea = true_centre) is refused, the eye unchanged
    if (is_action)
      effect = eye_->scanEffect(s.step - 1, image, s.action, listedObjects(s),
                                s.action_target_x >= 0 && s.action_target_y >= 0
                                    ? std::optional<cv::Point2d>(cv::Point2d(s.action_target_x, s.action_target_y))
                                    : std::nullopt);
    else
      eye_->setScene(image, listedObjects(s));
  } catch (const std::invalid_argument& e) {
    throw Refusal(e.what());
  }
  if (!same) seen_data_ = s.data;
  guess_.reset();  // the scene changes: a guess made on the old one is void

  if (effect) {
    const effect_t m = effectMessage(runId(), s, *effect, config().eye.focus_side);
    log_->debug("effect of step {}: action {} image change {:.5f} position change {:.4f} -> affordance {}", m.step,
                m.action, m.image_change, m.position_change, m.affordance);
    publish(ch::effect, m);
    last_effect_ = s.step - 1;
    handled(s.step - 1);
  }
  if (s.changes_next != objectsAppearAt(s.step + 1))
    log_->warn("SCENE of step {} says objects appear at the next step: {}, the run's world.objects: {}", s.step,
               s.changes_next, objectsAppearAt(s.step + 1));
  if (s.scan && config().phase == Phase::Intrinsic) next_step_ = s.step;  // the goals phase looks where the planner asks
}

void EyeNode::afterInput() {
  // The one place a step starts: a scene that says scan (the start, after an
  // action, when objects appear) or a pass that no scene follows named it.
  if (!next_step_) return;
  const std::int64_t step = *next_step_;
  next_step_.reset();
  scanStep(step);
}

bool EyeNode::objectsAppearAt(std::int64_t step) const {
  return step < config().steps && config().world.lateObjectsAt(step);
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

// Intrinsic phase (the one with snapshots): the scene held (its bytes, the
// retina built from them), the focus, the steps scanned and whose effect was
// seen. A speculated scan is not kept: scan(step) == look(peekScan(step)).
void EyeNode::saveState(SnapshotWriter& w) {
  w.i64(last_scanned_);
  w.i64(last_effect_);
  w.i64(last_look_);  // goals phase: the LOOKs answered, and the scene they look on
  w.i64(last_scene_);
  w.i64(outer_scene_);
  w.blob(seen_data_);
  eye_->save(w);
}

void EyeNode::loadState(SnapshotReader& r) {
  last_scanned_ = r.within("last step scanned", -1, config().steps);
  last_effect_ = r.within("last step whose effect was seen", -1, config().steps);
  last_look_ = static_cast<std::int32_t>(r.within("last LOOK answered", -1, INT32_MAX));
  last_scene_ = r.within("step of the last scene", -1, config().steps);
  outer_scene_ = r.within("serial of the last scene", -1, INT64_MAX);
  seen_data_ = r.blob("scene bytes", static_cast<std::size_t>(config().protocol.bus.max_message_bytes));
  eye_->load(r);
  guess_.reset();
  next_step_.reset();
}

}  // namespace afford

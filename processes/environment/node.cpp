#include "environment/node.hpp"

#include "afford/actions.hpp"
#include "afford/protocol.hpp"
#include "afford/object_probe_t.hpp"
#include "afford/scene_t.hpp"

namespace afford {

EnvironmentNode::EnvironmentNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol)
    : NodeBase(lcm, "environment", std::move(log), protocol) {
  takes(ch::decision,
        "intrinsic phase: the DECISION of each step, in step order: an action is executed (its SCENE, and one "
        "more when objects appear at the next step), a pass changes nothing but the objects that appear; "
        "extrinsic phase: each DECISION of the planner from the current iteration on, its actions executed; goals "
        "phase: as in the intrinsic phase, the planner deciding")
      .in({Phase::Intrinsic, Phase::Goals})
      .inOrder([](const decision_t& d) { return d.step; }, [this] { return next_decision_; }, "the decision of step")
      .then([this](const decision_t& d) { decide(d); })
      .in(Phase::Extrinsic)
      .refuse([this](const decision_t& d) {
        return d.step < next_decision_ ? "step " + std::to_string(d.step) + " is in the past (now at " +
                                             std::to_string(next_decision_) + ")"
                                       : std::string();
      })
      .ignoreIf([](const decision_t& d) { return !d.acted; })
      .then([this](const decision_t& d) { act(d); });
}

void EnvironmentNode::onConfigured(const RunConfig& config) {
  env_ = makeWorld(config);
  next_decision_ = 0;
}

void EnvironmentNode::onStop() {
  env_.reset();
  sent_scene_.release();
  sent_data_.clear();
}

void EnvironmentNode::onStart() {
  if (extrinsic()) {  // paper 2.4.3: the goal is shown and memorised, then the objects are set up
    const cv::Mat goal = env_->goalScene();
    const std::vector<cv::Point2d> where = env_->goalCentres();
    publishScene(0, scene_t::CAUSE_GOAL, false, -1, -1.0, -1.0, &goal, &where);
    publishScene(0, scene_t::CAUSE_START, false, -1, -1.0, -1.0);
    return;
  }
  object_probe_t probe;
  probe.run_id = runId();
  probe.step = 0;
  probe.names = env_->probeNames();
  probe.images = env_->probeImages();
  probe.n_objects = static_cast<int32_t>(probe.images.size());
  probe.size = static_cast<int32_t>(probe.images.front().size());
  publish(ch::probe, probe);
  publishScene(0, scene_t::CAUSE_START, true, -1, -1.0, -1.0);
}

void EnvironmentNode::publishScene(std::int64_t step, int8_t cause, bool scan, int action, double tx, double ty,
                                   const cv::Mat* image, const std::vector<cv::Point2d>* centres) {
  scene_t s{};
  s.run_id = runId();
  s.step = step;
  s.cause = cause;
  s.scan = scan;
  s.changes_next = step + 1 < config().steps && env_->objectsAppearAt(step + 1);
  s.action = static_cast<int8_t>(action);
  s.action_target_x = tx;
  s.action_target_y = ty;
  s.width = config().world.size_px;
  s.height = config().world.rows();
  s.goal_distance = extrinsic() ? env_->goalDistance() : -1.0;
  s.goal_utility = extrinsic() ? env_->goalUtility() : -1.0;
  s.encoding = scene_t::ENCODING_ZLIB_RGB8;
  const cv::Mat scene = image ? *image : env_->render();
  if (!sameImage(scene, sent_scene_)) {
    sent_data_ = encodeScene(scene);
    scene.copyTo(sent_scene_);
  }
  s.data = sent_data_;
  s.size = static_cast<int32_t>(s.data.size());
  if (config().eye.fovea == Fovea::TrueCentre) {  // the eye's true_centre window needs them; it alone reads them
    for (const cv::Point2d& c : centres ? *centres : env_->centres()) {
      s.object_x.push_back(c.x);
      s.object_y.push_back(c.y);
    }
  }
  s.n_objects = static_cast<int16_t>(s.object_x.size());
  publish(ch::scene, s);
}

void EnvironmentNode::act(const decision_t& d) {
  // The planner's steps are its iterations; it decides at most once in each.
  // A place the decision does not give (-1) is drawn by the world, as in the intrinsic phase.
  std::optional<std::pair<double, double>> target;
  if (takesPlace(config().world.kind, d.action) && d.target_x >= 0.0 && d.target_y >= 0.0)
    target = std::make_pair(d.target_x, d.target_y);
  const ActionOutcome out = env_->execute(d.step, d.action, d.x, d.y, target);
  next_decision_ = d.step + 1;
  handled(d.step);
  publishScene(d.step, scene_t::CAUSE_ACTION, false, d.action, out.target_x, out.target_y);
}

void EnvironmentNode::decide(const decision_t& d) {
  const std::int64_t next = d.step + 1;
  const bool more = next < config().steps;
  next_decision_ = next;
  handled(d.step);
  if (d.acted) {
    std::optional<std::pair<double, double>> target;
    if (takesPlace(config().world.kind, d.action) && d.target_x >= 0.0 && d.target_y >= 0.0) target = std::make_pair(d.target_x, d.target_y);
    const ActionOutcome out = env_->execute(d.step, d.action, d.x, d.y, target);
    log_->debug("step {}: action {} on object: {} succeeded: {} target ({}, {})", d.step, d.action, out.on_object,
                out.succeeded, out.target_x, out.target_y);
    if (out.unstable)
      log_->warn("step {}: the simulation became unstable in the action's primitive (MuJoCo set it back): the action "
                 "failed and the scene is set up anew; a smaller table.timestep makes this rarer", d.step);
    const bool appear = more && env_->objectsAppearAt(next);
    // The action's own scene first, so the eye sees its effect without the newcomers.
    publishScene(next, scene_t::CAUSE_ACTION, more && !appear, d.action, out.target_x, out.target_y);
    if (appear) {
      env_->introduceObjectsAt(next);
      publishScene(next, scene_t::CAUSE_OBJECTS_APPEARED, true, -1, -1.0, -1.0);
    }
  } else if (more && env_->introduceObjectsAt(next)) {
    publishScene(next, scene_t::CAUSE_OBJECTS_APPEARED, true, -1, -1.0, -1.0);
  }  // otherwise nothing changed: no scene; the eye goes on with the one it has
  if (!more) setState(process_status_t::DONE);
}

void EnvironmentNode::saveState(SnapshotWriter& w) {
  w.i64(next_decision_);
  env_->save(w);
}

void EnvironmentNode::loadState(SnapshotReader& r) {
  next_decision_ = r.within("next decision", 0, config().steps);
  env_->load(r);
}

}  // namespace afford

// Environment process node.
// Channels in:  RUN_CONFIG, RUN_CONTROL (START), DECISION (motivation, or planner)
// Channels out: PROBE (once, at START), SCENE (when the scene changes), STATUS
// Extrinsic phase: at START the goal scene (to memorise), then the initial
// scene; then a scene after every action the planner decides.
// With eye.fovea = true_centre each SCENE also lists its objects' true centres.
#pragma once
#include <memory>

#include "afford/decision_t.hpp"
#include "afford/node.hpp"
#include "environment/environment.hpp"
#include "environment/world.hpp"

namespace afford {

class EnvironmentNode : public NodeBase {
 public:
  EnvironmentNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol);

 private:
  void onConfigured(const RunConfig& config) override;
  void onStart() override;
  void onStop() override;
  bool snapshots() const override { return true; }
  void saveState(SnapshotWriter& w) override;
  void loadState(SnapshotReader& r) override;
  void decide(const decision_t& d);  // intrinsic: a step's decision
  void act(const decision_t& d);     // extrinsic: the planner's action
  void publishScene(std::int64_t step, int8_t cause, bool scan, int action, double tx, double ty,
                    const cv::Mat* image = nullptr, const std::vector<cv::Point2d>* centres = nullptr);
  bool extrinsic() const { return config().phase == Phase::Extrinsic; }

  std::unique_ptr<SimWorld> env_;  // world.kind: the grid (Environment) or the table (TableWorld)
  std::int64_t next_decision_ = 0;  // the step whose decision is awaited
  // The last scene published and its compressed bytes: an action that changes
  // nothing (a third of a run's actions fail) shows that scene again, and its
  // bytes are not compressed again.
  cv::Mat sent_scene_;
  std::vector<std::uint8_t> sent_data_;
};

}  // namespace afford

// Eye process node.
// Channels in:  RUN_CONFIG, RUN_CONTROL, SCENE, DECISION, LOOK (extrinsic phase)
// Channels out: EFFECT (after a scene caused by an action), FOCUS, STATUS
// Its inputs and their rules are stated in the constructor (NodeBase::takes).
// Intrinsic phase: a step starts with a scene (start, action, newcomers) or,
// when the decision was to pass and no objects appear at the next step (the
// run's world.objects say when), with that decision; either input names the
// step, and afterInput() starts it.
// Extrinsic phase: the goal scene is memorised for the inner eye; each LOOK is
// answered with one FOCUS, on the scene it names (the serial of the last SCENE
// the planner took): a LOOK that overtakes its scene waits for it.
#pragma once
#include <map>
#include <memory>
#include <optional>
#include <utility>

#include "afford/decision_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/look_t.hpp"
#include "afford/node.hpp"
#include "afford/scene_t.hpp"
#include "eye/eye.hpp"

namespace afford {

class EyeNode : public NodeBase {
 public:
  // `speculate`: while the decision of a step is pending, compute the next
  // step's scan on the current scene, so that a pass is answered at once.
  // Results are the same either way; it pays where the eye would otherwise
  // wait (its own process), not in a single-threaded memq host.
  EyeNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol, bool speculate = true);

 private:
  void onConfigured(const RunConfig& config) override;
  void takeLooks();  // the LOOK input of each phase (the constructor states the others)
  void onStop() override;
  bool snapshots() const override { return true; }
  void saveState(SnapshotWriter& w) override;
  void loadState(SnapshotReader& r) override;
  void see(const scene_t& s);      // intrinsic: a scene (an action's effect, a scene to scan)
  void keep(const scene_t& s);     // extrinsic: the goal, or a scene for a LOOK to name
  void answer(const look_t& l);    // extrinsic: a LOOK's FOCUS
  void lookHere(const look_t& l);  // goals phase: a LOOK's FOCUS, on the scene held
  void afterInput() override;      // starts the step named by the last input, if any
  void scanStep(std::int64_t step);
  // Late objects appear at `step`: the environment publishes a scene for it
  // whether or not the step before acted, and that scene starts the step.
  bool objectsAppearAt(std::int64_t step) const;
  void publishFocus(std::int64_t step, const Focus& f, int8_t kind = 0, int32_t seq = 0);

  std::unique_ptr<Eye> eye_;
  // Intrinsic phase: the bytes of the scene the eye holds. A scene with the
  // same bytes (an action that changed nothing) is that scene: not inflated again.
  std::vector<std::uint8_t> seen_data_;
  std::int64_t last_scanned_ = -1;   // last step whose FOCUS was published
  std::int64_t last_effect_ = -1;    // last step whose EFFECT was published
  bool speculate_;
  std::int32_t last_look_ = -1;      // extrinsic: last LOOK answered
  std::int64_t last_scene_ = -1;     // extrinsic: step of the last scene
  std::int64_t outer_scene_ = -1;    // extrinsic: serial of the scene the outer eye holds
  // extrinsic: scenes taken, not yet named by a LOOK (by serial), with the objects they list
  std::map<std::int64_t, std::pair<cv::Mat, std::vector<cv::Point2d>>> scenes_;
  std::optional<std::pair<std::int64_t, Focus>> guess_;  // peekScan of the next step, if computed
  std::optional<std::int64_t> next_step_;  // a step to start now (set by an input, started by afterInput)
};

}  // namespace afford

// Eye process node.
// Channels in:  RUN_CONFIG, RUN_CONTROL, SCENE
// Channels out: EFFECT (after a scene caused by an action), FOCUS (every step), STATUS
#pragma once
#include <memory>

#include "afford/node.hpp"
#include "afford/scene_t.hpp"
#include "eye/eye.hpp"

namespace afford {

class EyeNode : public NodeBase {
 public:
  EyeNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log);

 private:
  void onConfigured(const RunConfig& config) override;
  void onStop() override;
  void onScene(const scene_t& msg);
  void publishFocus(std::int64_t step, const Focus& f);

  std::unique_ptr<Eye> eye_;
  std::int64_t last_scanned_ = -1;   // last step whose FOCUS was published
  std::int64_t last_effect_ = -1;    // last step whose EFFECT was published
};

}  // namespace afford

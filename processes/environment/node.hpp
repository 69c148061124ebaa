// Environment process node.
// Channels in:  RUN_CONFIG, RUN_CONTROL (START), DECISION
// Channels out: PROBE (once, at START), SCENE (when the scene changes), STATUS
#pragma once
#include <memory>

#include "afford/decision_t.hpp"
#include "afford/node.hpp"
#include "environment/environment.hpp"

namespace afford {

class EnvironmentNode : public NodeBase {
 public:
  EnvironmentNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log);

 private:
  void onConfigured(const RunConfig& config) override;
  void onStart() override;
  void onStop() override;
  void onDecision(const decision_t& msg);
  void publishScene(std::int64_t step, int8_t cause, bool scan, int action, double tx, double ty);

  std::unique_ptr<Environment> env_;
  std::int64_t next_decision_ = 0;  // the step whose decision is awaited
};

}  // namespace afford

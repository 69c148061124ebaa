// Motivation process node.
// Channels in:  RUN_CONFIG, RUN_CONTROL, PREDICTION (intrinsic phase only)
// Channels out: DECISION, STATUS
#pragma once
#include <map>
#include <memory>

#include "afford/node.hpp"
#include "afford/prediction_t.hpp"
#include "motivation/motivation.hpp"

namespace afford {

class MotivationNode : public NodeBase {
 public:
  MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log);

 private:
  void onConfigured(const RunConfig& config) override;
  void onStop() override;
  void onPrediction(const prediction_t& m);
  void drain();

  std::unique_ptr<Motivation> core_;
  std::int64_t last_ = -1;                  // last decided step
  std::map<std::int64_t, prediction_t> early_;
};

}  // namespace afford

// Motivation process node.
// Channels in:  RUN_CONFIG, RUN_CONTROL, PREDICTION, TRAINED (IMP with observed_change)
// Channels out: DECISION, STATUS
#pragma once
#include <map>
#include <memory>

#include "afford/node.hpp"
#include "afford/prediction_t.hpp"
#include "afford/trained_t.hpp"
#include "motivation/motivation.hpp"

namespace afford {

class MotivationNode : public NodeBase {
 public:
  MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log);

 private:
  void onConfigured(const RunConfig& config) override;
  void onStop() override;
  void onPrediction(const prediction_t& m);
  void onTrained(const trained_t& m);
  void drain();

  std::unique_ptr<Motivation> core_;
  std::int64_t last_ = -1;                  // last decided step
  std::int64_t last_acted_ = -1;            // last step with an action
  std::map<std::int64_t, prediction_t> early_;
};

}  // namespace afford

// Motivation process node.
// Channels in:  RUN_CONFIG, RUN_CONTROL, PREDICTION (intrinsic phase only)
// Channels out: DECISION, STATUS
// Its one input, PREDICTION, is stated in the constructor (NodeBase::takes):
// predictions are decided in step order, so the decisions are a pure function
// of the run.
#pragma once
#include <memory>

#include "afford/node.hpp"
#include "afford/prediction_t.hpp"
#include "motivation/component.hpp"

namespace afford {

class MotivationNode : public NodeBase {
 public:
  MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol);

 private:
  void onConfigured(const RunConfig& config) override;
  void onStop() override;
  bool snapshots() const override { return core_ && core_->snapshots(); }
  void saveState(SnapshotWriter& w) override {
    w.i64(last_);
    core_->save(w);
  }
  void loadState(SnapshotReader& r) override {
    last_ = r.within("last step decided", -1, config().steps);
    core_->load(r);
  }
  void decide(const prediction_t& m);

  std::unique_ptr<MotivationComponent> core_;
  std::int64_t last_ = -1;  // last decided step
};

}  // namespace afford

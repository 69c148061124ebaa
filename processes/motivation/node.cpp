#include "motivation/node.hpp"

#include "afford/channels.hpp"
#include "afford/decision_t.hpp"

namespace afford {

MotivationNode::MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log)
    : NodeBase(lcm, "motivation", std::move(log)) {
  subscribe<prediction_t>(channel::kPrediction, [this](const prediction_t& m) { onPrediction(m); });
}

void MotivationNode::onConfigured(const RunConfig& config) {
  core_ = std::make_unique<Motivation>(config);
  last_ = -1;
  early_.clear();
}

void MotivationNode::onStop() { core_.reset(); }

void MotivationNode::onPrediction(const prediction_t& m) {
  const char* ch = channel::kPrediction;
  if (config().phase == Phase::Extrinsic) return;  // the planner decides in the extrinsic phase
  if (m.step <= last_)
    return drop(ch, "step " + std::to_string(m.step) + " is in the past (decided up to " + std::to_string(last_) + ")");
  if (m.step >= config().steps) return drop(ch, "step " + std::to_string(m.step) + " is beyond the run's last step");
  if (early_.size() > 1000) return drop(ch, "too many early messages buffered");
  early_.emplace(m.step, m);
  drain();
}

void MotivationNode::drain() {
  while (!early_.empty() && early_.begin()->first == last_ + 1) {
    const prediction_t m = early_.begin()->second;
    early_.erase(early_.begin());
    // IMP with observed_change: the threshold takes the observed change of
    // the affordance output that the last action caused.
    if (core_->awaitingObservation()) {
      if (m.n_trained != 1 || m.trained[0].step != m.step - 1) {
        drop(channel::kPrediction, "step " + std::to_string(m.step) + " lacks the report of step " +
                                       std::to_string(m.step - 1) + "'s update");
        continue;
      }
      core_->observeChange(std::abs(m.trained[0].affordance_after - m.trained[0].affordance_before));
    }
    std::array<double, kNumActions> aff{}, lp{};
    std::copy(m.affordance.begin(), m.affordance.end(), aff.begin());
    std::copy(m.learning_progress.begin(), m.learning_progress.end(), lp.begin());
    const Decision d = core_->decide(aff, lp);
    decision_t out;
    out.run_id = runId();
    out.step = m.step;
    out.acted = d.act;
    out.action = static_cast<int8_t>(d.act ? d.action : decision_t::NONE);
    out.x = m.x;
    out.y = m.y;
    out.target_x = out.target_y = -1.0;
    out.motivation = d.motivation;
    out.threshold = d.threshold;
    publish(channel::kDecision, out);
    last_ = m.step;
    handled(m.step);
    if (m.step == config().steps - 1) setState(process_status_t::DONE);
  }
}

}  // namespace afford

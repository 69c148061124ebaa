#include "motivation/node.hpp"

#include <cmath>

#include "afford/protocol.hpp"
#include "afford/decision_t.hpp"

namespace afford {

MotivationNode::MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol)
    : NodeBase(lcm, "motivation", std::move(log), protocol) {
  subscribe(ch::prediction, [this](const prediction_t& m) { return onPrediction(m); });
}

void MotivationNode::onConfigured(const RunConfig& config) {
  core_ = std::make_unique<Motivation>(config);
  last_ = -1;
}

void MotivationNode::onStop() { core_.reset(); }

Turn MotivationNode::onPrediction(const prediction_t& m) {
  if (config().phase == Phase::Extrinsic) return Turn::take();  // the planner decides in the extrinsic phase
  if (m.step <= last_)
    return Turn::refuse("step " + std::to_string(m.step) + " is in the past (decided up to " + std::to_string(last_) + ")");
  if (m.step >= config().steps)
    return Turn::refuse("step " + std::to_string(m.step) + " is beyond the run's last step");
  if (m.step != last_ + 1) return Turn::later();  // an earlier prediction is still to come
  // Every refusal comes before the core changes: a refused message is asked for again, and must find it as it was.
  const bool remembered = m.n_tried == kNumActions;
  if (config().motivation.revisit.enabled && !remembered)
    return Turn::refuse("step " + std::to_string(m.step) + " says nothing of what was tried on the look (n_tried = 0), "
                        "which motivation.revisit needs: do the predictors keep a memory?");
  if (core_->awaitingObservation() && (m.n_trained != 1 || m.trained[0].step != m.step - 1))
    return Turn::refuse("step " + std::to_string(m.step) + " lacks the report of step " + std::to_string(m.step - 1) +
                        "'s update");
  // IMP with observed_change: the threshold takes the observed change of
  // the affordance output that the last action caused.
  if (core_->awaitingObservation())
    core_->observeChange(std::abs(m.trained[0].affordance_after - m.trained[0].affordance_before));
  std::array<double, kNumActions> aff{}, lp{};
  std::copy(m.affordance.begin(), m.affordance.end(), aff.begin());
  std::copy(m.learning_progress.begin(), m.learning_progress.end(), lp.begin());
  std::array<std::int64_t, kNumActions> tried{};
  if (remembered) std::copy(m.tried_ago.begin(), m.tried_ago.end(), tried.begin());
  const Decision d = core_->decide(aff, lp, remembered ? &tried : nullptr, m.step);
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
  out.revisit = d.revisit;
  publish(ch::decision, out);
  last_ = m.step;
  handled(m.step);
  if (m.step == config().steps - 1) setState(process_status_t::DONE);
  return Turn::take();
}

}  // namespace afford

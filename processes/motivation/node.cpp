#include "motivation/node.hpp"

#include <cmath>

#include "afford/protocol.hpp"
#include "afford/decision_t.hpp"

namespace afford {

MotivationNode::MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol)
    : NodeBase(lcm, "motivation", std::move(log), protocol) {
  takes(ch::prediction,
        "intrinsic phase: the PREDICTION of each step, in step order, one decision each (paper Algorithm 1); "
        "with motivation.revisit, it says what was tried on the look; with IMP's observed_change threshold, it "
        "carries the report of the previous step's update")
      .in(Phase::Intrinsic)
      .withinRun([this] { return config().steps; })
      .stepInOrder([this] { return last_ + 1; })
      .refuse([this](const prediction_t& m) {
        return config().motivation.revisit.enabled && m.n_tried != kNumActions
                   ? "step " + std::to_string(m.step) +
                         " says nothing of what was tried on the look (n_tried = 0), which motivation.revisit "
                         "needs: do the predictors keep a memory?"
                   : "";
      })
      .refuse([this](const prediction_t& m) {
        return core_->awaitingObservation() && (m.n_trained != 1 || m.trained[0].step != m.step - 1)
                   ? "step " + std::to_string(m.step) + " lacks the report of step " + std::to_string(m.step - 1) +
                         "'s update"
                   : "";
      })
      .then([this](const prediction_t& m) { decide(m); });
}

void MotivationNode::onConfigured(const RunConfig& config) {
  core_ = std::make_unique<Motivation>(config);
  last_ = -1;
}

void MotivationNode::onStop() { core_.reset(); }

void MotivationNode::decide(const prediction_t& m) {
  const bool remembered = m.n_tried == kNumActions;
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
}

}  // namespace afford

#include "motivation/node.hpp"

#include "afford/protocol.hpp"
#include "motivation/messages.hpp"

namespace afford {

MotivationNode::MotivationNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol)
    : NodeBase(lcm, "motivation", std::move(log), protocol) {
  takes(ch::prediction,
        "intrinsic phase: the PREDICTION of each step, in step order, one decision each (paper Algorithm 1); "
        "when the motivation needs the predictors' memory (motivation.revisit; novelty), it says which look is in "
        "focus and what was tried on it; with IMP's observed_change threshold, it carries the report of the previous step's update")
      .in(Phase::Intrinsic)
      .withinRun([this] { return config().steps; })
      .stepInOrder([this] { return last_ + 1; })
      .refuse([this](const prediction_t& m) {
        return core_->needsMemory() && m.n_tried != kNumActions
                   ? "step " + std::to_string(m.step) +
                         " says nothing of the look in focus (n_tried = 0), which motivation '" +
                         config().motivation.kind + "' needs: do the predictors keep a memory?"
                   : "";
      })
      .refuse([this](const prediction_t& m) {
        return core_->needsLastChange() && (m.n_trained != 1 || m.trained[0].step != m.step - 1)
                   ? "step " + std::to_string(m.step) + " lacks the report of step " + std::to_string(m.step - 1) +
                         "'s update"
                   : "";
      })
      .then([this](const prediction_t& m) { decide(m); });
}

void MotivationNode::onConfigured(const RunConfig& config) {
  core_ = makeMotivation(config);
  last_ = -1;
}

void MotivationNode::onStop() { core_.reset(); }

void MotivationNode::decide(const prediction_t& m) {
  publish(ch::decision, decisionMessage(runId(), m, core_->decide(perceptOf(m))));
  last_ = m.step;
  handled(m.step);
  if (m.step == config().steps - 1) setState(process_status_t::DONE);
}

}  // namespace afford

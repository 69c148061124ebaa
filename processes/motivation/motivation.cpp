#include "motivation/motivation.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace afford {

double entropyBits(double p) {
  if (p <= 0.0 || p >= 1.0) return 0.0;
  return -p * std::log2(p) - (1.0 - p) * std::log2(1.0 - p);
}

Motivation::Motivation(const RunConfig& config)
    : config_(config),
      threshold_(config.system == System::FIX ? config.motivation.fixed_threshold
                                              : config.motivation.initial_threshold) {}

int revisitAction(const std::array<std::int64_t, kNumActions>& tried_ago, std::int64_t after_steps) {
  int never = -1, stalest = -1;
  for (int a = 0; a < kNumActions; ++a) {
    if (tried_ago[a] < 0) {
      if (never < 0) never = a;  // the action order: move first (a move keeps the look), then the colours
    } else if (after_steps > 0 && tried_ago[a] >= after_steps && (stalest < 0 || tried_ago[a] > tried_ago[stalest])) {
      stalest = a;
    }
  }
  return never >= 0 ? never : stalest;
}

Decision Motivation::decide(const std::array<double, kNumActions>& affordance,
                            const std::array<double, kNumActions>& learning_progress,
                            const std::array<std::int64_t, kNumActions>* tried_ago) {
  Decision d;
  for (int a = 0; a < kNumActions; ++a) {
    const double signal =
        config_.system == System::IMP ? std::abs(learning_progress[a]) : entropyBits(affordance[a]);
    if (d.action < 0 || signal > d.motivation) {  // ties go to the lowest action index
      d.action = a;
      d.motivation = signal;
    }
  }
  d.threshold = threshold_;
  if (config_.motivation.revisit.enabled) {
    if (!tried_ago) throw std::invalid_argument("motivation.revisit needs what was tried on the look (the predictors' memory)");
    const int a = revisitAction(*tried_ago, config_.motivation.revisit.after_steps);
    if (a >= 0) {
      // Not an IM-driven choice: the threshold, the opportunity cost of the IM signal's choices, stays as it is.
      d.act = d.revisit = true;
      d.action = a;
      d.motivation = config_.system == System::IMP ? std::abs(learning_progress[a]) : entropyBits(affordance[a]);
      return d;
    }
  }
  d.act = d.motivation + config_.motivation.act_margin >= threshold_;
  if (config_.system == System::FIX) return d;
  if (!d.act)
    leak(0.0);  // Algorithm 1 line 16: no action, the leaky average gets 0
  else if (config_.system == System::IMP && config_.motivation.imp_threshold_input == ImpThresholdInput::ObservedChange)
    awaiting_ = true;
  else
    leak(d.motivation);  // line 13: the IM signal of the performed action
  return d;
}

void Motivation::observeChange(double absolute_change) {
  if (!awaiting_) return;
  awaiting_ = false;
  leak(absolute_change);
}

}  // namespace afford

#include "motivation/motivation.hpp"

#include "afford/rng.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace afford {

double entropyBits(double p) {
  if (p <= 0.0 || p >= 1.0) return 0.0;
  return -p * std::log2(p) - (1.0 - p) * std::log2(1.0 - p);
}

Motivation::Motivation(const MotivationParams& params)
    : config_(params.motivation),
      system_(params.system),
      seed_(params.seed),
      threshold_(params.system == System::FIX ? params.motivation.fixed_threshold
                                              : params.motivation.initial_threshold) {}

int revisitAction(const std::array<std::int64_t, kNumActions>& tried_ago, const RevisitConfig& revisit,
                  std::int64_t seed, std::int64_t step) {
  std::array<int, kNumActions> order{};
  for (int a = 0; a < kNumActions; ++a) order[a] = a;  // move first: a move keeps the look
  if (revisit.order == RevisitOrder::Random) {
    // A successful colour change leaves the look, and may lead where the look never comes back from: the objects
    // that enter a look should not all leave it the same way. Fisher-Yates over the colours, keyed by the step.
    const KeyedRng rng(seed, step, Purpose::Revisit);
    for (int i = kNumActions - 1; i > 1; --i) {
      const int j = 1 + static_cast<int>(rng.bits(static_cast<std::uint64_t>(i)) % static_cast<std::uint64_t>(i));
      std::swap(order[i], order[j]);
    }
  }
  int stalest = -1;
  for (const int a : order)
    if (tried_ago[a] < 0) return a;
  for (int a = 0; a < kNumActions; ++a)
    if (revisit.after_steps > 0 && tried_ago[a] >= revisit.after_steps &&
        (stalest < 0 || tried_ago[a] > tried_ago[stalest]))
      stalest = a;
  return stalest;
}

Decision Motivation::decide(const std::array<double, kNumActions>& affordance,
                            const std::array<double, kNumActions>& learning_progress,
                            const std::array<std::int64_t, kNumActions>* tried_ago, std::int64_t step) {
  Decision d;
  for (int a = 0; a < kNumActions; ++a) {
    const double signal =
        system_ == System::IMP ? std::abs(learning_progress[a]) : entropyBits(affordance[a]);
    if (d.action < 0 || signal > d.motivation) {  // ties go to the lowest action index
      d.action = a;
      d.motivation = signal;
    }
  }
  d.threshold = threshold_;
  if (config_.revisit.enabled) {
    if (!tried_ago) throw std::invalid_argument("motivation.revisit needs what was tried on the look (the predictors' memory)");
    const int a = revisitAction(*tried_ago, config_.revisit, seed_, step);
    if (a >= 0) {
      // Not an IM-driven choice: the threshold, the opportunity cost of the IM signal's choices, stays as it is.
      d.act = d.revisit = true;
      d.action = a;
      d.motivation = system_ == System::IMP ? std::abs(learning_progress[a]) : entropyBits(affordance[a]);
      return d;
    }
  }
  d.act = d.motivation + config_.act_margin >= threshold_;
  if (system_ == System::FIX) return d;
  if (!d.act)
    leak(0.0);  // Algorithm 1 line 16: no action, the leaky average gets 0
  else if (system_ == System::IMP && config_.imp_threshold_input == ImpThresholdInput::ObservedChange)
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

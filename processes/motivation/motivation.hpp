// Motivation core (paper 2.4.1, Algorithm 1 lines 2-3 and 13-16): the IM
// signal of FIX, IGN and IMP, the act-or-pass decision and the leaky-average
// threshold of equation 2. No LCM here.
#pragma once
#include <array>

#include "afford/actions.hpp"
#include "afford/config.hpp"

namespace afford {

// Shannon entropy in bits of a binary event of probability p (equation 1).
double entropyBits(double p);

struct Decision {
  bool act = false;
  int action = -1;          // the action with the highest IM signal
  double motivation = 0;    // its IM signal
  double threshold = 0;     // the threshold it was compared with
};

class Motivation {
 public:
  explicit Motivation(const RunConfig& config);

  // Decide for one focused object. Updates the threshold (IGN, IMP) unless the
  // update waits for an observed change (IMP with imp_threshold_input:
  // observed_change after an action).
  Decision decide(const std::array<double, kNumActions>& affordance,
                  const std::array<double, kNumActions>& learning_progress);
  // The observed |change| of the affordance output of the executed action.
  void observeChange(double absolute_change);
  bool awaitingObservation() const { return awaiting_; }
  double threshold() const { return threshold_; }

 private:
  void leak(double input) { threshold_ += config_.motivation.leak * (input - threshold_); }

  RunConfig config_;
  double threshold_;
  bool awaiting_ = false;
};

}  // namespace afford

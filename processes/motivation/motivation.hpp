// Motivation core (paper 2.4.1, Algorithm 1 lines 2-3 and 13-16): the IM
// signal of FIX, IGN and IMP, the act-or-pass decision and the leaky-average
// threshold of equation 2; beyond the paper, revisits (motivation.revisit,
// docs/model.md#revisit). No LCM here.
#pragma once
#include <array>
#include <cstdint>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "afford/snapshot.hpp"

namespace afford {

// Shannon entropy in bits of a binary event of probability p (equation 1).
double entropyBits(double p);

struct Decision {
  bool act = false;
  int action = -1;          // the action with the highest IM signal (or the revisited one)
  double motivation = 0;    // its IM signal
  double threshold = 0;     // the threshold it was compared with
  bool revisit = false;     // the revisit rule chose the action (it was acted on whatever the threshold)
};

// The action the revisit rule tries on a look, or -1: the first action never
// tried on it, in the action order (move, turn green, turn red, turn blue);
// else, if after_steps > 0, the one not tried for longest, once that is
// after_steps or more (ties: the first in that order). tried_ago: steps since
// each action was last tried on the look, -1 for never.
// The action a revisit tries on the focused look, or -1: one never tried on it
// (by `order`: the action order, or move then the colours in an order drawn
// from (seed, step, Purpose::Revisit)), else the one tried longest ago if that
// is after_steps or more.
int revisitAction(const std::array<std::int64_t, kNumActions>& tried_ago, const RevisitConfig& revisit,
                  std::int64_t seed, std::int64_t step);

// What a motivation is given of the run's configuration: its own section, the run's system and seed; and
// for a component written in another language (Python), the whole configuration as its RUN_CONFIG carries it.
struct MotivationParams {
  MotivationConfig motivation;
  System system = System::IMP;
  std::int64_t seed = 0;
  std::int64_t steps = 0;
  std::string experiment;
  std::string config_text;  // the run's configuration, YAML (for a component that reads it whole)
  MotivationParams() = default;
  MotivationParams(const RunConfig& c)  // NOLINT: the section a run's configuration gives
      : motivation(c.motivation), system(c.system), seed(c.seed), steps(c.steps), experiment(c.experiment),
        config_text(c.text) {}
};

class Motivation {
 public:
  explicit Motivation(const MotivationParams& params);

  // Decide for one focused object. Updates the threshold (IGN, IMP) unless the
  // update waits for an observed change (IMP with imp_threshold_input:
  // observed_change after an action).
  // `tried_ago` (the predictors' memory, needed with motivation.revisit):
  // a revisit acts without comparing with the threshold, and leaves it as it is.
  Decision decide(const std::array<double, kNumActions>& affordance,
                  const std::array<double, kNumActions>& learning_progress,
                  const std::array<std::int64_t, kNumActions>* tried_ago = nullptr, std::int64_t step = 0);
  // The observed |change| of the affordance output of the executed action.
  void observeChange(double absolute_change);
  bool awaitingObservation() const { return awaiting_; }
  double threshold() const { return threshold_; }
  // Its state for a snapshot: the threshold, and whether it awaits an observed change.
  void save(SnapshotWriter& w) const {
    w.f64(threshold_);
    w.i64(awaiting_ ? 1 : 0);
  }
  void load(SnapshotReader& r) {
    threshold_ = r.f64("threshold");
    awaiting_ = r.within("awaiting an observed change", 0, 1) == 1;
  }

 private:
  void leak(double input) { threshold_ += config_.leak * (input - threshold_); }

  MotivationConfig config_;
  System system_;
  std::int64_t seed_;
  double threshold_;
  bool awaiting_ = false;
};

}  // namespace afford

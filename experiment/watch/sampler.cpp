#include "experiment/watch/sampler.hpp"

namespace afford {

StepSampler::StepSampler(const WatchState& state, std::function<void(bool)> take, Clock::duration gap)
    : state_(state), take_(std::move(take)), gap_(gap) {}

void StepSampler::take(bool on) {
  if (on == taking_) return;
  take_(on);
  taking_ = on;
}

void StepSampler::tick(Clock::time_point now) {
  const WatchState::Progress p = state_.progress();
  if (p.phase != "intrinsic") return take(true);
  if (taking_) {
    // A focus and a prediction of a step after the one at which they were taken again (or a new run).
    if (p.focus_and_prediction > from_ || p.step < from_) {
      take(false);
      next_ = now + gap_;
    }
  } else if (now >= next_) {
    from_ = p.step;
    take(true);
  }
}

}  // namespace afford

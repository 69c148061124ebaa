// A motivation the paper does not have: count-based novelty, a standard
// baseline of the curiosity literature. On the focused look, the action this
// motivation chose least often there; its signal is 1 / sqrt(1 + n), n that
// count; it acts while the signal is at least motivation.novelty.threshold.
// Its state, the counts, is a pure function of the percepts in order, so
// replay and live restart reproduce it. (docs/writing-a-component.md)
#include <cmath>
#include <limits>
#include <map>

#include "motivation/component.hpp"

namespace afford {

namespace {

class Novelty : public MotivationComponent {
 public:
  explicit Novelty(const MotivationParams& params) : threshold_(params.motivation.novelty_threshold) {}

  Decision decide(const Percept& p) override {
    std::array<std::int64_t, kNumActions>& n = counts_[p.look];  // by look: the predictors' memory
    int least = 0;
    for (int a = 1; a < kNumActions; ++a)
      if (n[a] < n[least]) least = a;  // ties: the first in the action order
    Decision d;
    d.action = least;
    d.motivation = 1.0 / std::sqrt(1.0 + static_cast<double>(n[least]));
    d.threshold = threshold_;
    d.act = d.motivation >= threshold_;
    if (d.act) ++n[least];
    return d;
  }
  bool needsMemory() const override { return true; }
  bool snapshots() const override { return true; }
  void save(SnapshotWriter& w) const override {
    w.i64(static_cast<std::int64_t>(counts_.size()));
    for (const auto& [look, n] : counts_) {
      w.i64(look);
      for (std::int64_t k : n) w.i64(k);
    }
  }
  void load(SnapshotReader& r) override {
    counts_.clear();
    const std::int64_t looks = r.within("looks counted", 0, 100'000'000);
    for (std::int64_t i = 0; i < looks; ++i) {
      auto& n = counts_[static_cast<int>(r.within("look", -1, std::numeric_limits<int>::max()))];
      for (std::int64_t& k : n) k = r.within("times chosen", 0, std::numeric_limits<std::int64_t>::max());
    }
  }

 private:
  double threshold_;
  std::map<int, std::array<std::int64_t, kNumActions>> counts_;  // look -> times each action was chosen on it
};

}  // namespace

std::unique_ptr<MotivationComponent> makeNoveltyMotivation(const MotivationParams& params) {
  return std::make_unique<Novelty>(params);
}

}  // namespace afford

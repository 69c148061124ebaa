#include "motivation/component.hpp"

#include <cmath>
#include <map>
#include <mutex>

namespace afford {

namespace {

// The paper's motivations (FIX, IGN, IMP by the run's system), with revisits (docs/model.md#revisit).
class PaperMotivation : public MotivationComponent {
 public:
  explicit PaperMotivation(const RunConfig& config) : core_(config), revisit_(config.motivation.revisit.enabled) {}
  Decision decide(const Percept& p) override {
    // IMP with observed_change: the threshold takes the observed change the last action caused.
    if (core_.awaitingObservation()) core_.observeChange(*p.last_change);
    return core_.decide(p.affordance, p.learning_progress, p.tried_ago ? &*p.tried_ago : nullptr, p.step);
  }
  bool needsLastChange() const override { return core_.awaitingObservation(); }
  bool needsMemory() const override { return revisit_; }

 private:
  Motivation core_;
  bool revisit_;
};

struct Registry {
  std::mutex mutex;
  std::vector<std::pair<std::string, MotivationFactory>> kinds;
};
Registry& registry() {
  static Registry r;
  static std::once_flag shipped;
  std::call_once(shipped, [] {
    r.kinds.emplace_back("paper", [](const RunConfig& c) { return std::make_unique<PaperMotivation>(c); });
    r.kinds.emplace_back("novelty", makeNoveltyMotivation);
  });
  return r;
}

}  // namespace

void registerMotivation(const std::string& kind, MotivationFactory factory) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  for (auto& [name, f] : r.kinds)
    if (name == kind) {
      f = std::move(factory);
      return;
    }
  r.kinds.emplace_back(kind, std::move(factory));
}

std::vector<std::string> motivationKinds() {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  std::vector<std::string> out;
  for (const auto& [name, f] : r.kinds) out.push_back(name);
  return out;
}

std::unique_ptr<MotivationComponent> makeMotivation(const RunConfig& config) {
  Registry& r = registry();
  MotivationFactory factory;
  std::string known;
  {
    std::lock_guard<std::mutex> lock(r.mutex);
    for (const auto& [name, f] : r.kinds) {
      known += (known.empty() ? "" : ", ") + name;
      if (name == config.motivation.kind) factory = f;
    }
  }
  if (!factory)
    throw ConfigError("config key 'motivation.kind': '" + config.motivation.kind +
                      "' is not one of the motivations built into this process (" + known +
                      "); a motivation of one's own runs as its own process: --process motivation='COMMAND' "
                      "(docs/writing-a-component.md)");
  return factory(config);
}

}  // namespace afford

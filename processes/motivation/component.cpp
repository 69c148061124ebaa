#include "motivation/component.hpp"

#include <spdlog/spdlog.h>

#include "afford/components.hpp"

namespace afford {

namespace {

// The paper's motivations (FIX, IGN, IMP by the run's system), with revisits (docs/model.md#revisit).
class PaperMotivation : public MotivationComponent {
 public:
  explicit PaperMotivation(const MotivationParams& params) : core_(params), revisit_(params.motivation.revisit.enabled) {}
  Decision decide(const Percept& p) override {
    // IMP with observed_change: the threshold takes the observed change the last action caused.
    if (core_.awaitingObservation()) core_.observeChange(*p.last_change);
    return core_.decide(p.affordance, p.learning_progress, p.tried_ago ? &*p.tried_ago : nullptr, p.step);
  }
  bool needsLastChange() const override { return core_.awaitingObservation(); }
  bool needsMemory() const override { return revisit_; }
  bool snapshots() const override { return true; }
  void save(SnapshotWriter& w) const override { core_.save(w); }
  void load(SnapshotReader& r) override { core_.load(r); }

 private:
  Motivation core_;
  bool revisit_;
};

ComponentRegistry<MotivationComponent, MotivationParams>& registry() {
  static ComponentRegistry<MotivationComponent, MotivationParams> r(
      "motivation.kind", "motivation",
      {{"paper", [](const MotivationParams& p) { return std::make_unique<PaperMotivation>(p); }},
       {"novelty", makeNoveltyMotivation}});
  return r;
}

}  // namespace

void registerMotivation(const std::string& kind, MotivationFactory factory) { registry().add(kind, std::move(factory)); }

void registerRunConfigMotivation(const std::string& kind, RunConfigMotivationFactory factory) {
  spdlog::warn("motivation '{}': its factory takes the whole RunConfig, which is deprecated since 0.2.0 and kept for "
               "that release only: take const afford::MotivationParams& (its section, system, seed, steps, and "
               "config_text for the rest) (docs/writing-a-component.md)",
               kind);
  registry().add(kind, [factory = std::move(factory)](const MotivationParams& p) {
    return factory(parseRunConfigText(p.config_text));
  });
}

std::vector<std::string> motivationKinds() { return registry().kinds(); }

std::unique_ptr<MotivationComponent> makeMotivation(const MotivationParams& params) {
  return registry().make(params, params.motivation.kind);
}

}  // namespace afford

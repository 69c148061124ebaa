#include "predictors/affordance.hpp"

#include "afford/components.hpp"
#include "afford/rng.hpp"

namespace afford {

namespace {

// The paper's affordance predictor (paper 2.3.3): for each action a sigmoid
// perceptron of the focus image, trained by the delta rule towards 1 (the
// effect was seen) or 0; and for IMP a linear perceptron that learns the
// change of that output, the learning progress (Algorithm 1 lines 7-9).
class PaperAffordance : public AffordanceComponent {
 public:
  explicit PaperAffordance(const AffordanceParams& params) : config_(params.predictors), system_(params.system) {
    const int dim = params.focus_side * params.focus_side * 3 + 1;
    for (int a = 0; a < kNumActions; ++a) {
      affordance_.emplace_back(dim, true);  // zero weights: output 0.5, ignorance 1 (paper 2.4.1)
      learning_progress_.emplace_back(dim, false);
      // Learning-progress weights: random sign, fixed magnitude (docs/parameters.md).
      const KeyedRng rng(params.seed, 0, Purpose::LearningProgressInit, static_cast<std::uint64_t>(a));
      Eigen::VectorXd& w = learning_progress_.back().weights();
      for (int i = 0; i < dim; ++i)
        w[i] = (rng.bits(static_cast<std::uint64_t>(i)) & 1u) ? params.predictors.learning_progress_init
                                                              : -params.predictors.learning_progress_init;
    }
  }

  void predict(const FocusView& focus, PerAction& affordance, PerAction& learning_progress) const override {
    for (int a = 0; a < kNumActions; ++a) {
      affordance[a] = affordance_[a].output(focus.input);
      learning_progress[a] = learning_progress_[a].output(focus.input);
    }
  }

  Learned learn(const FocusView& focus, int a, bool succeeded) override {
    Learned r;
    r.before = affordance_[a].train(focus.input, succeeded ? 1.0 : 0.0, config_.affordance_learning_rate);
    r.after = affordance_[a].output(focus.input);
    r.learning_progress = learning_progress_[a].output(focus.input);
    // Algorithm 1 line 9: only IMP (and GOALS, whose learning is Algorithm 1's with IMP's predictors)
    if (system_ == System::IMP || system_ == System::GOALS)
      learning_progress_[a].train(focus.input, r.after - r.before, config_.learning_progress_learning_rate);
    return r;
  }

  void relearn(const FocusView& focus, int a, bool succeeded) override {
    affordance_[a].train(focus.input, succeeded ? 1.0 : 0.0, config_.affordance_learning_rate);
  }

  std::vector<StateArray> state(int a) override {
    Eigen::VectorXd& aff = affordance_[a].weights();
    Eigen::VectorXd& lp = learning_progress_[a].weights();
    return {{aff.data(), static_cast<std::size_t>(aff.size())}, {lp.data(), static_cast<std::size_t>(lp.size())}};
  }

 private:
  PredictorsConfig config_;
  System system_;
  std::vector<Unit> affordance_, learning_progress_;
};

ComponentRegistry<AffordanceComponent, AffordanceParams>& registry() {
  static ComponentRegistry<AffordanceComponent, AffordanceParams> r(
      "predictors.affordance.kind", "predictors",
      {{"paper", [](const AffordanceParams& p) { return std::make_unique<PaperAffordance>(p); }}});
  return r;
}

}  // namespace

void registerAffordance(const std::string& kind, AffordanceFactory factory) { registry().add(kind, std::move(factory)); }

std::vector<std::string> affordanceKinds() { return registry().kinds(); }

std::unique_ptr<AffordanceComponent> makeAffordance(const AffordanceParams& params) {
  return registry().make(params, params.predictors.affordance_kind);
}

}  // namespace afford

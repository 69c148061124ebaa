#include "predictors/predictors.hpp"

#include "afford/checksum.hpp"
#include "afford/rng.hpp"

namespace afford {

Predictors::Predictors(const RunConfig& config)
    : config_(config), input_size_(config.eye.focus_side * config.eye.focus_side * 3) {
  const int dim = input_size_ + 1;
  for (int a = 0; a < kNumActions; ++a) {
    affordance_.emplace_back(dim, true);  // zero weights: output 0.5, ignorance 1 (paper 2.4.1)
    learning_progress_.emplace_back(dim, false);
    what_.emplace_back(input_size_, dim, true);
    where_.emplace_back(2, a == kMove ? 5 : 3, false);
    // Learning-progress weights: random sign, fixed magnitude (PARAMETERS.md).
    const KeyedRng rng(config.seed, 0, Purpose::LearningProgressInit, static_cast<std::uint64_t>(a));
    Eigen::VectorXd& w = learning_progress_.back().weights();
    for (int i = 0; i < dim; ++i)
      w[i] = (rng.bits(static_cast<std::uint64_t>(i)) & 1u) ? config.predictors.learning_progress_init
                                                            : -config.predictors.learning_progress_init;
  }
}

Prediction Predictors::predict(const std::vector<std::uint8_t>& focus_image) const {
  const SparseInput x = focusInput(focus_image);
  Prediction p;
  for (int a = 0; a < kNumActions; ++a) {
    p.affordance[a] = affordance_[a].output(x);
    p.learning_progress[a] = learning_progress_[a].output(x);
  }
  return p;
}

SparseInput Predictors::whereInput(int action, double x, double y, double tx, double ty) const {
  return action == kMove ? denseInput({tx, ty, x, y}) : denseInput({x, y});
}

TrainingReport Predictors::train(const Experience& e) {
  TrainingReport r = trainAffordance(e);
  trainEffects(e);
  return r;
}

TrainingReport Predictors::trainAffordance(const Experience& e) {
  const int a = e.action;
  const SparseInput x = focusInput(e.before_image);
  TrainingReport r;
  r.action = a;
  r.affordance = e.affordance;
  r.affordance_before = affordance_[a].train(x, e.affordance ? 1.0 : 0.0, config_.predictors.affordance_learning_rate);
  r.affordance_after = affordance_[a].output(x);
  r.learning_progress = learning_progress_[a].output(x);
  if (config_.system == System::IMP)  // Algorithm 1 line 9: only IMP
    learning_progress_[a].train(x, r.affordance_after - r.affordance_before,
                                config_.predictors.learning_progress_learning_rate);
  ++executed_[a];
  if (e.affordance) ++successes_[a];
  r.effect_trained = e.affordance;
  return r;
}

void Predictors::trainEffects(const Experience& e) {
  if (!e.affordance) return;  // effect predictors learn from successes only
  const int a = e.action;
  Eigen::VectorXd target(input_size_);
  for (int i = 0; i < input_size_; ++i) target[i] = e.after_image[i] / 255.0;
  what_[a].train(focusInput(e.before_image), target, config_.predictors.what_effect_learning_rate);
  where_[a].train(whereInput(a, e.before_x, e.before_y, e.target_x, e.target_y), Eigen::Vector2d(e.after_x, e.after_y),
                  config_.predictors.where_effect_learning_rate);
}

std::vector<PerAction> Predictors::table(const std::vector<std::vector<std::uint8_t>>& probes) const {
  std::vector<PerAction> out;
  for (const auto& img : probes) out.push_back(predict(img).affordance);
  return out;
}

std::vector<double> Predictors::whatEffect(int action, const std::vector<std::uint8_t>& focus_image) const {
  const Eigen::VectorXd y = what_[action].output(focusInput(focus_image));
  return std::vector<double>(y.data(), y.data() + y.size());
}

std::array<double, 2> Predictors::whereEffect(int action, double x, double y, double tx, double ty) const {
  const Eigen::VectorXd p = where_[action].output(whereInput(action, x, y, tx, ty));
  return {p[0], p[1]};
}

std::string Predictors::weightsChecksum() const {
  Fnv1a h;
  for (int a = 0; a < kNumActions; ++a) {
    h.add(affordance_[a].weights().data(), sizeof(double) * affordance_[a].weights().size());
    h.add(learning_progress_[a].weights().data(), sizeof(double) * learning_progress_[a].weights().size());
    h.add(what_[a].weights().data(), sizeof(double) * what_[a].weights().size());
    h.add(where_[a].weights().data(), sizeof(double) * where_[a].weights().size());
  }
  return h.hex();
}

}  // namespace afford

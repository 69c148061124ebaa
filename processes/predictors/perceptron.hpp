// Single-layer perceptrons of paper 2.3.3, trained with the delta rule (times
// the sigmoid derivative for sigmoid units). Inputs are focus images, which are
// mostly black, so inputs are kept sparse: the arithmetic is exactly that of
// the dense product, skipping only terms whose input is zero.
#pragma once
#include <Eigen/Dense>

#include <cstdint>
#include <vector>

namespace afford {

// Non-zero entries of an input vector whose last entry is the bias (1).
struct SparseInput {
  int dim = 0;                  // including the bias
  std::vector<int> index;       // ascending
  std::vector<double> value;
};

// Focus image bytes (value / 255) plus bias.
SparseInput focusInput(const std::vector<std::uint8_t>& focus_image);
// A small dense vector plus bias (where-effect inputs).
SparseInput denseInput(std::initializer_list<double> values);

inline double sigmoid(double a) { return 1.0 / (1.0 + std::exp(-a)); }

// One output unit: sigmoid or linear.
class Unit {
 public:
  Unit(int dim, bool sigmoid) : w_(Eigen::VectorXd::Zero(dim)), sigmoid_(sigmoid) {}
  double output(const SparseInput& x) const;
  // One delta-rule step towards target; returns the output before the step.
  double train(const SparseInput& x, double target, double learning_rate);
  Eigen::VectorXd& weights() { return w_; }
  const Eigen::VectorXd& weights() const { return w_; }

 private:
  Eigen::VectorXd w_;
  bool sigmoid_;
};

// A layer of units sharing one input (what-effect: 1323 sigmoid units;
// where-effect: 2 linear units). Weights are outputs x inputs, column-major,
// so a sparse input touches whole columns.
class Layer {
 public:
  Layer(int outputs, int dim, bool sigmoid);
  Eigen::VectorXd output(const SparseInput& x) const;
  void train(const SparseInput& x, const Eigen::VectorXd& target, double learning_rate);
  // The same step, given `y`, output(x) with the weights as they are.
  void train(const SparseInput& x, const Eigen::VectorXd& y, const Eigen::VectorXd& target, double learning_rate);
  Eigen::MatrixXd& weights() { return w_; }
  const Eigen::MatrixXd& weights() const { return w_; }

 private:
  Eigen::MatrixXd w_;
  bool sigmoid_;
};

}  // namespace afford

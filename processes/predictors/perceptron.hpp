// Single-layer perceptrons of paper 2.3.3, trained with the delta rule (times
// the sigmoid derivative for sigmoid units). Inputs are focus images, which are
// mostly black, so inputs are kept sparse: the arithmetic is exactly that of
// the dense product, skipping only terms whose input is zero.
#pragma once
#include <Eigen/Dense>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
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

// A second thread for a layer's rows: split(n, f) runs f(0, m) on the
// caller's thread and f(m, n) on its own at the same time, and returns when
// both are done (m about n / 2, on a cache line). The units of a layer are
// independent, so each output and each weight is computed by the same
// operations in the same order, whichever thread makes it: the values are
// bit-identical to one thread's. One split at a time; callers wait in turn.
class SecondCore {
 public:
  SecondCore();
  ~SecondCore();
  SecondCore(const SecondCore&) = delete;
  SecondCore& operator=(const SecondCore&) = delete;
  void split(Eigen::Index n, const std::function<void(Eigen::Index, Eigen::Index)>& f);
  std::int64_t splits() const { return splits_; }  // made so far

 private:
  void work();
  std::mutex one_at_a_time_, mutex_;
  std::condition_variable changed_;
  const std::function<void(Eigen::Index, Eigen::Index)>* job_ = nullptr;
  Eigen::Index from_ = 0, to_ = 0;
  bool stop_ = false;
  std::int64_t splits_ = 0;
  std::thread thread_;
};

// A layer of units sharing one input (what-effect: 1323 sigmoid units;
// where-effect: 2 linear units). Weights are outputs x inputs, column-major,
// so a sparse input touches whole columns.
class Layer {
 public:
  Layer(int outputs, int dim, bool sigmoid);
  // `second`: split the rows with it (nullptr: all on this thread); the same values either way.
  Eigen::VectorXd output(const SparseInput& x, SecondCore* second = nullptr) const;
  void train(const SparseInput& x, const Eigen::VectorXd& target, double learning_rate,
             SecondCore* second = nullptr);
  // The same step, given `y`, output(x) with the weights as they are.
  void train(const SparseInput& x, const Eigen::VectorXd& y, const Eigen::VectorXd& target, double learning_rate,
             SecondCore* second = nullptr);
  Eigen::MatrixXd& weights() { return w_; }
  const Eigen::MatrixXd& weights() const { return w_; }

 private:
  // Rows [from, to) of output() and of a train() step's column updates.
  void outputRows(const SparseInput& x, Eigen::VectorXd& a, Eigen::Index from, Eigen::Index to) const;
  void trainRows(const SparseInput& x, const Eigen::VectorXd& delta, Eigen::Index from, Eigen::Index to);

  Eigen::MatrixXd w_;
  bool sigmoid_;
};

}  // namespace afford

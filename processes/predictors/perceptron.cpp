#include "predictors/perceptron.hpp"

#include <sys/mman.h>

#include <cassert>
#include <cstdint>

namespace afford {

SparseInput focusInput(const std::vector<std::uint8_t>& focus_image) {
  SparseInput x;
  x.dim = static_cast<int>(focus_image.size()) + 1;
  for (std::size_t i = 0; i < focus_image.size(); ++i)
    if (focus_image[i] != 0) {
      x.index.push_back(static_cast<int>(i));
      x.value.push_back(focus_image[i] / 255.0);
    }
  x.index.push_back(x.dim - 1);
  x.value.push_back(1.0);
  return x;
}

SparseInput denseInput(std::initializer_list<double> values) {
  SparseInput x;
  x.dim = static_cast<int>(values.size()) + 1;
  int i = 0;
  for (double v : values) {
    x.index.push_back(i++);
    x.value.push_back(v);
  }
  x.index.push_back(x.dim - 1);
  x.value.push_back(1.0);
  return x;
}

double Unit::output(const SparseInput& x) const {
  assert(x.dim == w_.size());
  double a = 0.0;
  for (std::size_t k = 0; k < x.index.size(); ++k) a += w_[x.index[k]] * x.value[k];
  return sigmoid_ ? sigmoid(a) : a;
}

double Unit::train(const SparseInput& x, double target, double learning_rate) {
  const double y = output(x);
  double delta = target - y;
  if (sigmoid_) delta *= y * (1.0 - y);
  const double step = learning_rate * delta;
  for (std::size_t k = 0; k < x.index.size(); ++k) w_[x.index[k]] += step * x.value[k];
  return y;
}

namespace {

// A what-effect layer is 1323 x 1324 doubles (14 MB): a focus image touches a
// few hundred of its columns, 10.6 KB apart, each on pages of its own. Asked
// before the pages are first touched, the kernel backs the matrix with 2 MB
// pages where it has them (transparent huge pages in madvise mode), and the
// walk through the columns misses the TLB far less. The values and the order
// of every operation are the same either way.
void preferHugePages(double* data, std::size_t bytes) {
  constexpr std::uintptr_t kHuge = 2u << 20;
  const auto from = (reinterpret_cast<std::uintptr_t>(data) + kHuge - 1) & ~(kHuge - 1);
  const auto to = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHuge - 1);
  if (to > from) (void)madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
}

}  // namespace

Layer::Layer(int outputs, int dim, bool sigmoid) : w_(outputs, dim), sigmoid_(sigmoid) {
  preferHugePages(w_.data(), static_cast<std::size_t>(w_.size()) * sizeof(double));
  w_.setZero();
}

namespace {
// The columns a sparse input touches are 10.6 KB apart (a what-effect layer):
// each is one sequential stream, but the jump to the next is one the
// hardware prefetcher cannot foresee. While one column is summed, the next is
// asked for, a cache line at a time. Only memory traffic changes: the values
// and the order of every operation are the same.
template <int kWrite>
void prefetchColumn(const double* column, Eigen::Index rows) {
  constexpr std::size_t kLine = 64;
  const char* p = reinterpret_cast<const char*>(column);
  const char* const end = p + static_cast<std::size_t>(rows) * sizeof(double);
  for (; p < end; p += kLine) __builtin_prefetch(p, kWrite, 3);
}

// Below this many multiply-adds a split costs more than it saves (a
// where-effect layer: 2 x 7).
constexpr Eigen::Index kWorthSplitting = 16384;

// `second`, where a pass of `rows` over x's columns is worth splitting; else nullptr.
SecondCore* splitter(SecondCore* second, Eigen::Index rows, const SparseInput& x) {
  return rows * static_cast<Eigen::Index>(x.index.size()) >= kWorthSplitting ? second : nullptr;
}
}  // namespace

SecondCore::SecondCore() : thread_([this] { work(); }) {}

SecondCore::~SecondCore() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void SecondCore::split(Eigen::Index n, const std::function<void(Eigen::Index, Eigen::Index)>& f) {
  std::lock_guard<std::mutex> turn(one_at_a_time_);
  const Eigen::Index m = (n / 2) & ~Eigen::Index{7};  // 8 doubles: a cache line each side
  ++splits_;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &f;
    from_ = m;
    to_ = n;
  }
  changed_.notify_all();
  f(0, m);
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return job_ == nullptr; });
}

void SecondCore::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stop_ || job_ != nullptr; });
    if (job_ == nullptr) return;  // stopping, nothing asked
    const auto* f = job_;
    const Eigen::Index from = from_, to = to_;
    lock.unlock();
    (*f)(from, to);
    lock.lock();
    job_ = nullptr;
    changed_.notify_all();
  }
}

void Layer::outputRows(const SparseInput& x, Eigen::VectorXd& a, Eigen::Index from, Eigen::Index to) const {
  const Eigen::Index rows = to - from;
  const std::size_t n = x.index.size();
  for (std::size_t k = 0; k < n; ++k) {
    if (k + 1 < n) prefetchColumn<0>(w_.col(x.index[k + 1]).data() + from, rows);
    a.segment(from, rows).noalias() += w_.col(x.index[k]).segment(from, rows) * x.value[k];
  }
  if (sigmoid_) a.segment(from, rows) = a.segment(from, rows).unaryExpr([](double v) { return sigmoid(v); });
}

void Layer::trainRows(const SparseInput& x, const Eigen::VectorXd& delta, Eigen::Index from, Eigen::Index to) {
  const Eigen::Index rows = to - from;
  const std::size_t n = x.index.size();
  for (std::size_t k = 0; k < n; ++k) {
    if (k + 1 < n) prefetchColumn<1>(w_.col(x.index[k + 1]).data() + from, rows);
    w_.col(x.index[k]).segment(from, rows).noalias() += delta.segment(from, rows) * x.value[k];
  }
}

Eigen::VectorXd Layer::output(const SparseInput& x, SecondCore* second) const {
  assert(x.dim == w_.cols());
  Eigen::VectorXd a = Eigen::VectorXd::Zero(w_.rows());
  if (SecondCore* s = splitter(second, w_.rows(), x))
    s->split(w_.rows(), [&](Eigen::Index from, Eigen::Index to) { outputRows(x, a, from, to); });
  else
    outputRows(x, a, 0, w_.rows());
  return a;
}

void Layer::train(const SparseInput& x, const Eigen::VectorXd& target, double learning_rate, SecondCore* second) {
  train(x, output(x, second), target, learning_rate, second);
}

void Layer::train(const SparseInput& x, const Eigen::VectorXd& y, const Eigen::VectorXd& target, double learning_rate,
                  SecondCore* second) {
  Eigen::VectorXd delta = target - y;
  if (sigmoid_) delta = delta.cwiseProduct(y.cwiseProduct(Eigen::VectorXd::Ones(y.size()) - y));
  delta *= learning_rate;
  if (SecondCore* s = splitter(second, w_.rows(), x))
    s->split(w_.rows(), [&](Eigen::Index from, Eigen::Index to) { trainRows(x, delta, from, to); });
  else
    trainRows(x, delta, 0, w_.rows());
}

}  // namespace afford

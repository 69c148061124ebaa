#include <gtest/gtest.h>

#include <cstring>

#include "predictors/perceptron.hpp"

namespace afford {
namespace {

TEST(Perceptron, FocusInputScalesBytesAndAppendsTheBias) {
  const SparseInput x = focusInput({0, 255, 0, 51});
  EXPECT_EQ(x.dim, 5);
  ASSERT_EQ(x.index, (std::vector<int>{1, 3, 4}));
  EXPECT_DOUBLE_EQ(x.value[0], 1.0);
  EXPECT_DOUBLE_EQ(x.value[1], 0.2);
  EXPECT_DOUBLE_EQ(x.value[2], 1.0);
}

TEST(Perceptron, ZeroSigmoidUnitOutputsOneHalf) {
  Unit u(5, true);
  EXPECT_DOUBLE_EQ(u.output(focusInput({0, 255, 0, 255})), 0.5);
}

TEST(Perceptron, SigmoidUnitFollowsTheDeltaRuleTimesTheDerivative) {
  Unit u(3, true);
  u.weights() << 0.2, -0.1, 0.05;
  const SparseInput x = denseInput({0.5, 1.0});
  const double y = sigmoid(0.2 * 0.5 - 0.1 * 1.0 + 0.05);
  const double before = u.train(x, 1.0, 0.1);
  EXPECT_DOUBLE_EQ(before, y);
  const double step = 0.1 * (1.0 - y) * y * (1.0 - y);
  EXPECT_DOUBLE_EQ(u.weights()[0], 0.2 + step * 0.5);
  EXPECT_DOUBLE_EQ(u.weights()[1], -0.1 + step * 1.0);
  EXPECT_DOUBLE_EQ(u.weights()[2], 0.05 + step);
}

TEST(Perceptron, LinearUnitFollowsTheDeltaRule) {
  Unit u(3, false);
  u.weights() << 1.0, 2.0, 0.5;
  const SparseInput x = denseInput({0.5, -1.0});
  const double y = 1.0 * 0.5 - 2.0 + 0.5;
  u.train(x, 2.0, 0.01);
  EXPECT_DOUBLE_EQ(u.weights()[0], 1.0 + 0.01 * (2.0 - y) * 0.5);
  EXPECT_DOUBLE_EQ(u.weights()[1], 2.0 + 0.01 * (2.0 - y) * -1.0);
}

TEST(Perceptron, SparseProductEqualsTheDenseProduct) {
  std::vector<std::uint8_t> img(60, 0);
  for (int i = 0; i < 60; i += 7) img[i] = static_cast<std::uint8_t>(i * 4);
  Unit u(61, false);
  for (int i = 0; i < 61; ++i) u.weights()[i] = 0.01 * (i % 13) - 0.05;
  double dense = u.weights()[60];
  for (int i = 0; i < 60; ++i) dense += u.weights()[i] * img[i] / 255.0;
  EXPECT_NEAR(u.output(focusInput(img)), dense, 1e-12);
}

TEST(Perceptron, LayerTrainsEveryOutputTowardsItsTarget) {
  Layer l(3, 3, true);
  const SparseInput x = denseInput({1.0, 0.0});
  Eigen::VectorXd target(3);
  target << 1.0, 0.0, 0.5;
  for (int k = 0; k < 2000; ++k) l.train(x, target, 0.5);
  const Eigen::VectorXd y = l.output(x);
  EXPECT_GT(y[0], 0.9);
  EXPECT_LT(y[1], 0.1);
  EXPECT_NEAR(y[2], 0.5, 1e-9);
  // The input that was zero kept its weights.
  EXPECT_EQ(l.weights().col(1).norm(), 0.0);
}

// A what-effect layer (1323 units of a 21 x 21 x 3 focus image) trained and
// asked with its rows split between two threads holds and gives the very
// bits it does on one thread.
TEST(Perceptron, ALayerSplitWithASecondCoreComputesTheSameBits) {
  constexpr int kUnits = 1323;
  Layer one(kUnits, kUnits + 1, true), two(kUnits, kUnits + 1, true);
  SecondCore second;
  Eigen::VectorXd target(kUnits);
  std::vector<std::uint8_t> image(kUnits);
  for (int step = 0; step < 20; ++step) {
    for (int i = 0; i < kUnits; ++i) {
      image[static_cast<std::size_t>(i)] = (i * 7 + step * 13) % 5 == 0 ? static_cast<std::uint8_t>((i * 31 + step) % 256) : 0;
      target[i] = ((i + step) % 3) / 2.0;
    }
    const SparseInput x = focusInput(image);
    if (step % 2 == 0) {
      one.train(x, target, 0.1);
      two.train(x, target, 0.1, &second);
    } else {  // from an output already made, as an update after a query does
      one.train(x, one.output(x), target, 0.1);
      two.train(x, two.output(x, &second), target, 0.1, &second);
    }
    const Eigen::VectorXd a = one.output(x), b = two.output(x, &second);
    ASSERT_EQ(0, std::memcmp(a.data(), b.data(), sizeof(double) * kUnits)) << "outputs differ at step " << step;
  }
  EXPECT_EQ(0, std::memcmp(one.weights().data(), two.weights().data(),
                           sizeof(double) * static_cast<std::size_t>(one.weights().size())));
  EXPECT_GT(one.weights().cwiseAbs().sum(), 0.0);
  EXPECT_EQ(second.splits(), 20 * 3);  // every output and update of the big layer was split
}

}  // namespace
}  // namespace afford

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "afford/actions.hpp"
#include "environment/environment.hpp"
#include "predictors/predictors.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

struct Fixture : ::testing::Test {
  RunConfig imp = test::shippedConfig("base", System::IMP);
  std::vector<std::vector<std::uint8_t>> probes = Environment(imp).probeImages();

  Experience experience(int action, bool success, int probe = 0) const {
    Experience e;
    e.action = action;
    e.before_image = probes[probe];
    e.before_x = 0.2;
    e.before_y = 0.2;
    e.affordance = success;
    e.after_image = probes[(probe + 1) % probes.size()];
    e.after_x = action == kMove ? 0.6 : 0.2;
    e.after_y = action == kMove ? 0.7 : 0.2;
    if (action == kMove) e.target_x = 0.6, e.target_y = 0.7;
    return e;
  }
};

TEST_F(Fixture, AffordancesStartAtOneHalf) {
  const Predictors p(imp);
  for (const auto& row : p.table(probes))
    for (double v : row) EXPECT_DOUBLE_EQ(v, 0.5);
}

TEST_F(Fixture, LearningProgressWeightsHaveRandomSignAndFixedMagnitude) {
  const Predictors p(imp);
  const std::vector<std::uint8_t> black(1323, 0);  // only the bias weight contributes
  for (int a = 0; a < kNumActions; ++a)
    EXPECT_DOUBLE_EQ(std::abs(p.predict(black).learning_progress[a]), 0.00075);
  EXPECT_NE(p.weightsChecksum(), Predictors(test::shippedConfig("base", System::IMP, 2)).weightsChecksum());
  EXPECT_EQ(p.weightsChecksum(), Predictors(imp).weightsChecksum());
}

TEST_F(Fixture, TrainingMovesOnlyThePerformedActionsAffordance) {
  Predictors p(imp);
  const TrainingReport r = p.train(experience(kTurnGreen, true));
  EXPECT_DOUBLE_EQ(r.affordance_before, 0.5);
  EXPECT_GT(r.affordance_after, 0.5);
  const Prediction after = p.predict(probes[0]);
  EXPECT_DOUBLE_EQ(after.affordance[kTurnGreen], r.affordance_after);
  for (int a : {kMove, kTurnRed, kTurnBlue}) EXPECT_DOUBLE_EQ(after.affordance[a], 0.5);
}

TEST_F(Fixture, FailureLowersTheAffordance) {
  Predictors p(imp);
  EXPECT_LT(p.train(experience(kTurnRed, false)).affordance_after, 0.5);
}

TEST_F(Fixture, LearningProgressLearnsTheChangeOfTheAffordanceOutputForImpOnly) {
  Predictors p(imp);
  const double lp0 = p.predict(probes[0]).learning_progress[kTurnBlue];
  const TrainingReport r = p.train(experience(kTurnBlue, true));
  const double target = r.affordance_after - r.affordance_before;
  const double lp1 = p.predict(probes[0]).learning_progress[kTurnBlue];
  EXPECT_LT(std::abs(lp1 - target), std::abs(lp0 - target));

  Predictors ign(test::shippedConfig("base", System::IGN));
  const double before = ign.predict(probes[0]).learning_progress[kTurnBlue];
  ign.train(experience(kTurnBlue, true));
  EXPECT_DOUBLE_EQ(ign.predict(probes[0]).learning_progress[kTurnBlue], before);
}

TEST_F(Fixture, EffectPredictorsLearnFromSuccessesOnly) {
  Predictors p(imp);
  const auto what0 = p.whatEffect(kTurnGreen, probes[0]);
  p.train(experience(kTurnGreen, false));
  EXPECT_EQ(p.whatEffect(kTurnGreen, probes[0]), what0);
  p.train(experience(kTurnGreen, true));
  EXPECT_NE(p.whatEffect(kTurnGreen, probes[0]), what0);
}

TEST_F(Fixture, WhatEffectConvergesToTheObservedFocusImage) {
  Predictors p(imp);
  for (int k = 0; k < 1000; ++k) p.trainEffects(experience(kTurnGreen, true));
  const auto what = p.whatEffect(kTurnGreen, probes[0]);
  double err = 0;
  for (std::size_t i = 0; i < what.size(); ++i) err += std::abs(what[i] - probes[1][i] / 255.0);
  EXPECT_LT(err / what.size(), 0.01);
}

TEST_F(Fixture, WhereEffectOfMoveLearnsTheTarget) {
  Predictors p(imp);
  for (int k = 0; k < 300; ++k) {
    Experience e = experience(kMove, true);
    e.target_x = e.after_x = 0.2 + 0.6 * ((k * 37) % 100) / 100.0;
    e.target_y = e.after_y = 0.2 + 0.6 * ((k * 61) % 100) / 100.0;
    p.trainEffects(e);
  }
  const auto where = p.whereEffect(kMove, 0.2, 0.2, 0.55, 0.35);
  EXPECT_NEAR(where[0], 0.55, 0.02);
  EXPECT_NEAR(where[1], 0.35, 0.02);
}

TEST_F(Fixture, CheckpointRestoresEveryWeight) {
  Predictors trained(imp);
  for (int k = 0; k < 20; ++k) trained.train(experience(k % 4, k % 3 != 0, k % 9));
  const std::string path = test::tempDir("ckpt") + "/sub/predictors.ckpt";
  trained.save(path);
  Predictors fresh(imp);
  ASSERT_NE(fresh.weightsChecksum(), trained.weightsChecksum());
  fresh.load(path);
  EXPECT_EQ(fresh.weightsChecksum(), trained.weightsChecksum());
  EXPECT_EQ(fresh.executed(), trained.executed());
  EXPECT_EQ(fresh.whatEffect(kTurnRed, probes[4]), trained.whatEffect(kTurnRed, probes[4]));
}

TEST_F(Fixture, BadCheckpointsAreRefusedNamingTheFile) {
  const std::string dir = test::tempDir("ckpt-bad");
  Predictors p(imp);
  auto refusal = [&](const std::string& path) {
    try {
      p.load(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(refusal(dir + "/missing.ckpt").find("missing.ckpt: cannot be read"), std::string::npos);
  std::ofstream(dir + "/junk.ckpt") << "not a checkpoint at all";
  EXPECT_NE(refusal(dir + "/junk.ckpt").find("not an afford predictors checkpoint"), std::string::npos);
  p.save(dir + "/good.ckpt");
  std::filesystem::resize_file(dir + "/good.ckpt", std::filesystem::file_size(dir + "/good.ckpt") - 100);
  EXPECT_NE(refusal(dir + "/good.ckpt").find("truncated"), std::string::npos);
  Predictors other(test::shippedConfig("base", System::IMP, 1, {"eye.focus_side=19"}));
  other.save(dir + "/small.ckpt");
  EXPECT_NE(refusal(dir + "/small.ckpt").find("focus images of 1083 values"), std::string::npos);
}

TEST_F(Fixture, SplitTrainingEqualsWholeTraining) {
  Predictors whole(imp), split(imp);
  for (int k = 0; k < 10; ++k) {
    const Experience e = experience(k % 4, k % 3 != 0, k % 9);
    whole.train(e);
    split.trainAffordance(e);
    split.trainEffects(e);
  }
  EXPECT_EQ(whole.weightsChecksum(), split.weightsChecksum());
  EXPECT_NE(whole.weightsChecksum(), Predictors(imp).weightsChecksum());
}

}  // namespace
}  // namespace afford

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <iterator>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "afford/actions.hpp"
#include "afford/version.hpp"
#include "environment/environment.hpp"
#include "predictors/affordance.hpp"
#include "predictors/effect_trainer.hpp"
#include "predictors/predictors.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

// A checkpoint file's bytes, and its plain format (inflated; empty if it is not a packed checkpoint).
struct CheckpointBytes {
  std::string file, plain;
};
CheckpointBytes readCheckpoint(const std::string& path) {
  CheckpointBytes c;
  std::ifstream in(path, std::ios::binary);
  c.file.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (c.file.size() < 16 || c.file.substr(0, 8) != "AFFORDCZ") return c;
  std::uint64_t size = 0;
  std::memcpy(&size, c.file.data() + 8, sizeof size);
  std::string plain(size, '\0');
  uLongf plain_size = static_cast<uLongf>(size);
  if (uncompress(reinterpret_cast<Bytef*>(plain.data()), &plain_size, reinterpret_cast<const Bytef*>(c.file.data() + 16),
                 static_cast<uLong>(c.file.size() - 16)) == Z_OK &&
      plain_size == size)
    c.plain = std::move(plain);
  return c;
}

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

// Checkpoints are deflated (issue 13): the same weights come back, bit for
// bit, from a file a fraction of the plain one's size, and a plain checkpoint
// (as written before) still loads.
TEST_F(Fixture, CheckpointsAreCompressedLosslesslyAndPlainOnesStillLoad) {
  Predictors trained(imp);
  for (int k = 0; k < 200; ++k) trained.train(experience(k % 4, k % 3 != 0, k % 9));
  const std::string dir = test::tempDir("ckpt-packed");
  trained.save(dir + "/p.ckpt");
  const auto [file, plain] = readCheckpoint(dir + "/p.ckpt");
  ASSERT_EQ(file.substr(0, 8), "AFFORDCZ");
  ASSERT_FALSE(plain.empty()) << "the checkpoint does not inflate";
  EXPECT_EQ(plain.substr(0, 8), "AFFORDCK");
  EXPECT_EQ(plain.substr(plain.size() - 16), trained.weightsChecksum());  // the plain format ends with the checksum
  EXPECT_LT(file.size() * 5, plain.size()) << "compressed " << file.size() << " of " << plain.size() << " bytes";
  std::ofstream(dir + "/plain.ckpt", std::ios::binary) << plain;
  for (const char* name : {"/p.ckpt", "/plain.ckpt"}) {
    Predictors fresh(imp);
    fresh.load(dir + name);
    EXPECT_EQ(fresh.weightsChecksum(), trained.weightsChecksum()) << name;
    EXPECT_EQ(fresh.executed(), trained.executed()) << name;
    EXPECT_EQ(fresh.whatEffect(kTurnRed, probes[4]), trained.whatEffect(kTurnRed, probes[4])) << name;
  }
  // A flipped byte in the compressed data is refused, naming the file.
  std::string bad = file;
  bad[bad.size() / 2] = static_cast<char>(bad[bad.size() / 2] ^ 0x5a);
  std::ofstream(dir + "/bad.ckpt", std::ios::binary) << bad;
  Predictors p(imp);
  try {
    p.load(dir + "/bad.ckpt");
    FAIL() << "a corrupt compressed checkpoint was loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.ckpt"), std::string::npos) << e.what();
  }
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

// A what-effect output is computed once for a model as it stands (issue 57): a query asked again of an unchanged
// model, and the update after an action on the image just asked about, take the model's last output; the
// answers and the weights are those of predictors computing every output afresh.
TEST_F(Fixture, AnUnchangedModelsLastOutputServesTheQueryAskedAgainAndTheUpdateAfterIt) {
  Predictors asked(imp), plain(imp);  // the same updates; `plain` computes each output it is asked for afresh
  const auto afresh = [&](int action, int probe) {
    const std::int64_t computed = plain.whatOutputs();
    auto out = plain.whatEffect(action, probes[static_cast<std::size_t>(probe)]);
    EXPECT_EQ(plain.whatOutputs(), computed + 1);
    return out;
  };
  const auto turn_green = asked.whatEffect(kTurnGreen, probes[0]);
  const auto move = asked.whatEffect(kMove, probes[0]);
  EXPECT_EQ(asked.whatOutputs(), 2);
  EXPECT_EQ(asked.whatEffect(kTurnGreen, probes[0]), turn_green);  // asked again: the same model, the same image
  EXPECT_EQ(asked.whatOutputs(), 2);
  EXPECT_EQ(asked.whatEffect(kTurnGreen, probes[1]), afresh(kTurnGreen, 1));  // another image: computed
  EXPECT_EQ(asked.whatOutputs(), 3);
  EXPECT_EQ(asked.whatEffect(kTurnGreen, probes[0]), turn_green);
  EXPECT_EQ(asked.whatOutputs(), 4);

  const auto trainBoth = [&](const Experience& e) {
    asked.train(e);
    plain.train(e);
    EXPECT_EQ(asked.weightsChecksum(), plain.weightsChecksum());
  };
  // The action asked about, on that image: its update starts from the query's output.
  trainBoth(experience(kTurnGreen, true, 0));
  EXPECT_EQ(asked.whatOutputs(), 4);
  // That model learned: its output is computed again; the move model's is still its last.
  EXPECT_NE(asked.whatEffect(kTurnGreen, probes[0]), turn_green);
  EXPECT_EQ(asked.whatEffect(kTurnGreen, probes[0]), afresh(kTurnGreen, 0));
  EXPECT_EQ(asked.whatEffect(kMove, probes[0]), move);
  EXPECT_EQ(asked.whatOutputs(), 5);
  // An update of an image other than the last asked computes its own output, as before.
  trainBoth(experience(kMove, true, 3));
  EXPECT_EQ(asked.whatOutputs(), 6);
  EXPECT_EQ(asked.whatEffect(kMove, probes[0]), afresh(kMove, 0));

  // Weights loaded: no earlier output stands for them.
  const std::string dir = test::tempDir("last-output");
  asked.save(dir + "/asked.ckpt");
  Predictors other(imp);
  for (int k = 0; k < 6; ++k) other.train(experience(k % 4, true, k % 9));
  const auto before = other.whatEffect(kMove, probes[0]);
  other.load(dir + "/asked.ckpt");
  EXPECT_NE(other.whatEffect(kMove, probes[0]), before);
  EXPECT_EQ(other.whatEffect(kMove, probes[0]), asked.whatEffect(kMove, probes[0]));
}

// The worker makes the outputs a query is expected to ask for after the updates queued before them: the query
// finds them made, and they are those of the models as updated.
TEST_F(Fixture, TheWorkerMakesTheOutputsAheadAfterTheUpdatesBeforeThem) {
  Predictors ahead(imp), plain(imp);
  plain.train(experience(kTurnRed, true, 2));
  const auto turn_red = plain.whatEffect(kTurnRed, probes[2]), move = plain.whatEffect(kMove, probes[2]);
  {
    EffectTrainer worker(ahead);
    TrainingReport r = ahead.trainAffordance(experience(kTurnRed, true, 2));
    std::vector<Memory::Ref> updates = std::move(r.effect_updates);
    ASSERT_EQ(updates.size(), 1u);
    worker.push(std::move(updates));
    worker.ahead({kTurnRed, kMove}, probes[2]);
    worker.drain();
  }
  EXPECT_EQ(ahead.whatOutputs(), 3);  // the update's own, then the two ahead
  EXPECT_EQ(ahead.whatEffect(kTurnRed, probes[2]), turn_red);
  EXPECT_EQ(ahead.whatEffect(kMove, probes[2]), move);
  EXPECT_EQ(ahead.whatOutputs(), 3);
  EXPECT_EQ(ahead.weightsChecksum(), plain.weightsChecksum());
}

// ---- the memory of issue 11 (docs/model.md#memory, #replay) ----------------------------

TEST_F(Fixture, WithoutTheMemoryOptionsThePredictorsKeepNoMemory) {
  Predictors p(imp);
  const Prediction seen = p.see(probes[0], 0);
  EXPECT_FALSE(seen.remembered);
  EXPECT_EQ(p.memory(), nullptr);
  const TrainingReport r = p.trainAffordance(experience(kMove, true), 0);
  ASSERT_EQ(r.effect_updates.size(), 1u);  // its own forward-model update, nothing replayed
  EXPECT_EQ(p.replayedUpdates(), 0);
}

TEST_F(Fixture, ReplayKeepsTrainingRememberedExperiencesOfOtherLooks) {
  // One success on the red square, then many failures on the green one: the red square's affordance is trained
  // by replay at each of them; without replay it stays where its one update left it.
  const RunConfig with_replay = test::shippedConfig("base", System::IGN, 1, {"predictors.replay.enabled=true"});
  Predictors replaying(with_replay), plain(test::shippedConfig("base", System::IGN));
  for (Predictors* p : {&replaying, &plain}) {
    p->train(experience(kTurnGreen, true, 0), 0, p->see(probes[0], 0).look);
    for (int t = 1; t <= 30; ++t) p->train(experience(kTurnGreen, false, 1), t, p->see(probes[1], t).look);
  }
  EXPECT_GT(replaying.predict(probes[0]).affordance[kTurnGreen], plain.predict(probes[0]).affordance[kTurnGreen] + 0.1);
  EXPECT_EQ(replaying.replayedUpdates(), 31 * with_replay.predictors.replay.ratio);
  EXPECT_EQ(replaying.memory()->looks(), 2);
}

TEST_F(Fixture, EachStepMakesEffectsRatioForwardModelUpdatesItsOwnFirst) {
  std::vector<std::string> options = test::kMemoryOptions;
  options.push_back("predictors.replay.effects_ratio=3");
  Predictors p(test::shippedConfig("base", System::IMP, 1, options));
  const int look = p.see(probes[0], 0).look;
  const TrainingReport failure = p.trainAffordance(experience(kTurnBlue, false), 0, look);
  EXPECT_TRUE(failure.effect_updates.empty());  // nothing remembered with an effect yet
  const Experience e = experience(kTurnGreen, true);
  const TrainingReport success = p.trainAffordance(e, 1, look);
  ASSERT_EQ(success.effect_updates.size(), 3u);  // its own, and 2 remembered
  EXPECT_EQ(success.effect_updates[0]->action, kTurnGreen);
  EXPECT_EQ(success.effect_updates[0]->after_image, e.after_image);
  for (const auto& u : success.effect_updates) EXPECT_TRUE(u->affordance);
  EXPECT_EQ(p.replay(2).size(), 3u);  // a pass: all 3 remembered
  EXPECT_EQ(p.replayedEffectUpdates(), 5);
  EXPECT_THROW(p.trainAffordance(e, 3), std::invalid_argument);  // a memory files it under a look
}

TEST_F(Fixture, SeeReportsWhatWasTriedOnTheLook) {
  Predictors p(test::shippedConfig("base", System::IMP, 1, test::kMemoryOptions));
  int look = p.see(probes[2], 10).look;
  p.train(experience(kTurnRed, true, 2), 10, look);
  const Prediction later = p.see(probes[2], 25);
  EXPECT_TRUE(later.remembered);
  EXPECT_EQ(later.look, look);
  EXPECT_EQ(later.tried_ago, (Memory::TriedAgo{-1, -1, 15, -1}));
  EXPECT_EQ(later.affordance, p.predict(probes[2]).affordance);
}

TEST_F(Fixture, TheCheckpointHoldsTheMemoryAndTheChecksumCoversIt) {
  const RunConfig c = test::shippedConfig("base", System::IMP, 1, test::kMemoryOptions);
  Predictors trained(c);
  for (int k = 0; k < 20; ++k) trained.train(experience(k % 4, k % 3 != 0, k % 9), k, trained.see(probes[k % 9], k).look);
  const std::string dir = test::tempDir("ckpt-memory");
  trained.save(dir + "/p.ckpt");
  const std::string saved = trained.weightsChecksum();
  Predictors fresh(c);
  fresh.load(dir + "/p.ckpt");
  EXPECT_EQ(fresh.weightsChecksum(), trained.weightsChecksum());
  EXPECT_EQ(fresh.memory()->experiences(), 20u);
  EXPECT_EQ(fresh.see(probes[4], 30).tried_ago, trained.see(probes[4], 30).tried_ago);
  // The same experiences continue the same way from either.
  for (Predictors* p : {&fresh, &trained}) p->train(experience(kMove, true, 5), 31, p->see(probes[5], 31).look);
  EXPECT_EQ(fresh.weightsChecksum(), trained.weightsChecksum());
  // The checksum says more than the weights: the same weights with another memory differ.
  Predictors same_weights(c);
  same_weights.load(dir + "/p.ckpt");
  same_weights.see(probes[8], 40);  // a look seen later
  EXPECT_NE(same_weights.weightsChecksum(), trained.weightsChecksum());
  // Predictors that keep a memory refuse a checkpoint without one; an agent that kept one is restored whole,
  // whatever the loading run does with it (the extrinsic phase loads it).
  Predictors paper(imp);
  paper.save(dir + "/paper.ckpt");
  Predictors memoryless_into_memory(c);
  try {
    memoryless_into_memory.load(dir + "/paper.ckpt");
    FAIL() << "a checkpoint without a memory was taken by predictors that keep one";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("holds no memory"), std::string::npos) << e.what();
  }
  Predictors into_paper(imp);
  into_paper.load(dir + "/p.ckpt");
  EXPECT_EQ(into_paper.weightsChecksum(), saved);
}

// ---- the affordance component (predictors/affordance.hpp, docs/writing-a-component.md) ----

// A component of another kind: a constant affordance per action, nudged by each outcome; its state one array.
class Tally : public AffordanceComponent {
 public:
  void predict(const FocusView&, PerAction& affordance, PerAction& learning_progress) const override {
    for (int a = 0; a < kNumActions; ++a) affordance[a] = counts_[a] / (1.0 + counts_[a]), learning_progress[a] = 0;
  }
  Learned learn(const FocusView& f, int a, bool succeeded) override {
    Learned l;
    PerAction before{}, lp{};
    predict(f, before, lp);
    relearn(f, a, succeeded);
    PerAction after{};
    predict(f, after, lp);
    l.before = before[a];
    l.after = after[a];
    return l;
  }
  void relearn(const FocusView&, int a, bool succeeded) override { counts_[a] += succeeded ? 1 : 0; }
  std::vector<StateArray> state(int a) override {
    if (a == 0) return {{counts_.data(), counts_.size()}};
    return {};
  }

 private:
  std::array<double, kNumActions> counts_{};
};

TEST_F(Fixture, TheAffordanceKindPicksTheComponentAndItsStateIsTheChecksumsAndTheCheckpoints) {
  registerAffordance("tally", [](const AffordanceParams&) { return std::make_unique<Tally>(); });
  RunConfig tally = imp;
  tally.predictors.affordance_kind = "tally";
  Predictors p(tally), paper(imp);
  for (int k = 0; k < 12; ++k) p.train(experience(k % 4, k % 3 != 0, k % 9)), paper.train(experience(k % 4, k % 3 != 0, k % 9));
  p.train(experience(kTurnBlue, true)), paper.train(experience(kTurnBlue, true));
  // each action succeeded twice in its three tries (k % 3 != 0), blue once more
  EXPECT_DOUBLE_EQ(p.predict(probes[0]).affordance[kTurnGreen], 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(p.predict(probes[0]).affordance[kTurnBlue], 3.0 / 4.0);
  // The component's state is what the checksum takes: the forward models alike, the affordances not.
  EXPECT_NE(p.weightsChecksum(), paper.weightsChecksum());
  EXPECT_EQ(p.whatEffect(kTurnRed, probes[4]), paper.whatEffect(kTurnRed, probes[4]));
  const std::string dir = test::tempDir("ckpt-kind");
  p.save(dir + "/tally.ckpt");
  paper.save(dir + "/paper.ckpt");
  Predictors back(tally);
  back.load(dir + "/tally.ckpt");
  EXPECT_EQ(back.weightsChecksum(), p.weightsChecksum());
  EXPECT_DOUBLE_EQ(back.predict(probes[0]).affordance[kTurnGreen], 2.0 / 3.0);
  // A checkpoint names its component: another kind does not load it.
  auto refusal = [](Predictors& into, const std::string& path) {
    try {
      into.load(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  Predictors wrong_paper(imp), wrong_tally(tally);
  EXPECT_NE(refusal(wrong_paper, dir + "/tally.ckpt")
                .find("its affordance predictor is 'tally', this run's predictors.affordance.kind is 'paper'"),
            std::string::npos);
  EXPECT_NE(refusal(wrong_tally, dir + "/paper.ckpt")
                .find("its affordance predictor is 'paper', this run's predictors.affordance.kind is 'tally'"),
            std::string::npos);
}

TEST_F(Fixture, ACheckpointSaysItsFormatItsComponentAndTheReleaseThatWroteIt) {
  Predictors p(imp);
  const std::string dir = test::tempDir("ckpt-format");
  p.save(dir + "/p.ckpt");
  const std::string plain = readCheckpoint(dir + "/p.ckpt").plain;
  ASSERT_FALSE(plain.empty()) << "the checkpoint does not inflate";
  std::uint32_t version = 0;
  std::memcpy(&version, plain.data() + 8, sizeof version);
  EXPECT_EQ(version, 4u);
  const std::string release = affordVersion();
  EXPECT_NE(plain.find("paper"), std::string::npos);
  EXPECT_NE(plain.find(release), std::string::npos);
  EXPECT_EQ(plain.size(), 8 + 8 + (4 + 5) + (4 + release.size()) + 4 * (2 * 1324 + 1323 * 1324) * 8 +
                              (5 + 3 + 3 + 3) * 2 * 8 + 2 * 4 * 8 + 1 + 16);
  Predictors back(imp);
  back.load(dir + "/p.ckpt");
  EXPECT_EQ(back.checkpointWrittenBy(), release);
  EXPECT_EQ(back.weightsChecksum(), p.weightsChecksum());
}

TEST(Checkpoints, EveryCheckpointAnEarlierReleaseWroteLoadsToTheWeightsItKept) {
  // tests/data/compat/<release>: each run's checkpoint and each stored agent's, loaded with the run's
  // configuration (its log's manifest), give the checksum of the weights the release kept for it.
  namespace fs = std::filesystem;
  int loaded = 0;
  for (const auto& release : fs::directory_iterator(std::string(AFFORD_SOURCE_DIR) + "/tests/data/compat")) {
    const fs::path logs = release.path() / "experiment/logs";
    const std::string name = release.path().filename().string();
    const auto load = [&](const fs::path& ckpt, const std::string& run_id, const std::string& checksum) {
      SCOPED_TRACE(ckpt.string());
      const std::string config_yaml = test::readJson(logs / run_id / "manifest.json")["config_yaml"];
      Predictors p(parseRunConfigText(config_yaml));
      p.load(ckpt.string());
      EXPECT_EQ(p.weightsChecksum(), checksum);
      // (0.1.0 wrote format 2, which does not say; later ones say themselves: "0.2.0+<commit>")
      EXPECT_EQ(p.checkpointWrittenBy().substr(0, name == "0.1.0" ? std::string::npos : name.size() + 1),
                name == "0.1.0" ? "0.1.0 or earlier" : name + "+");
      ++loaded;
    };
    for (const auto& dir : fs::directory_iterator(logs)) {
      if (dir.path().filename() == "agents") {
        for (const auto& agent : fs::directory_iterator(dir.path())) {
          const auto stored = test::readJson(agent.path() / "outcome.json");
          load(agent.path() / "predictors.ckpt", stored["run_id"], stored["outcome"]["weights_checksum"]);
        }
      } else if (fs::exists(dir.path() / "predictors.ckpt")) {
        const std::string id = dir.path().filename().string();
        load(dir.path() / "predictors.ckpt", id,
             test::readJson(release.path() / "experiment/runs" / (id + ".json"))["outcome"]["weights_checksum"]);
      }
    }
  }
  EXPECT_GE(loaded, 4) << "the corpus holds fewer checkpoints than it was recorded with";
}

TEST_F(Fixture, AnAffordanceKindNotBuiltInIsRefusedNamingTheKey) {
  RunConfig c = imp;
  c.predictors.affordance_kind = "nowhere";
  try {
    Predictors p(c);
    ADD_FAILURE() << "kind 'nowhere' was taken";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("predictors.affordance.kind"), std::string::npos) << what;
    EXPECT_NE(what.find("'nowhere'"), std::string::npos) << what;
    EXPECT_NE(what.find("--process predictors="), std::string::npos) << what;
  }
}

TEST_F(Fixture, MemoryKeepOverridesWhatTheOtherKeysWouldKeep) {
  RunConfig always = imp;
  always.predictors.memory.keep = MemoryKeep::Always;
  EXPECT_NE(Predictors(always).memory(), nullptr);
  RunConfig never = test::shippedConfig("base", System::IMP, 1, {"motivation.kind=novelty", "predictors.memory.keep=never"});
  EXPECT_EQ(Predictors(never).memory(), nullptr);
  EXPECT_NE(Predictors(test::shippedConfig("base", System::IMP, 1, {"motivation.kind=novelty"})).memory(), nullptr);
  try {
    test::shippedConfig("base", System::IMP, 1, {"predictors.replay.enabled=true", "predictors.memory.keep=never"});
    ADD_FAILURE() << "replay without a memory was taken";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("predictors.memory.keep"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("predictors.replay.enabled"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace afford

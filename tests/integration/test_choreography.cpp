// The whole choreography hosted in one process over memq:// (the same node
// code as the real processes): ordering, repeatability, bad input, bad config.
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <memory>
#include <sstream>

#include "afford/protocol.hpp"
#include "afford/decision_t.hpp"
#include "experiment/run/driver.hpp"
#include "afford/focus_t.hpp"
#include "afford/resend_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/scene_t.hpp"
#include "afford/seal.hpp"
#include "environment/node.hpp"
#include "eye/node.hpp"
#include "motivation/node.hpp"
#include "planner/node.hpp"
#include "predictors/node.hpp"
#include "tests/in_process.hpp"
#include "tests/reference_loops.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

using test::Bytes;
using test::Injector;
using test::InProcessRun;
using test::Restart;
using test::baseYaml;

TEST(Choreography, ARunHasOnePredictionAndOneDecisionPerStepInOrder) {
  InProcessRun run(baseYaml(System::IMP, 200), System::IMP, 3, 200);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  EXPECT_EQ(run.count(ch::focus.name), 200);
  EXPECT_EQ(run.count(ch::prediction.name), 200);
  EXPECT_EQ(run.count(ch::decision.name), 200);
  EXPECT_GT(run.count(ch::effect.name), 0);
  EXPECT_EQ(run.count(ch::effect.name), test::trainingReports(run.events));  // every action learned from once
  EXPECT_EQ(run.count(ch::result.name), 1);
  ASSERT_GE(run.events.size(), 3u);
  EXPECT_EQ(run.events[0].channel, ch::runConfig.name);
  EXPECT_EQ(run.events[1].channel, ch::runControl.name);
  EXPECT_EQ(run.events[2].channel, ch::probe.name);
  EXPECT_EQ(run.events[3].channel, ch::scene.name);
  // Curves at steps 0, 100, 200.
  ASSERT_EQ(run.outcome.curve.size(), 3u);
  EXPECT_EQ(run.outcome.curve[1].step, 100);
  EXPECT_EQ(run.outcome.curve.back().affordance.size(), 9u);
  EXPECT_EQ(run.outcome.weights_checksum.size(), 16u);
}

// Two requests of one run are two runs (their chains start from each request's number), whose messages are the
// same but for the bytes that name the request.
TEST(Choreography, RepeatedRunsAreByteIdenticalButForTheirRequestAndSeedsDiffer) {
  InProcessRun a(baseYaml(System::IGN, 300), System::IGN, 3, 300);
  InProcessRun b(baseYaml(System::IGN, 300), System::IGN, 3, 300);
  ASSERT_TRUE(a.outcome.ok && b.outcome.ok);
  ASSERT_EQ(a.events.size(), b.events.size());
  int differ = 0;
  for (std::size_t i = 0; i < a.events.size(); ++i) {
    ASSERT_EQ(a.events[i].channel, b.events[i].channel) << "event " << i;
    differ += a.events[i].data != b.events[i].data;
    ASSERT_EQ(test::withoutRequest(a.events[i].channel, a.events[i].data),
              test::withoutRequest(b.events[i].channel, b.events[i].data))
        << "event " << i << " on " << a.events[i].channel;
  }
  EXPECT_EQ(differ, static_cast<int>(a.events.size()));  // every message names its own request
  EXPECT_EQ(a.outcome.weights_checksum, b.outcome.weights_checksum);
  InProcessRun c(baseYaml(System::IGN, 300, 4), System::IGN, 4, 300);
  EXPECT_NE(a.outcome.weights_checksum, c.outcome.weights_checksum);
}

// The processes' choreography computes exactly Algorithm 1 as a plain loop.
TEST(Choreography, ComputesWhatThePlainAlgorithmComputes) {
  for (System s : {System::FIX, System::IGN, System::IMP}) {
    InProcessRun run(baseYaml(s, 400), s, 3, 400);
    ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
    const RunConfig c = parseRunConfigText(baseYaml(s, 400));
    EXPECT_EQ(run.outcome.weights_checksum, test::runIntrinsic(c).weightsChecksum()) << toString(s);
  }
}

// The paper's agent is what it was before the memory options of issue 11
// existed: the weights of these runs were recorded at a5ce55f, the commit
// before them, and nothing may change them while the options are off.
TEST(Choreography, ThePapersAgentIsUnchangedByTheMemoryOptions) {
  const std::map<System, std::string> before = {
      {System::FIX, "9a85cf039de6aeaa"}, {System::IGN, "fbb9808d891333cd"}, {System::IMP, "2a074f572fa66b79"}};
  for (const auto& [s, checksum] : before) {
    InProcessRun run(baseYaml(s, 500, 1), s, 1, 500);
    ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
    EXPECT_EQ(run.outcome.weights_checksum, checksum) << toString(s);
  }
}

// With replay and revisits, the choreography still computes exactly the plain loop: the predictors see each focus
// once, file each experience under its look, and replay by (seed, step); the motivation revisits on what they report.
TEST(Choreography, WithTheMemoryOptionsComputesWhatThePlainAlgorithmComputes) {
  for (System s : {System::FIX, System::IGN, System::IMP}) {
    const std::string yaml = test::shippedConfigYaml("base", s, 3, 400, test::kMemoryOptions);
    InProcessRun run(yaml, s, 3, 400);
    ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
    const Predictors plain = test::runIntrinsic(parseRunConfigText(yaml));
    EXPECT_EQ(run.outcome.weights_checksum, plain.weightsChecksum()) << toString(s);
    EXPECT_GT(plain.replayedUpdates(), 0) << toString(s);
    int revisits = 0;
    for (const auto& e : run.events)
      if (e.channel == ch::decision.name) {
        decision_t d;
        d.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
        revisits += d.revisit;
      }
    EXPECT_GE(revisits, 4) << toString(s);  // at least every action once on the first look
  }
}

TEST(Choreography, ProcessesLeftInAnEarlierRunAreStoppedAgain) {
  InProcessRun run(baseYaml(System::IMP, 50), System::IMP, 3, 50, {}, 50, /*leave_stale_run=*/true);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  EXPECT_NE(run.log.str().find("still in run 'stale-run': told to stop again"), std::string::npos) << run.log.str();
}

TEST(Choreography, ObservedChangeThresholdInputRuns) {
  RunRequest req{"base", System::IMP, 3, 300, {"motivation.imp_threshold_input=observed_change"}};
  const std::string yaml = emitYaml(effectiveConfig(std::string(AFFORD_SOURCE_DIR) + "/config", req));
  InProcessRun run(yaml, System::IMP, 3, 300);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  EXPECT_EQ(run.count(ch::decision.name), 300);
  EXPECT_EQ(run.outcome.weights_checksum, test::runIntrinsic(parseRunConfigText(yaml)).weightsChecksum());
}

TEST(Choreography, LateObjectsEnterTheSceneAtTheirStep) {
  const std::string yaml = test::shippedConfigYaml("late1", System::IMP, 3, 2050);
  InProcessRun run(yaml, System::IMP, 3, 2050);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  int appeared = 0;
  for (const auto& e : run.events) {
    if (e.channel != ch::scene.name) continue;
    scene_t s;
    s.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
    if (s.cause == scene_t::CAUSE_OBJECTS_APPEARED) {
      ++appeared;
      EXPECT_EQ(s.step, 2000);
    }
    if (s.step == 1999) {
      EXPECT_TRUE(s.changes_next);
    }
  }
  EXPECT_EQ(appeared, 1);
  EXPECT_EQ(run.outcome.weights_checksum, test::runIntrinsic(parseRunConfigText(yaml)).weightsChecksum());
}

// Late objects arriving right after two passes: no scene was published for
// the step before theirs (nothing changed), so only the run's world.objects
// tell the eye to wait for the newcomers' scene instead of scanning the old
// one. (A run stalled here once: the eye scanned ahead, then refused the
// newcomers' scene as past, and asked for it again without end.)
TEST(Choreography, LateObjectsAfterTwoPassesStartTheirStepWithTheirScene) {
  YAML::Node c = YAML::Load(test::shippedConfigYaml("late1", System::IMP, 4, 400));
  for (YAML::Node o : c["world"]["objects"])
    if (o["appears_at"].as<int>() > 0) o["appears_at"] = 10000;  // not in this run
  InProcessRun probe(YAML::Dump(c), System::IMP, 4, 400);
  ASSERT_TRUE(probe.outcome.ok) << probe.outcome.error;
  std::map<std::int64_t, bool> acted;
  for (const auto& e : probe.events)
    if (e.channel == ch::decision.name) {
      decision_t d;
      d.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
      acted[d.step] = d.acted;
    }
  std::int64_t at = -1;
  for (std::int64_t j = 50; j < 390 && at < 0; ++j)
    if (!acted.at(j - 2) && !acted.at(j - 1)) at = j;
  ASSERT_GT(at, 0) << "no two passes in a row in 400 steps of IMP";
  for (YAML::Node o : c["world"]["objects"])
    if (o["appears_at"].as<int>() > 0) o["appears_at"] = at;
  const std::string yaml = YAML::Dump(c);
  InProcessRun run(yaml, System::IMP, 4, 400);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  std::int64_t scene_at = -1, focus_at = -1;  // event indices
  for (std::size_t i = 0; i < run.events.size(); ++i) {
    const auto& e = run.events[i];
    if (e.channel == ch::scene.name) {
      scene_t s;
      s.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
      if (s.cause == scene_t::CAUSE_OBJECTS_APPEARED) scene_at = static_cast<std::int64_t>(i);
    }
    if (e.channel == ch::focus.name) {
      focus_t f;
      f.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
      if (f.step == at && focus_at < 0) focus_at = static_cast<std::int64_t>(i);
    }
  }
  ASSERT_GE(scene_at, 0);
  EXPECT_GT(focus_at, scene_at) << "the focus of step " << at << " came before the newcomers' scene";
  EXPECT_EQ(run.log.str().find("dropped message"), std::string::npos) << run.log.str().substr(0, 4000);
  EXPECT_EQ(run.outcome.weights_checksum, test::runIntrinsic(parseRunConfigText(yaml)).weightsChecksum());
}

// The runner reads the configuration it is to send: one no process could take
// fails the run naming the key, and no process is configured with it.
TEST(Choreography, ARejectedConfigFailsTheRunNamingTheKeyBeforeAnyProcessTakesIt) {
  YAML::Node root = effectiveConfig(std::string(AFFORD_SOURCE_DIR) + "/config", RunRequest{"base", System::IMP, 3, 50, {}});
  root["eye"]["focus_side"] = 20;
  InProcessRun run(emitYaml(root), System::IMP, 3, 50);
  EXPECT_FALSE(run.outcome.ok);
  EXPECT_NE(run.outcome.error.find("eye.focus_side"), std::string::npos) << run.outcome.error;
  EXPECT_EQ(run.count(ch::runConfig.name), 0);
  EXPECT_EQ(run.log.str().find("configured for run"), std::string::npos) << run.log.str();
}

// Live restart in one process: a node destroyed mid-run and made anew is
// given the run again by the runner, goes on from its latest snapshot (taken
// every 100 steps here), catches up from what its peers still hold (RESEND:
// only what followed its snapshot), and the run ends as if nothing had
// happened; the snapshots themselves change nothing of the run. The eye and
// the predictors write theirs in a forked copy of the process (as the
// processes do), the others on their own path. (Restarts from the run's
// start: the memory options' test below, tests/restart.)
TEST(Choreography, AProcessRestartedMidRunGoesOnFromItsSnapshotAndTheRunIsUnchanged) {
  const std::string yaml = test::shippedConfigYaml("base", System::IMP, 3, 400, {"protocol.recovery.snapshot_steps=100"});
  InProcessRun plain(baseYaml(System::IMP, 400), System::IMP, 3, 400);
  ASSERT_TRUE(plain.outcome.ok) << plain.outcome.error;
  for (const std::string& p : runProcesses(Phase::Intrinsic, /*recorded=*/false)) {
    const std::string snapshots = test::tempDir("choreography-snapshots-" + p);
    const bool fork = p == "eye" || p == "predictors";
    InProcessRun run(yaml, System::IMP, 3, 400, {}, 50, false, Restart{p, 250, snapshots, false, fork});
    ASSERT_TRUE(run.outcome.ok) << p << ": " << run.outcome.error;
    ASSERT_TRUE(run.restarted) << p;
    EXPECT_GE(run.restarted_at, 250) << p;
    EXPECT_LT(run.restarted_at, 399) << p;
    // Its latest durable one: the one of step 200 is made durable while the run goes on, and on a loaded
    // machine it may not be there yet at step 250.
    EXPECT_GE(run.restored_step, 100) << p << " went on from no snapshot";
    EXPECT_LE(run.restored_step, run.restarted_at) << p;
    // What it asked for again came after its snapshot: it did not pull the run from its start.
    for (const auto& e : run.events)
      if (e.channel == ch::resend.name) {
        resend_t r;
        r.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
        if (r.requester == p) {
          EXPECT_GT(r.first, 0) << p << " asked for " << r.channel << " from its start";
        }
      }
    EXPECT_FALSE(std::filesystem::exists(snapshots + "/test-run")) << "the run's end removes its snapshots";
    EXPECT_NE(run.log.str().find(std::string("process ") + p + " is free again"), std::string::npos) << run.log.str();
    EXPECT_EQ(run.outcome.weights_checksum, plain.outcome.weights_checksum) << p;
    ASSERT_EQ(run.outcome.curve.size(), plain.outcome.curve.size()) << p;
    for (std::size_t i = 0; i < plain.outcome.curve.size(); ++i)
      EXPECT_EQ(run.outcome.curve[i].affordance, plain.outcome.curve[i].affordance) << p << " curve point " << i;
  }
}

// Ctrl-C in a run: the process takes a snapshot as it leaves, says no final counts (the run goes on), and
// started again it goes on from exactly there; the run is unchanged.
TEST(Choreography, AProcessStoppedBySigintMidRunGoesOnFromWhereItLeft) {
  const std::string yaml = test::shippedConfigYaml("base", System::IMP, 3, 400, {"protocol.recovery.snapshot_steps=100"});
  InProcessRun plain(baseYaml(System::IMP, 400), System::IMP, 3, 400);
  ASSERT_TRUE(plain.outcome.ok) << plain.outcome.error;
  InProcessRun run(yaml, System::IMP, 3, 400, {}, 50, false,
                   Restart{"eye", 250, test::tempDir("choreography-sigint"), /*graceful=*/true});
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  EXPECT_EQ(run.restored_step, run.restarted_at) << "its snapshot is the one it took as it left";
  EXPECT_EQ(run.log.str().find("at or beyond"), std::string::npos) << run.log.str().substr(0, 3000);
  EXPECT_EQ(run.outcome.weights_checksum, plain.outcome.weights_checksum);
}

// The memory is part of the predictors' state: a restarted process rebuilds it from the run's messages, and the
// run ends with the same weights, memory and decisions.
TEST(Choreography, WithTheMemoryOptionsARestartedProcessCatchesUpAndTheRunIsUnchanged) {
  const std::string yaml = test::shippedConfigYaml("base", System::IGN, 3, 400, test::kMemoryOptions);
  InProcessRun plain(yaml, System::IGN, 3, 400);
  ASSERT_TRUE(plain.outcome.ok) << plain.outcome.error;
  for (const char* p : {"predictors", "motivation"}) {
    InProcessRun run(yaml, System::IGN, 3, 400, {}, 50, false, Restart{p, 150, ""});
    ASSERT_TRUE(run.outcome.ok) << p << ": " << run.outcome.error;
    ASSERT_TRUE(run.restarted) << p;
    EXPECT_EQ(run.outcome.weights_checksum, plain.outcome.weights_checksum) << p;
    ASSERT_EQ(run.outcome.curve.size(), plain.outcome.curve.size()) << p;
    for (std::size_t i = 0; i < plain.outcome.curve.size(); ++i)
      EXPECT_EQ(run.outcome.curve[i].affordance, plain.outcome.curve[i].affordance) << p << " curve point " << i;
  }
}

// One extrinsic test both ways: as the process choreography (in one process)
// and as the plain loop of Algorithm 2 or 3 with the same trained agent.
struct BothWays {
  RunOutcome run;
  test::GoalTestOutcome plain;
};
BothWays runBothWays(const std::string& yaml, std::int64_t seed, const std::string& checkpoint) {
  BothWays out;
  out.run = InProcessRun(yaml, System::IMP, seed, 125).outcome;
  const RunConfig c = parseRunConfigText(yaml);
  Predictors loaded(c);
  loaded.load(checkpoint);
  out.plain = test::runGoalTest(c, *c.scenario, loaded);
  return out;
}

// The extrinsic phase as a choreography (environment, eye, predictors,
// planner) reaches exactly the outcome of Algorithm 2 as a plain loop.
TEST(Choreography, ExtrinsicTestsMatchThePlainPlanner) {
  const std::string dir = test::tempDir("extrinsic");
  const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  const RunConfig train = parseRunConfigText(baseYaml(System::IMP, 6000, 5));
  test::runIntrinsic(train).save(dir + "/predictors.ckpt");
  for (int k : {1, 3, 5}) {
    const std::string scenario = "scenario" + std::to_string(k);
    const std::string yaml = emitYaml(
        extrinsicConfig(config_dir, RunRequest{"base", System::IMP, 50 + k, std::nullopt, {}}, dir + "/predictors.ckpt", scenario));
    const BothWays both = runBothWays(yaml, 50 + k, dir + "/predictors.ckpt");
    ASSERT_TRUE(both.run.ok) << both.run.error;
    const test::GoalTestOutcome& ref = both.plain;
    const ExtrinsicOutcome& got = both.run.extrinsic;
    EXPECT_EQ(got.scenario, scenario);
    // Scenario 5's moved circle is at a new pixel phase that the learned move
    // prediction misses by about the planner's image_match (docs/results-discussion.md):
    // some agents fail it, as in the authors' code. Both ways must agree either way.
    if (k != 5) {
      EXPECT_TRUE(got.success) << scenario;
    }
    EXPECT_EQ(got.success, ref.success) << scenario;
    EXPECT_EQ(got.completion, ref.completion) << scenario;
    EXPECT_EQ(got.attempts, ref.attempts) << scenario;
    ASSERT_EQ(got.sub_goals.size(), ref.sub_goals.size()) << scenario;
    for (std::size_t i = 0; i < ref.sub_goals.size(); ++i) {
      EXPECT_EQ(got.sub_goals[i].actions_checked, ref.sub_goals[i].actions_checked) << scenario << " sub-goal " << i;
      EXPECT_EQ(got.sub_goals[i].reached, ref.sub_goals[i].reached) << scenario << " sub-goal " << i;
    }
  }
}

// With the authors' eye (issue 28) the choreography computes what the plain
// loops compute, in both phases: every SCENE lists its objects' true centres
// (the goal's for the goal scene), and the eye's windows go there. Without the
// option no SCENE lists any, and the agent learns otherwise.
TEST(Choreography, WithTheAuthorsEyeComputesWhatThePlainAlgorithmComputes) {
  const std::vector<std::string> option = {"eye.fovea=true_centre"};
  const std::string yaml = test::shippedConfigYaml("base", System::IMP, 3, 400, option);
  InProcessRun run(yaml, System::IMP, 3, 400);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  EXPECT_EQ(run.outcome.weights_checksum, test::runIntrinsic(parseRunConfigText(yaml)).weightsChecksum());
  const auto listed = [](const InProcessRun& r) {
    std::set<int> counts;
    for (const auto& e : r.events)
      if (e.channel == ch::scene.name) {
        scene_t m;
        m.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
        counts.insert(m.n_objects);
      }
    return counts;
  };
  EXPECT_EQ(listed(run), std::set<int>{9});
  InProcessRun ours(test::shippedConfigYaml("base", System::IMP, 3, 400), System::IMP, 3, 400);
  ASSERT_TRUE(ours.outcome.ok) << ours.outcome.error;
  EXPECT_EQ(listed(ours), std::set<int>{0});
  EXPECT_NE(ours.outcome.weights_checksum, run.outcome.weights_checksum);

  const std::string dir = test::tempDir("authors-eye");
  const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  test::runIntrinsic(parseRunConfigText(test::shippedConfigYaml("base", System::IMP, 5, 3000, option)))
      .save(dir + "/predictors.ckpt");
  for (const std::string scenario : {"scenario3", "scenario5"}) {
    const std::string test_yaml = emitYaml(extrinsicConfig(
        config_dir, RunRequest{"base", System::IMP, 53, std::nullopt, option}, dir + "/predictors.ckpt", scenario));
    const BothWays both = runBothWays(test_yaml, 53, dir + "/predictors.ckpt");
    ASSERT_TRUE(both.run.ok) << both.run.error;
    EXPECT_EQ(both.run.extrinsic.success, both.plain.success) << scenario;
    EXPECT_EQ(both.run.extrinsic.completion, both.plain.completion) << scenario;
    EXPECT_EQ(both.run.extrinsic.attempts, both.plain.attempts) << scenario;
    ASSERT_EQ(both.run.extrinsic.sub_goals.size(), both.plain.sub_goals.size()) << scenario;
    for (std::size_t i = 0; i < both.plain.sub_goals.size(); ++i)
      EXPECT_EQ(both.run.extrinsic.sub_goals[i].actions_checked, both.plain.sub_goals[i].actions_checked) << scenario;
  }
}

// The paper's planner (Algorithm 2, bottom-up attention, one-step search) is
// what it was before issue 12's options: these outcomes were recorded at
// 9b41607, before them, for an IMP agent of 6000 steps (seed 5) on the five
// base scenarios; nothing may change them while the options are off.
TEST(Choreography, ThePapersPlannerIsUnchanged) {
  const std::map<std::string, std::string> before = {
      {"scenario1", "solved at 1, 1 attempts; 0i2c1a+ utility 1"},
      {"scenario2", "solved at 4, 2 attempts; 1i5c1a+ 1i5c1a+ utility 2"},
      {"scenario3", "solved at 9, 3 attempts; 1i5c1a+ 1i5c1a+ 4i13c1a+ utility 3"},
      {"scenario4", "solved at 13, 4 attempts; 0i1c1a+ 3i12c1a+ 1i5c1a+ 5i17c1a+ utility 4"},
      {"scenario5",
       "not solved at 0, 4 attempts; 1i6c1a+ 8i24c0a- 0i0c0a+ 8i24c0a- 8i24c0a- 1i5c1a+ 8i24c0a- 0i0c0a+ 4i14c1a+ 8i24c0a- 3i10c1a+ 8i24c0a- 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 8i24c0a- 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 8i24c0a- 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 8i24c0a- 0i0c0a+ 0i0c0a+ 0i0c0a+ 8i24c0a- 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 0i0c0a+ 6i18c0a- utility 4"}};
  const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  const Predictors trained = test::runIntrinsic(parseRunConfigText(baseYaml(System::IMP, 6000, 5)));
  const std::string dir = test::tempDir("planner-golden");
  trained.save(dir + "/predictors.ckpt");
  for (const auto& [scenario, outcome] : before) {
    const int k = scenario.back() - '0';
    const RunConfig c = parseRunConfigText(emitYaml(extrinsicConfig(
        config_dir, RunRequest{"base", System::IMP, 50 + k, std::nullopt, {}}, dir + "/predictors.ckpt", scenario)));
    const test::GoalTestOutcome got = test::runGoalTest(c, *c.scenario, trained);
    std::ostringstream o;
    o << (got.success ? "solved" : "not solved") << " at " << got.completion << ", " << got.attempts << " attempts;";
    for (const SubGoalRecord& g : got.sub_goals)
      o << " " << g.iterations << "i" << g.actions_checked << "c" << g.actions_taken << "a" << (g.reached ? "+" : "-");
    o << " utility " << got.utility;
    EXPECT_EQ(o.str(), outcome) << scenario;
  }
}

// Algorithm 3 and the action budget in the stochastic environment: the
// choreography gains exactly the utility the plain loop gains, test by test.
TEST(Choreography, UtilityTestsMatchThePlainPlanner) {
  const std::string dir = test::tempDir("utility");
  const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  test::runIntrinsic(test::shippedConfig("stochastic", System::IMP, 3)).save(dir + "/predictors.ckpt");
  double gained = 0;
  for (const char* kind : {"goal", "utility"})
    for (int budget : {1, 3}) {
      const std::vector<std::string> settings{std::string("planner.kind=") + kind,
                                              "planner.max_attempts=" + std::to_string(budget)};
      const std::int64_t seed = 70 + budget;
      const std::string yaml = emitYaml(extrinsicConfig(config_dir, RunRequest{"utility", System::IMP, seed, std::nullopt, settings},
                                                        dir + "/predictors.ckpt", "utility"));
      const BothWays both = runBothWays(yaml, seed, dir + "/predictors.ckpt");
      ASSERT_TRUE(both.run.ok) << both.run.error;
      const test::GoalTestOutcome& ref = both.plain;
      const ExtrinsicOutcome& got = both.run.extrinsic;
      EXPECT_EQ(got.attempts, ref.attempts) << kind << " budget " << budget;
      EXPECT_LE(got.attempts, budget) << kind;
      EXPECT_DOUBLE_EQ(got.utility, ref.utility) << kind << " budget " << budget;
      EXPECT_EQ(got.sub_goals.size(), ref.sub_goals.size()) << kind << " budget " << budget;
      gained += got.utility;
    }
  EXPECT_GT(gained, 0.0);  // some sub-goal was reached
}

TEST(Choreography, AnExtrinsicRunWithABadCheckpointIsRefusedNamingTheFile) {
  const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  const std::string yaml = emitYaml(extrinsicConfig(config_dir, RunRequest{"base", System::IMP, 1, std::nullopt, {}},
                                                    "/nonexistent/predictors.ckpt", "scenario1"));
  InProcessRun run(yaml, System::IMP, 1, 125);
  EXPECT_FALSE(run.outcome.ok);
  EXPECT_NE(run.outcome.error.find("/nonexistent/predictors.ckpt"), std::string::npos) << run.outcome.error;
}

// A run's configuration names its checkpoint files, but cannot choose where
// the predictors write or read: a path outside their checkpoint folder (or,
// for the one they write, outside the run's own folder in it) is refused
// naming the key, and nothing is written there.
TEST(Choreography, ACheckpointPathOutsideThePredictorsFolderIsRefusedAndNothingIsWritten) {
  const std::string elsewhere = test::tempDir("elsewhere");
  // Outside the folder, the refusal says so and which option to give (not that the file is no checkpoint);
  // inside it, that it is not the run's own folder.
  const std::string outside = "', outside this process's checkpoint folder";
  for (const auto& [path, said] :
       {std::pair<std::string, std::string>{test::checkpointRoot() + "/../x/predictors.ckpt", outside},
        {"relative/../../predictors.ckpt", outside},
        {elsewhere + "/predictors.ckpt", "' is not in the run's own folder "},
        {test::checkpointRoot() + "/another-run/predictors.ckpt", "' is not in the run's own folder "}}) {
    YAML::Node root = YAML::Load(baseYaml(System::IMP, 50));
    root["run"]["checkpoint"] = path;
    InProcessRun run(emitYaml(root), System::IMP, 3, 50);
    EXPECT_FALSE(run.outcome.ok) << path;
    EXPECT_NE(run.outcome.error.find(said), std::string::npos) << run.outcome.error;
    if (said == outside) {
      EXPECT_NE(run.outcome.error.find("run.checkpoint: the run writes its checkpoint to '" + path + said +
                                       " '" + test::checkpointRoot() + "' (--checkpoint-dir): start afford-predictors "
                                       "with --checkpoint-dir set to the runner's --log-root"),
                std::string::npos)
          << run.outcome.error;
    }
    EXPECT_FALSE(std::filesystem::exists(path)) << path;
  }
  const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  const std::string yaml = emitYaml(
      extrinsicConfig(config_dir, RunRequest{"base", System::IMP, 1, std::nullopt, {}}, "/etc/passwd", "scenario1"));
  InProcessRun run(yaml, System::IMP, 1, 125);
  EXPECT_FALSE(run.outcome.ok);
  EXPECT_NE(run.outcome.error.find("extrinsic.checkpoint: the run loads its agent from '/etc/passwd', outside"),
            std::string::npos)
      << run.outcome.error;
}

// ---- bad input: each kind is dropped with one line naming channel and reason,
// and the run ends exactly as without it.

struct BadInput {
  const char* name;
  const char* channel;
  const char* reason;
  Injector inject;
};

// A scene of newcomers at `step`, empty (no image bytes), unsealed: a test
// changes the field it is about.
scene_t newcomersScene(const std::string& run, std::int64_t step) {
  scene_t sc;
  sc.run_id = run;
  sc.step = step;
  sc.serial = 0;
  sc.cause = scene_t::CAUSE_OBJECTS_APPEARED;
  sc.scan = true;
  sc.changes_next = false;
  sc.action = -1;
  sc.action_target_x = sc.action_target_y = -1;
  sc.goal_distance = sc.goal_utility = -1;
  sc.width = sc.height = 150;
  sc.encoding = scene_t::ENCODING_ZLIB_RGB8;
  sc.size = 0;
  sc.n_objects = 0;
  return sc;
}

focus_t validFocus(const std::string& run, std::int64_t step) {
  focus_t f;
  f.run_id = run;
  f.step = step;
  f.serial = 0;
  f.kind = focus_t::SCENE_SCAN;
  f.seq = 0;
  f.x = f.y = 0.5;
  f.side = 21;
  f.size = 1323;
  f.image.assign(1323, 0);
  f.n_diffs = 0;
  return f;
}
prediction_t validPrediction(const std::string& run, std::int64_t step) {
  prediction_t p;
  p.run_id = run;
  p.step = step;
  p.serial = 0;
  p.x = p.y = 0.5;
  p.n_actions = 4;
  p.affordance = {0.5, 0.5, 0.5, 0.5};
  p.learning_progress = {0, 0, 0, 0};
  p.look = -1;
  p.n_tried = 0;
  p.n_trained = 0;
  return p;
}
decision_t validDecision(const std::string& run, std::int64_t step) {
  decision_t d;
  d.run_id = run;
  d.step = step;
  d.serial = 0;
  d.acted = false;
  d.action = decision_t::NONE;
  d.x = d.y = 0.5;
  d.target_x = d.target_y = -1;
  d.motivation = d.threshold = 0;
  d.revisit = false;
  d.seq = 0;
  return d;
}
template <class Msg>
std::vector<std::uint8_t> encode(const Msg& m) {
  std::vector<std::uint8_t> buf(m.getEncodedSize());
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}
// A message with its digest, as a process publishes it.
template <class Msg>
void publishSealed(lcm::LCM& l, const char* channel, Msg m) {
  const auto b = sealed(m);
  l.publish(channel, b.data(), static_cast<unsigned>(b.size()));
}

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

std::vector<BadInput> badInputs() {
  return {
      {"WrongFingerprint", "FOCUS", "wrong fingerprint",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         const auto b = encode(validDecision(run, s));  // a decision sent as a focus
         l.publish("FOCUS", b.data(), static_cast<unsigned>(b.size()));
       }},
      {"Truncated", "FOCUS", "field image",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         auto b = encode(validFocus(run, s + 1));
         b.resize(b.size() / 2);
         l.publish("FOCUS", b.data(), static_cast<unsigned>(b.size()));
       }},
      {"WrongArraySize", "FOCUS", "field size has size 100, expected 1323",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         focus_t f = validFocus(run, s + 1);
         f.size = 100;
         f.image.resize(100);
         l.publish("FOCUS", &f);
       }},
      {"NaN", "PREDICTION", "field affordance[2] is not finite",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         prediction_t p = validPrediction(run, s);
         p.affordance[2] = kNaN;
         l.publish("PREDICTION", &p);
       }},
      {"Infinite", "DECISION", "field x is not finite",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         decision_t d = validDecision(run, s);
         d.x = kInf;
         l.publish("DECISION", &d);
       }},
      {"ActionOutOfRange", "DECISION", "action id 9 is out of range",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         decision_t d = validDecision(run, s);
         d.acted = true;
         d.action = 9;
         l.publish("DECISION", &d);
       }},
      {"RevisitWithoutAnAction", "DECISION", "field revisit must be false when acted is false",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         decision_t d = validDecision(run, s);
         d.revisit = true;
         l.publish("DECISION", &d);
       }},
      {"TriedAgoOfOneAction", "PREDICTION", "field n_tried = 1 must be 0 or 4",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         prediction_t p = validPrediction(run, s);
         p.look = 0;
         p.n_tried = 1;
         p.tried_ago = {3};
         l.publish("PREDICTION", &p);
       }},
      {"ObjectPositionOutOfRange", "EFFECT", "field after_x = 1.5 is out of range",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         effect_t e;
         e.run_id = run;
         e.step = s;
         e.serial = 0;
         e.action = 0;
         e.target_x = e.target_y = -1;
         e.before_x = e.before_y = e.after_y = 0.5;
         e.after_x = 1.5;
         e.side = 21;
         e.size = 1323;
         e.image.assign(1323, 0);
         l.publish("EFFECT", &e);
       }},
      {"ObjectCountOutOfRange", "PROBE", "field n_objects has size 0, expected 9",
       [](lcm::LCM& l, const std::string& run, std::int64_t, const Bytes&) {
         object_probe_t p;
         p.run_id = run;
         p.step = 0;
         p.serial = 0;
         p.n_objects = 0;
         p.size = 1323;
         l.publish("PROBE", &p);
       }},
      {"UnknownRunId", "FOCUS", "unknown run id 'intruder'",
       [](lcm::LCM& l, const std::string&, std::int64_t s, const Bytes&) {
         const focus_t f = validFocus("intruder", s + 1);
         l.publish("FOCUS", &f);
       }},
      // A message whose serial was had already is a repeat (a resend's answer
      // reaches every subscriber): dropped without a word.
      {"RepeatedSerial", "FOCUS", "",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         publishSealed(l, "FOCUS", validFocus(run, s - 10));  // serial 0
       }},
      // A well-formed, valid message whose digest does not match (a forgery or a corrupted copy).
      {"DigestMismatch", "FOCUS", "field digest does not match",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         focus_t f = validFocus(run, s + 1);
         f.serial = s + 1;
         auto b = sealed(f);
         b[b.size() - 20] ^= 0x01;  // one bit of the image flipped after sealing
         l.publish("FOCUS", b.data(), static_cast<unsigned>(b.size()));
       }},
      // The step's real focus, re-sealed with the next serial: it would take the
      // next focus's place, but it does not follow the real one in the chain.
      {"CopyWithTheNextSerial", "FOCUS", "field prev_digest does not follow",
       [](lcm::LCM& l, const std::string&, std::int64_t, const Bytes& real) {
         focus_t f;
         f.decode(real.data(), 0, static_cast<int>(real.size()));
         ++f.serial;
         publishSealed(l, "FOCUS", f);
       }},
      {"CopyWithTheNextSerialAndStep", "FOCUS", "field prev_digest does not follow",
       [](lcm::LCM& l, const std::string&, std::int64_t, const Bytes& real) {
         focus_t f;
         f.decode(real.data(), 0, static_cast<int>(real.size()));
         ++f.serial;
         ++f.step;
         publishSealed(l, "FOCUS", f);
       }},
      // The real focus re-sealed with another step: its serial was had, so it is a repeat.
      {"CopyWithAnotherStep", "FOCUS", "",
       [](lcm::LCM& l, const std::string&, std::int64_t, const Bytes& real) {
         focus_t f;
         f.decode(real.data(), 0, static_cast<int>(real.size()));
         f.step += 7;
         publishSealed(l, "FOCUS", f);
       }},
      // A size field far beyond anything the run sends: refused before any decode.
      {"HugeArraySize", "PREDICTION", "field n_actions",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         prediction_t p = validPrediction(run, s);
         auto b = sealed(p);
         const std::size_t at = 8 + 4 + run.size() + 1 + 8 + 8 + 8 + 8 + 8;  // fingerprint, run_id, step, serial, prev_digest, x, y
         b[at] = 0x10, b[at + 1] = 0x00, b[at + 2] = 0x00, b[at + 3] = 0x01;  // n_actions = 0x10000001
         l.publish("PREDICTION", b.data(), static_cast<unsigned>(b.size()));
       }},
      {"HugeStatusCount", "STATUS", "field n_channels",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         process_status_t st{};
         st.run_id = run;
         st.step = s;
         st.process = "eye";
         st.pid = 1;
         st.state = process_status_t::RUNNING;
         st.counts_run = run;
         st.counts_config = 0;
         st.n_channels = 0;
         st.n_takes = 0;
         st.started = 0;
         st.n_copies = 0;
         auto b = sealed(st);
         // n_channels sits after run_id, step, process, pid, beat, state, config_digest, detail, stuck, counts_run
         // and counts_config.
         const std::size_t at =
             8 + (4 + run.size() + 1) + 8 + (4 + 4) + 4 + 8 + 1 + 8 + (4 + 1) + (4 + 1) + (4 + run.size() + 1) + 8;
         b[at] = 0x01, b[at + 1] = b[at + 2] = b[at + 3] = 0x00;  // n_channels = 0x01000000
         l.publish("STATUS", b.data(), static_cast<unsigned>(b.size()));
       }},
      {"WrongSceneSize", "SCENE", "field width has size 100, expected 150",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         scene_t sc = newcomersScene(run, s + 1);
         sc.width = 100;
         l.publish("SCENE", &sc);
       }},
      {"SceneObjectOutsideTheScene", "SCENE", "field object_x[1] = 2 is out of range [0, 1]",
       [](lcm::LCM& l, const std::string& run, std::int64_t s, const Bytes&) {
         scene_t sc = newcomersScene(run, s + 1);
         sc.n_objects = 2;
         sc.object_x = {0.5, 2.0};
         sc.object_y = {0.5, 0.5};
         l.publish("SCENE", &sc);
       }},
  };
}

class BadInputTest : public ::testing::TestWithParam<BadInput> {
 public:
  static const std::string& cleanChecksum() {
    static const std::string sum = InProcessRun(baseYaml(System::IMP, 120), System::IMP, 3, 120).outcome.weights_checksum;
    return sum;
  }
};

TEST_P(BadInputTest, IsDroppedWithOneLineAndTheRunGoesOnUnchanged) {
  const BadInput& bad = GetParam();
  InProcessRun run(baseYaml(System::IMP, 120), System::IMP, 3, 120, bad.inject);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  EXPECT_EQ(run.outcome.weights_checksum, cleanChecksum());
  const std::string want = std::string(bad.channel) + ": dropped message: ";
  int lines = 0;
  std::istringstream in(run.log.str());
  for (std::string line; std::getline(in, line);)
    if (line.find(want) != std::string::npos) {
      ++lines;
      EXPECT_NE(line.find(bad.reason), std::string::npos) << line;
    }
  if (std::string(bad.reason).empty()) {
    EXPECT_EQ(lines, 0) << run.log.str();
    return;
  }
  // One line per process that subscribes to the channel (DECISION: environment, eye, predictors;
  // STATUS: every process and the runner).
  EXPECT_GE(lines, 1) << run.log.str();
  EXPECT_LE(lines, 6) << run.log.str();
}

INSTANTIATE_TEST_SUITE_P(EachKind, BadInputTest, ::testing::ValuesIn(badInputs()),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace afford

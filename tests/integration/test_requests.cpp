// Each request of a run is a run of its own (run_config_t.request, drawn afresh by the runner): processes that
// served a run serve it again from its start when it is asked for again, whatever id and configuration are
// reused; the runner takes only what was computed for its request; what another request says (a recording
// played back, an earlier runner's) is dropped and counted, never a failure; and a run that cannot go on says
// which process could not take which message, and why. All in one process over memq (tests/in_process.hpp).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <filesystem>

#include "afford/run_control_t.hpp"
#include "motivation/component.hpp"
#include "tests/in_process.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using test::baseYaml;
using test::InProcessRun;

// The processes of an intrinsic run hosted on memq, serving one request after another, as a group started by
// hand serves the runs of its runners.
struct Group {
  lcm::LCM lcm{"memq://"};
  std::ostringstream said;
  ProtocolConfig protocol = test::shippedProtocol();
  std::shared_ptr<spdlog::sinks::ostream_sink_mt> sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(said);
  LoggerFactory logger = [this](const std::string& name) {
    auto l = std::make_shared<spdlog::logger>(name, sink);
    l->set_pattern("[%n] %v");
    return l;
  };
  InProcessHost host{lcm, protocol, logger, HostOptions{/*single_thread=*/false, test::checkpointRoot(), nullptr, ""}};
  // `recorded`: with a logger, whose log folder is the checkpoints' (test::checkpointRoot()).
  explicit Group(bool recorded = false) { host.start(runProcesses(Phase::Intrinsic, recorded)); }
  // A RUN_CONFIG and START of `yaml` for run `id` that no runner of ours sent (a recording played back): the
  // processes, free, take it.
  void playOther(const std::string& id, const std::string& yaml, std::int64_t request) {
    run_config_t other;
    other.run_id = id;
    other.step = 0;
    other.request = request;
    other.seed = 3;
    other.experiment = "base";
    other.system = "IMP";
    other.config_yaml = yaml;
    const auto config = sealed(other);
    run_control_t start;
    start.run_id = id;
    start.step = 0;
    start.command = run_control_t::START;
    start.config_digest = other.digest;
    const auto control = sealed(start);
    lcm.publish(ch::runConfig.name, config.data(), static_cast<unsigned>(config.size()));
    for (int i = 0; i < 20; ++i) pump();
    lcm.publish(ch::runControl.name, control.data(), static_cast<unsigned>(control.size()));
  }
  void pump() {
    while (lcm.handleTimeout(0) > 0) {
    }
    lcm.handleTimeout(2);
    host.tick();
  }
  // One request of `spec`, by a runner of its own (a new `afford experiment --attach` each time).
  RunOutcome run(const RunSpec& spec) {
    RunDriver driver(lcm, logger("runner"), protocol);
    RunOutcome out = driver.run(spec, [this] { pump(); }, [] { return std::string(); });
    for (int i = 0; i < 500 && host.inRun(); ++i) pump();  // the STOP taken, as between two runs
    return out;
  }
};

RunSpec specOf(const std::string& run_id, const std::string& yaml, std::int64_t seed, std::int64_t steps) {
  RunSpec spec;
  spec.run_id = run_id;
  spec.experiment = "base";
  spec.system = "IMP";
  spec.seed = seed;
  spec.steps = steps;
  spec.config_yaml = yaml;
  spec.processes = runProcesses(Phase::Intrinsic, /*recorded=*/false);
  spec.stall_seconds = 20;
  return spec;
}

// The base run, its checkpoint in <checkpoint root>/<run id>/ (where the predictors may write it).
std::string yamlWithCheckpoint(const std::string& run_id, std::int64_t steps) {
  YAML::Node c = YAML::Load(baseYaml(System::IMP, steps));
  c["run"]["checkpoint"] = (fs::path(test::checkpointRoot()) / run_id / "predictors.ckpt").string();
  return emitYaml(c);
}

// A run asked for again of the same processes, the same id and configuration, its earlier folder removed, runs
// again: the runner does not take the earlier request's result, which its processes still hold for late
// requests (the runner once did: "done in 0.1 s" with the first run's weights and a checkpoint that did not
// exist).
TEST(Requests, ARunAskedForAgainOfTheSameProcessesRunsAgainAndReportsWhatItComputed) {
  const std::string id = "again-" + std::to_string(getpid());
  const fs::path folder = fs::path(test::checkpointRoot()) / id;
  const std::string yaml = yamlWithCheckpoint(id, 300);
  Group group;
  const RunOutcome first = group.run(specOf(id, yaml, 3, 300));
  ASSERT_TRUE(first.ok) << first.error << group.said.str();
  ASSERT_TRUE(fs::exists(folder / "predictors.ckpt"));
  for (int again = 0; again < 3; ++again) {
    fs::remove_all(folder);  // `afford clean --delete`, or the folder moved aside
    const RunOutcome next = group.run(specOf(id, yaml, 3, 300));
    ASSERT_TRUE(next.ok) << next.error << group.said.str();
    EXPECT_TRUE(fs::exists(folder / "predictors.ckpt")) << "request " << again + 2 << " reported a run that did not run";
    EXPECT_EQ(next.checkpoint, (folder / "predictors.ckpt").string());
    EXPECT_EQ(next.weights_checksum, first.weights_checksum);
    EXPECT_EQ(next.curve.size(), first.curve.size());
  }
  fs::remove_all(folder);
}

// The RUN_CONFIG and START of another request of the run (a recording played back), taken by the processes
// before the runner's: they are told to leave it, take the runner's, and the run is the undisturbed one.
TEST(Requests, ProcessesHoldingAnotherRequestOfTheRunAreToldToLeaveIt) {
  const std::string yaml = baseYaml(System::IMP, 300);
  const InProcessRun undisturbed(yaml, System::IMP, 3, 300);
  ASSERT_TRUE(undisturbed.outcome.ok) << undisturbed.outcome.error;

  Group group;
  group.playOther("test-run", yaml, 12345);
  for (int i = 0; i < 20; ++i) group.pump();
  for (const auto& p : runProcesses(Phase::Intrinsic, false)) ASSERT_EQ(group.host.node(p).runId(), "test-run") << p;

  const RunOutcome out = group.run(specOf("test-run", yaml, 3, 300));
  ASSERT_TRUE(out.ok) << out.error << group.said.str();
  EXPECT_EQ(out.weights_checksum, undisturbed.outcome.weights_checksum);
  EXPECT_NE(group.said.str().find("holds another request of this run id: told to leave it"), std::string::npos);
}

// Another request of the run, played back and taken by the free processes, runs for a while before the runner asks
// for the run: its logger records it in the run's folder, its predictors save the after-one-action checkpoint there.
// Told to leave it, they set aside what they wrote for it (the logger its log, in other-request-1/; the predictors
// their checkpoint, renamed), and the run asked for is recorded and runs. (The logger refused the folder, and the
// run failed: "holds the log of another request".) What another process wrote is never set aside.
TEST(Requests, WhatProcessesWroteForAnotherRequestTheyLeftIsSetAsideAndTheRunAskedForRuns) {
  const std::string id = "written-" + std::to_string(getpid());
  const fs::path folder = fs::path(test::checkpointRoot()) / id;
  fs::remove_all(folder);
  YAML::Node c = YAML::Load(yamlWithCheckpoint(id, 300));
  c["run"]["record"] = true;
  c["run"]["checkpoint_after_actions"] = 1;
  const std::string yaml = emitYaml(c);
  Group group(/*recorded=*/true);
  group.playOther(id, yaml, 777);
  const std::string after_one = actionsCheckpoint((folder / "predictors.ckpt").string(), 1);
  for (int i = 0; i < 5000 && !(fs::exists(after_one) && group.host.node("logger").lastStep() > 10); ++i) group.pump();
  ASSERT_TRUE(fs::exists(after_one)) << group.said.str();
  ASSERT_TRUE(fs::exists(folder / "log.00.lcm"));

  RunSpec spec = specOf(id, yaml, 3, 300);
  spec.processes = runProcesses(Phase::Intrinsic, /*recorded=*/true);
  spec.log_root = test::checkpointRoot();
  const RunOutcome out = group.run(spec);
  ASSERT_TRUE(out.ok) << out.error << group.said.str();
  EXPECT_EQ(out.log_dir, folder.string());
  const auto manifest = test::readJson(folder / "manifest.json");
  EXPECT_EQ(manifest["complete"], true);
  EXPECT_NE(manifest["config_digest"], test::readJson(folder / "other-request-1/manifest.json")["config_digest"]);
  EXPECT_TRUE(fs::exists(after_one));                          // the run's own, saved after its first action
  EXPECT_TRUE(fs::exists(after_one + ".other-request-1"));     // the other request's, set aside
  EXPECT_TRUE(fs::exists(folder / "other-request-1/log.00.lcm"));

  // Another group's processes, asked for the run again (the folder kept): what the first group wrote is not theirs
  // to set aside. The run is refused, naming what it would overwrite, and the folder is left as it was.
  Group other(/*recorded=*/true);
  const RunOutcome refused = other.run(spec);
  EXPECT_FALSE(refused.ok);
  EXPECT_NE(refused.error.find("exists already"), std::string::npos) << refused.error;
  EXPECT_EQ(test::readJson(folder / "manifest.json"), manifest);
  EXPECT_FALSE(fs::exists(folder / "other-request-2"));
  fs::remove_all(folder);
}

// Everything another request of the same run id said (here: another seed, recorded whole: its RUN_CONFIG,
// START, every message, its RESULT, its STOP), played into a run at step 50: all of it is dropped, and the run
// ends with its own weights, not the recording's.
TEST(Requests, ARecordingOfAnotherRequestPlayedIntoARunIsDroppedAndTheRunIsItsOwn) {
  const InProcessRun recorded(baseYaml(System::IMP, 300, 4), System::IMP, 4, 300);
  const InProcessRun undisturbed(baseYaml(System::IMP, 300), System::IMP, 3, 300);
  ASSERT_TRUE(recorded.outcome.ok && undisturbed.outcome.ok);
  ASSERT_NE(recorded.outcome.weights_checksum, undisturbed.outcome.weights_checksum);
  const auto play = [&](lcm::LCM& lcm, const std::string&, std::int64_t, const test::Bytes&) {
    for (const auto& e : recorded.events) lcm.publish(e.channel, e.data.data(), static_cast<unsigned>(e.data.size()));
  };
  const InProcessRun run(baseYaml(System::IMP, 300), System::IMP, 3, 300, play, 50);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  EXPECT_EQ(run.outcome.weights_checksum, undisturbed.outcome.weights_checksum);
  EXPECT_EQ(run.outcome.curve.size(), undisturbed.outcome.curve.size());
}

// A motivation that does not compute what it computed before: each one made passes, but the first, which acts
// (not a function of its percepts: a count of the components made, as an unseeded generator would be).
class Unkeyed : public MotivationComponent {
 public:
  Decision decide(const Percept&) override {
    Decision d;
    d.act = first_;
    d.action = 0;
    d.motivation = 1;
    d.threshold = 0;
    return d;
  }

 private:
  static std::atomic<int> made_;
  bool first_ = made_++ == 0;
};
std::atomic<int> Unkeyed::made_{0};

// Killed and started again, it sends the run's next DECISION after decisions other than those its peers took:
// none of them can take it, and the run stops, saying who could not take what, and why (it used to say only
// "stalled: no progress for 30 s").
TEST(Requests, AStallNamesWhoCannotTakeWhichMessageAndWhy) {
  registerMotivation("unkeyed", [](const MotivationParams&) { return std::make_unique<Unkeyed>(); });
  YAML::Node c = YAML::Load(baseYaml(System::IMP, 400));
  c["motivation"]["kind"] = "unkeyed";
  test::Restart restart;
  restart.process = "motivation";
  restart.at = 100;
  const InProcessRun run(emitYaml(c), System::IMP, 3, 400, {}, 0, false, restart, /*stall_seconds=*/3);
  ASSERT_TRUE(run.restarted);
  ASSERT_FALSE(run.outcome.ok);
  const std::string& why = run.outcome.error;
  EXPECT_NE(why.find("stalled: no progress for 3 s"), std::string::npos) << why;
  EXPECT_NE(why.find("cannot take DECISION serial "), std::string::npos) << why;
  EXPECT_NE(why.find(" (published by motivation): field prev_digest does not follow"), std::string::npos) << why;
  EXPECT_NE(why.find("does not compute what it computed before"), std::string::npos) << why;
}

}  // namespace
}  // namespace afford

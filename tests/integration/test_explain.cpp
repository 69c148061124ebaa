// `afford explain`: real extrinsic tests recorded in one process (memq), written
// as run logs, and explained. What explain rebuilds from the messages must equal
// what the planner itself reported in the EXTRINSIC_RESULT.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "afford/protocol.hpp"
#include "experiment/present/explain_text.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "tests/in_process.hpp"
#include "tests/reference_loops.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using test::InProcessRun;

std::shared_ptr<spdlog::logger> quiet() {
  return std::make_shared<spdlog::logger>("explain-test", std::make_shared<spdlog::sinks::null_sink_mt>());
}

// The first `count` events of a recorded run, as a run log folder (log.00.lcm).
std::string writeLog(const std::vector<test::Event>& events, const fs::path& dir,
                     std::size_t count = std::numeric_limits<std::size_t>::max()) {
  fs::create_directories(dir);
  lcm::LogFile out((dir / "log.00.lcm").string(), "w");
  EXPECT_TRUE(out.good()) << dir;
  for (std::size_t i = 0; i < events.size() && i < count; ++i) {
    lcm::LogEvent e{};
    e.timestamp = static_cast<std::int64_t>(i);
    e.channel = events[i].channel;
    e.datalen = static_cast<std::int32_t>(events[i].data.size());
    e.data = const_cast<std::uint8_t*>(events[i].data.data());
    out.writeEvent(&e);
  }
  return dir.string();
}

extrinsic_result_t resultOf(const InProcessRun& run) {
  extrinsic_result_t r;
  for (const auto& e : run.events)
    if (e.channel == ch::extrinsicResult.name) r.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
  return r;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

// Explain's figures, rebuilt from the messages, against the planner's own.
void expectAgreement(const Explanation& e, const extrinsic_result_t& r) {
  EXPECT_TRUE(e.warnings.empty()) << joined(e.warnings);
  EXPECT_EQ(e.run_id, r.run_id);
  EXPECT_EQ(e.success, r.success);
  EXPECT_EQ(e.completion, r.completion);
  EXPECT_EQ(e.attempts, r.attempts);
  EXPECT_EQ(static_cast<std::int64_t>(e.steps.size()), r.step);
  ASSERT_EQ(e.sub_goals.size(), r.sub_goals.size());
  ASSERT_GT(r.n_sub_goals, 0);
  for (std::size_t i = 0; i < e.sub_goals.size(); ++i) {
    const ExplainedSubGoal& g = e.sub_goals[i];
    const sub_goal_t& p = r.sub_goals[i];
    EXPECT_EQ(g.x, p.x) << "sub-goal " << i;
    EXPECT_EQ(g.y, p.y) << "sub-goal " << i;
    EXPECT_EQ(g.iterations, p.iterations) << "sub-goal " << i;
    EXPECT_EQ(g.actions_checked, p.actions_checked) << "sub-goal " << i;
    EXPECT_EQ(g.actions_taken, p.actions_taken) << "sub-goal " << i;
    EXPECT_EQ(g.reached, p.reached) << "sub-goal " << i;
  }
}

class Explain : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = test::tempDir("explain");
    // An agent trained long enough to solve the easy scenarios (as in test_choreography).
    test::runIntrinsic(parseRunConfigText(test::baseYaml(System::IMP, 6000, 5))).save(dir_ + "/predictors.ckpt");
  }
  static std::string testYaml(const std::string& scenario, std::int64_t seed, std::vector<std::string> settings = {}) {
    const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
    return emitYaml(extrinsicConfig(config_dir, RunRequest{"base", System::IMP, seed, std::nullopt, std::move(settings)},
                                    dir_ + "/predictors.ckpt", scenario));
  }
  // One extrinsic test recorded, written as the log folder `name`, and explained.
  struct Recorded {
    std::unique_ptr<InProcessRun> run;
    std::string log;
    Explanation explained;
  };
  static Recorded record(const std::string& name, const std::string& yaml, std::int64_t seed) {
    Recorded r;
    r.run = std::make_unique<InProcessRun>(yaml, System::IMP, seed, 125);
    EXPECT_TRUE(r.run->outcome.ok) << r.run->outcome.error;
    r.log = writeLog(r.run->events, fs::path(dir_) / "logs" / name);
    r.explained = explainLog(r.log, "", *quiet());
    return r;
  }
  static std::string dir_;
};
std::string Explain::dir_;

TEST_F(Explain, ASolvedTestIsExplainedAsThePlannerReportedIt) {
  const Recorded t = record("solved", testYaml("scenario1", 51), 51);
  const Explanation& e = t.explained;
  expectAgreement(e, resultOf(*t.run));
  ASSERT_TRUE(e.success);
  EXPECT_EQ(e.end, "solved");
  EXPECT_EQ(e.scenario, "scenario1");
  EXPECT_GT(e.completion, 0);
  EXPECT_LT(e.final_goal_distance, e.planner.success_distance);
  EXPECT_GE(e.start_goal_distance, e.planner.success_distance);
  // The last action is the one that solved it: the goal distance after it is below the threshold.
  const ExplainedIteration& last = e.steps.back();
  ASSERT_GE(last.executed, 0);
  EXPECT_LT(last.goal_distance_after, e.planner.success_distance);
  // The executed action was the first of its iteration to pass both thresholds.
  ASSERT_FALSE(last.checks.empty());
  auto passed = std::find_if(last.checks.begin(), last.checks.end(), [](const ExplainedCheck& c) { return c.passes(); });
  ASSERT_NE(passed, last.checks.end());
  EXPECT_EQ(passed->action, last.executed);
  EXPECT_LT(passed->what_distance, e.planner.image_match);
  EXPECT_LE(passed->where_distance, e.planner.position_match);
  ASSERT_TRUE(last.affordance.has_value());
  EXPECT_GT((*last.affordance)[static_cast<std::size_t>(last.executed)], e.planner.affordance_threshold);

  const std::string text = explanationText(e);
  EXPECT_NE(text.find("solved at iteration " + std::to_string(e.completion)), std::string::npos) << text;
  const nlohmann::json j = explanationJson(e);
  EXPECT_EQ(j["end"], "solved");
  EXPECT_EQ(j["steps"].size(), e.steps.size());
  EXPECT_EQ(j["sub_goals"].size(), e.sub_goals.size());
}

TEST_F(Explain, ATestStoppedByTheActionLimitSaysSo) {
  // Scenario 3 takes three actions; one is allowed.
  const Recorded t = record("attempts", testYaml("scenario3", 53, {"planner.max_attempts=1"}), 53);
  const Explanation& e = t.explained;
  expectAgreement(e, resultOf(*t.run));
  EXPECT_FALSE(e.success);
  EXPECT_EQ(e.end, "attempts");
  EXPECT_EQ(e.attempts, 1);
  EXPECT_EQ(e.planner.max_attempts, 1);
  EXPECT_LT(e.iterations, e.planner.budget);
  EXPECT_GE(e.final_goal_distance, e.planner.success_distance);
  EXPECT_NE(explanationText(e).find("planner.max_attempts ran out"), std::string::npos) << explanationText(e);
}

TEST_F(Explain, ATestStoppedByTheBudgetSaysSoAndNamesItsSubGoals) {
  // Scenario 5 takes five actions, at most one an iteration: four iterations cannot solve it.
  const Recorded t = record("budget", testYaml("scenario5", 55, {"planner.budget=4"}), 55);
  const Explanation& e = t.explained;
  expectAgreement(e, resultOf(*t.run));
  EXPECT_FALSE(e.success);
  EXPECT_EQ(e.end, "budget");
  EXPECT_EQ(e.iterations, 4);
  ASSERT_FALSE(e.sub_goals.empty());
  EXPECT_EQ(e.sub_goals.back().ended, e.sub_goals.back().reached ? "reached" : "open");
}

TEST_F(Explain, TheUtilityPlannersTestAgreesToo) {
  const Recorded t = record("utility", testYaml("scenario3", 53, {"planner.kind=utility"}), 53);
  expectAgreement(t.explained, resultOf(*t.run));
  EXPECT_NE(t.explained.end, "unknown");
}

TEST_F(Explain, AnUnderTrainedAgentsTimeoutsAreNamed) {
  // An agent of 300 steps: its forward models miss, and sub-goals are abandoned.
  const std::string weak = dir_ + "/weak.ckpt";
  test::runIntrinsic(parseRunConfigText(test::baseYaml(System::IMP, 300, 5))).save(weak);
  const std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  const std::string yaml =
      emitYaml(extrinsicConfig(config_dir, RunRequest{"base", System::IMP, 52, std::nullopt, {}}, weak, "scenario2"));
  const Recorded t = record("weak", yaml, 52);
  const Explanation& e = t.explained;
  expectAgreement(e, resultOf(*t.run));
  ASSERT_FALSE(e.success);
  int timeouts = 0;
  for (const ExplainedSubGoal& g : e.sub_goals) {
    if (g.ended != "timeout") continue;
    ++timeouts;
    EXPECT_EQ(g.iterations, e.planner.subgoal_timeout);
    EXPECT_FALSE(g.reached);
  }
  EXPECT_GT(timeouts, 0) << explanationText(e);
}

// A log that lost a message: the rebuilt figures no longer match, and explain says so.
TEST_F(Explain, AMissingMessageIsAWarningNotASilentDifference) {
  const Recorded t = record("whole", testYaml("scenario5", 55, {"planner.budget=4"}), 55);
  ASSERT_GE(t.run->count(ch::forwardPrediction.name), 2);  // a loss is seen by the serials after it
  std::vector<test::Event> lossy;
  bool dropped = false;
  for (const auto& ev : t.run->events) {
    if (!dropped && ev.channel == ch::forwardPrediction.name) {
      dropped = true;
      continue;
    }
    lossy.push_back(ev);
  }
  ASSERT_TRUE(dropped);
  const Explanation e = explainLog(writeLog(lossy, fs::path(dir_) / "logs-lossy" / "lossy"), "", *quiet());
  const std::string w = joined(e.warnings);
  EXPECT_NE(w.find("FORWARD_PREDICTION serial 0 is missing from the log"), std::string::npos) << w;
  EXPECT_NE(w.find("has no FORWARD_PREDICTION"), std::string::npos) << w;
  EXPECT_NE(w.find("actions checked"), std::string::npos) << w;
}

TEST_F(Explain, BadInputIsNamedAndFails) {
  const Recorded t = record("for-bad-input", testYaml("scenario1", 51), 51);
  const fs::path bad = fs::path(dir_) / "bad";
  auto cli = [](const std::string& log) { return test::runCommand(test::afford("explain " + log)); };

  const auto missing = cli((bad / "nowhere").string());
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("no such log folder or file: " + (bad / "nowhere").string()), std::string::npos)
      << missing.output;

  InProcessRun intrinsic(test::baseYaml(System::IMP, 30), System::IMP, 3, 30);
  ASSERT_TRUE(intrinsic.outcome.ok) << intrinsic.outcome.error;
  const auto not_extrinsic = cli(writeLog(intrinsic.events, bad / "intrinsic"));
  EXPECT_NE(not_extrinsic.exit_code, 0);
  EXPECT_NE(not_extrinsic.output.find("is not an extrinsic test"), std::string::npos) << not_extrinsic.output;

  std::vector<test::Event> headless(t.run->events.begin() + 1, t.run->events.end());
  ASSERT_EQ(t.run->events.front().channel, ch::runConfig.name);
  const auto no_config = cli(writeLog(headless, bad / "no-config"));
  EXPECT_NE(no_config.exit_code, 0);
  EXPECT_NE(no_config.output.find("no RUN_CONFIG that the edge accepts in the log"), std::string::npos) << no_config.output;

  // Cut before the EXTRINSIC_RESULT, at an event boundary and in the middle of an event.
  const std::size_t half = t.run->events.size() / 2;
  const auto cut = cli(writeLog(t.run->events, bad / "cut", half));
  EXPECT_NE(cut.exit_code, 0);
  EXPECT_NE(cut.output.find("ends before its EXTRINSIC_RESULT"), std::string::npos) << cut.output;
  std::size_t result_at = 0;
  while (result_at < t.run->events.size() && t.run->events[result_at].channel != ch::extrinsicResult.name) ++result_at;
  ASSERT_LT(result_at, t.run->events.size());
  const std::string torn = writeLog(t.run->events, bad / "torn", result_at + 1);
  const auto size = fs::file_size(fs::path(torn) / "log.00.lcm");
  fs::resize_file(fs::path(torn) / "log.00.lcm", size - 10);  // into the EXTRINSIC_RESULT
  const auto torn_out = cli(torn);
  EXPECT_NE(torn_out.exit_code, 0);
  EXPECT_NE(torn_out.output.find("ends before its EXTRINSIC_RESULT"), std::string::npos) << torn_out.output;
  EXPECT_NE(torn_out.output.find("incomplete event"), std::string::npos) << torn_out.output;

  // Not an LCM log at all.
  fs::create_directories(bad / "garbage");
  std::ofstream(bad / "garbage" / "log.00.lcm") << "not an LCM log";
  const auto garbage = cli((bad / "garbage").string());
  EXPECT_NE(garbage.exit_code, 0);
  EXPECT_NE(garbage.output.find("holds no complete event"), std::string::npos) << garbage.output;

  // And the whole log is explained, exit 0.
  const auto whole = cli(t.log);
  EXPECT_EQ(whole.exit_code, 0) << whole.output;
  EXPECT_NE(whole.output.find("solved at iteration"), std::string::npos) << whole.output;
}

// Extrinsic tests of the reproduction's experiments, recorded before explain
// observed the planner core (tests/data/explain/README.md): each log is
// explained as stored, field by field. Four are as the earlier explain, which
// re-derived the planner from the messages, gave them; the two of multi-step
// differ where that derivation was wrong (the README says where).
TEST(ExplainRecorded, EachStoredTestIsExplainedAsItsStoredExplanation) {
  const fs::path data = fs::path(AFFORD_SOURCE_DIR) / "tests" / "data" / "explain";
  const fs::path dir = test::tempDir("explain-recorded");
  int explained = 0;
  for (const auto& f : fs::directory_iterator(data)) {
    if (f.path().extension() != ".gz") continue;
    const std::string name = f.path().stem().stem().string();  // NAME.lcm.gz
    const fs::path log = dir / name;
    fs::create_directories(log);
    const auto unzip = test::runCommand("gzip -dc '" + f.path().string() + "' > '" + (log / "log.00.lcm").string() + "'");
    ASSERT_EQ(unzip.exit_code, 0) << unzip.output;
    nlohmann::json got = explanationJson(explainLog(log.string(), "", *quiet()));
    got.erase("log");  // where it was read
    std::ifstream in(data / (name + ".json"));
    ASSERT_TRUE(in.good()) << name;
    const nlohmann::json want = nlohmann::json::parse(in);
    const nlohmann::json patch = nlohmann::json::diff(want, got);
    EXPECT_TRUE(patch.empty()) << name << ": what the explanation changes of the stored one: "
                               << patch.dump().substr(0, 3000);
    ++explained;
  }
  EXPECT_EQ(explained, 6);
}

// A folder of run logs: one line per test, the end reasons counted, other runs skipped.
TEST_F(Explain, AFolderOfLogsIsSummarised) {
  const fs::path root = fs::path(dir_) / "root";
  const Recorded solved = record("solved", testYaml("scenario1", 51), 51);
  const Recorded limited = record("attempts", testYaml("scenario3", 53, {"planner.max_attempts=1"}), 53);
  writeLog(solved.run->events, root / "a-solved");
  writeLog(limited.run->events, root / "b-attempts");
  InProcessRun intrinsic(test::baseYaml(System::IMP, 30), System::IMP, 3, 30);
  writeLog(intrinsic.events, root / "c-intrinsic");
  ASSERT_TRUE(isLogRoot(root.string()));
  ASSERT_FALSE(isLogRoot((root / "a-solved").string()));

  const auto r = test::runCommand("(" + test::afford("explain --json " + root.string()) + " 2>/dev/null)");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j["tests"].size(), 2u);
  EXPECT_EQ(j["end_reasons"]["all"]["solved"], 1);
  EXPECT_EQ(j["end_reasons"]["all"]["attempts"], 1);
  EXPECT_EQ(j["end_reasons"]["all"]["budget"], 0);
  EXPECT_EQ(j["end_reasons"]["IMP"]["solved"], 1);
  EXPECT_EQ(j["skipped"].size(), 1u);
  EXPECT_EQ(j["tests"][1]["end"], "attempts");
  EXPECT_FALSE(j["tests"][1].contains("steps"));  // per-test figures only

  // A cut log among them is named, and the summary fails.
  writeLog(solved.run->events, root / "d-cut", solved.run->events.size() / 2);
  const ExplainSummary s = explainLogRoot(root.string(), *quiet());
  EXPECT_EQ(s.tests.size(), 2u);
  ASSERT_EQ(s.errors.size(), 1u);
  EXPECT_NE(s.errors[0].second.find("ends before its EXTRINSIC_RESULT"), std::string::npos) << s.errors[0].second;
  const std::string text = summaryText(s);
  EXPECT_NE(text.find("end reasons: solved 1, budget 0, attempts 1 (2 tests)"), std::string::npos) << text;
  EXPECT_NE(text.find("closest misses of the failed tests"), std::string::npos) << text;
  EXPECT_NE(text.find("every sub-goal it picked was reached; it ended by attempts"), std::string::npos) << text;
  EXPECT_NE(test::runCommand(test::afford("explain " + root.string())).exit_code, 0);
}

// By agent: each sub-goal of each scenario over the agent's tests, and over
// the system's agents; the agent is the folder of the test's checkpoint.
TEST_F(Explain, AFolderOfLogsIsSummarisedBySubGoalAndAgent) {
  const fs::path root = fs::path(dir_) / "by-agent";
  const Recorded solved = record("solved", testYaml("scenario1", 51), 51);
  const Recorded again = record("solved-again", testYaml("scenario1", 52), 52);
  // The blue square's turn-green made unaffordable for the planner: never asked about.
  const Recorded blocked = record("blocked", testYaml("scenario1", 53, {"planner.affordance_threshold=0.9999", "planner.budget=6"}), 53);
  writeLog(solved.run->events, root / "a");
  writeLog(again.run->events, root / "b");
  writeLog(blocked.run->events, root / "c");
  const ExplainSummary s = explainLogRoot(root.string(), *quiet());
  ASSERT_EQ(s.tests.size(), 3u);
  ASSERT_FALSE(s.tests[2].success) << explanationText(s.tests[2]);
  const std::string agent = fs::path(dir_).filename().string();
  for (const Explanation& t : s.tests) EXPECT_EQ(t.agent, agent);

  const std::vector<AgentSubGoal> agents = subGoalsByAgent(s);
  ASSERT_EQ(agents.size(), 1u);  // one agent, one scenario, one sub-goal
  const AgentSubGoal& a = agents[0];
  EXPECT_EQ(a.tests, 3);
  EXPECT_EQ(a.reached, 2);
  EXPECT_EQ(a.scenario, "scenario1");
  EXPECT_NEAR(a.x, 0.2, 0.01);
  EXPECT_NEAR(a.y, 0.5, 0.01);
  EXPECT_EQ(a.colour_action, kTurnGreen);  // the blue square at the place, to turn green
  ASSERT_TRUE(a.place_affordance);
  EXPECT_GT((*a.place_affordance)[kTurnGreen], 0.5);
  EXPECT_EQ(a.colour_blocked, 1);  // the third test's threshold kept turn green from being asked about
  ASSERT_TRUE(a.closest);
  EXPECT_TRUE(a.closest->passes());
  EXPECT_EQ(a.closest->action, kTurnGreen);
  EXPECT_EQ(a.not_checked + a.what_miss + a.where_miss + a.passed, 1);

  const std::vector<SystemSubGoal> systems = subGoalsBySystem(agents);
  ASSERT_EQ(systems.size(), 1u);
  EXPECT_EQ(systems[0].agents, 1);
  EXPECT_EQ(systems[0].agents_always, 0);
  EXPECT_EQ(systems[0].agents_colour_blocked, 1);
  ASSERT_EQ(systems[0].closest_what.size(), 1u);
  EXPECT_DOUBLE_EQ(systems[0].closest_what[0], a.closest->what_distance);

  const auto r = test::runCommand("(" + test::afford("explain --by-agent --json " + root.string()) + " 2>/dev/null)");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j["by_agent"].size(), 1u);
  EXPECT_EQ(j["by_agent"][0]["agent"], agent);
  EXPECT_EQ(j["by_agent"][0]["colour_action"], "turn green");
  EXPECT_EQ(j["by_system"][0]["agents_colour_blocked"], 1);
  const auto text = test::runCommand("(" + test::afford("explain --by-agent " + root.string()) + " 2>/dev/null)");
  EXPECT_NE(text.output.find("turn green"), std::string::npos) << text.output;
  // --by-agent needs a folder of logs.
  const auto one = test::runCommand(test::afford("explain --by-agent " + solved.log) + " 2>&1");
  EXPECT_NE(one.exit_code, 0);
  EXPECT_NE(one.output.find("--by-agent summarises a folder of run logs"), std::string::npos) << one.output;
}

// A recording of a bus that carried a forged RUN_CONFIG and a log with a
// malformed event (a header claiming 0x7FFFFFFF bytes, as in the 3 KB file
// that crashed LCM's reader): replay skips both, names the event's offset,
// and replays the run to its recorded weights.
TEST(ReplayOfAForgedRecording, SkipsWhatItCannotTakeAndReplaysTheRun) {
  InProcessRun run(test::baseYaml(System::IMP, 200), System::IMP, 3, 200);
  ASSERT_TRUE(run.outcome.ok) << run.outcome.error;
  const fs::path dir = fs::path(test::tempDir("replay-forged")) / "forged";
  std::vector<test::Event> events;
  // Before the run's own: a RUN_CONFIG with the right fingerprint and nothing else right.
  std::vector<std::uint8_t> junk(300, 0x41);
  const std::int64_t hash = run_config_t::getHash();
  for (int i = 0; i < 8; ++i) junk[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(hash >> (56 - 8 * i));
  events.push_back({ch::runConfig.name, junk});
  events.insert(events.end(), run.events.begin(), run.events.end());
  writeLog(events, dir);
  // A malformed event spliced in after the tenth.
  const fs::path file = dir / "log.00.lcm";
  std::ifstream in(file, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  std::size_t at = 0;
  for (std::size_t i = 0; i < 10; ++i) at += 28 + events[i].channel.size() + events[i].data.size();
  std::vector<char> bad = {'\xED', '\xA1', '\xDA', '\x01'};
  bad.resize(20, 0);
  for (char c : {'\x00', '\x00', '\x00', '\x05', '\x7F', '\xFF', '\xFF', '\xFF'}) bad.push_back(c);
  for (char c : std::string("SCENE")) bad.push_back(c);
  bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(at), bad.begin(), bad.end());
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));

  const auto r = test::runCommand(test::afford("replay " + dir.string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("offset " + std::to_string(at) + ": data length 2147483647"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("skipped: 1 malformed part"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("skipped: 1 RUN_CONFIG event(s) the edge refuses"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("weights_checksum: " + run.outcome.weights_checksum), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("replay equals the record"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace afford

// The real executables over udpm, in a private network namespace that the
// `afford` runner creates for itself (needs root or user namespaces).
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <thread>

#include "afford/effect_t.hpp"
#include "afford/protocol.hpp"
#include "afford/scene_t.hpp"
#include "experiment/design/tables.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using test::readJson;

using test::slurp;

// `afford experiment ARGS` writing into DIR, with a log root of its own, DIR/logs:
// tests running at the same time never share a run folder (checkpoints live there).
std::string experimentIn(const std::string& dir, const std::string& args) {
  return test::afford("experiment " + args + " --out " + dir + " --log-root " + dir + "/logs");
}

// One short IMP base run; returns the output folder. The log root is part of
// the run's config (its checkpoint path), so runs to compare share one.
// Each trains its agent (--no-reuse-agents): the runs compared must both run.
std::string runBase(const std::string& name, const std::string& transport, int port,
                    const std::string& log_root = "") {
  const std::string dir = test::tempDir(name);
  const std::string logs = log_root.empty() ? dir + "/logs" : log_root;
  const auto r = test::runCommand(test::afford("experiment base --system IMP --reps 1 --steps 300 --seed 11 --quiet"
                                               " --run-prefix it --no-reuse-agents --transport " + transport + " --out " + dir +
                                               " --log-root " + logs + " --base-port " + std::to_string(port)));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return dir;
}

TEST(Processes, RealProcessesRunTheBaseTestAndRecordIt) {
  const std::string dir = runBase("udpm", "udpm", 7810);
  const json s = readJson(fs::path(dir) / "summary.json");
  const json& run = s["systems"]["IMP"]["runs"][0];
  EXPECT_EQ(run["run_id"], "it-base-IMP-s11");
  EXPECT_EQ(run["seed"], 11);
  EXPECT_EQ(run["weights_checksum"].get<std::string>().size(), 16u);
  ASSERT_EQ(run["affordance"].size(), 9u);
  EXPECT_EQ(run["affordance"][0].size(), 4u);
  EXPECT_EQ(s["systems"]["IMP"]["target"][0], json({1.0, 1.0, 0.0, 1.0}));
  EXPECT_EQ(s["systems"]["IMP"]["curves"]["steps"], json({0, 100, 200, 300}));
  EXPECT_TRUE(fs::exists(run["checkpoint"].get<std::string>()));  // the trained predictors, for the extrinsic phase

  const fs::path log_dir = run["log_dir"].get<std::string>();
  const auto events = test::readLog((log_dir / "log.00.lcm").string());
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front().channel, ch::runConfig.name);
  std::map<std::string, int> count;
  for (const auto& e : events) ++count[e.channel];
  EXPECT_EQ(count[ch::prediction.name], 300);
  EXPECT_EQ(count[ch::decision.name], 300);
  EXPECT_EQ(count[ch::focus.name], 300);
  EXPECT_EQ(count[ch::result.name], 1);
  EXPECT_EQ(count[ch::status.name], 0);  // heartbeats are not recorded
  EXPECT_EQ(count[ch::effect.name], test::trainingReports(events));

  const json m = readJson(log_dir / "manifest.json");
  EXPECT_EQ(m["seed"], 11);
  EXPECT_EQ(m["complete"], true);
  EXPECT_FALSE(m["config_yaml"].get<std::string>().empty());
  std::set<std::string> procs;
  for (const auto& p : m["processes"]) procs.insert(p["process"].get<std::string>());
  EXPECT_EQ(procs, (std::set<std::string>{"environment", "eye", "logger", "motivation", "predictors"}));
}

// Each channel has one publisher and a sender's datagrams arrive in order, so
// every channel's messages are identical on both transports, but for the bytes
// that name each run's own request (test::withoutRequest). (The interleaving
// of channels follows causality, but the kernel hands a multicast datagram to
// the sockets one by one, so a fast answer can overtake its cause on the way
// to the logger: about once in 40 udpm runs under load.)
std::map<std::string, std::vector<std::vector<std::uint8_t>>> byChannel(const std::vector<test::Event>& events) {
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> out;
  for (const auto& e : events) out[e.channel].push_back(test::withoutRequest(e.channel, e.data));
  return out;
}

TEST(Processes, UdpmAndMemqRunsGiveByteIdenticalLogsAndWeights) {
  const std::string logs = test::tempDir("det-logs");
  const std::string a = runBase("det-udpm", "udpm", 7820, logs);
  fs::rename(logs + "/it-base-IMP-s11", logs + "/udpm");
  const std::string b = runBase("det-memq", "memq", 7830, logs);
  const json sa = readJson(fs::path(a) / "summary.json"), sb = readJson(fs::path(b) / "summary.json");
  EXPECT_EQ(sa["systems"]["IMP"]["runs"][0]["weights_checksum"], sb["systems"]["IMP"]["runs"][0]["weights_checksum"]);
  const auto ea = test::readLog(logs + "/udpm/log.00.lcm");
  const auto eb = test::readLog(logs + "/it-base-IMP-s11/log.00.lcm");
  ASSERT_EQ(ea.size(), eb.size());
  EXPECT_NE(ea.front().data, eb.front().data);  // two requests of the run: each its own ...
  EXPECT_EQ(test::withoutRequest("RUN_CONFIG", ea.front().data),
            test::withoutRequest("RUN_CONFIG", eb.front().data));  // ... of the same RUN_CONFIG
  const auto ca = byChannel(ea), cb = byChannel(eb);
  ASSERT_EQ(ca.size(), cb.size());
  for (const auto& [channel, messages] : ca) {
    ASSERT_TRUE(cb.count(channel)) << channel;
    const auto& other = cb.at(channel);
    ASSERT_EQ(messages.size(), other.size()) << channel;
    for (std::size_t i = 0; i < messages.size(); ++i)
      ASSERT_EQ(messages[i], other[i]) << channel << " message " << i;
  }
}

// `afford WHAT` (an experiment of one run) over a transport into a folder of its own and the log root `logs`
// (its run named it-<experiment>-<system>-s<seed>): its summary.
json runInto(const std::string& what, const std::string& name, const std::string& transport, int port,
             const std::string& logs) {
  const std::string dir = test::tempDir(name);
  const auto r = test::runCommand(test::afford(what + " --quiet --run-prefix it --no-reuse-agents --transport " +
                                               transport + " --out " + dir + " --log-root " + logs + " --base-port " +
                                               std::to_string(port)));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return readJson(fs::path(dir) / "summary.json");
}

// `what` over udpm, then over memq (its run named `run` in the log root): both summaries, both logs' messages by
// channel, and the udpm run's log folder.
struct TwoRuns {
  json udpm, memq;
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> udpm_channels, memq_channels;
  std::string udpm_log;
};
TwoRuns overBoth(const std::string& what, const std::string& name, const std::string& run, int port) {
  const std::string logs = test::tempDir(name + "-logs");
  TwoRuns t;
  t.udpm = runInto(what, name + "-udpm", "udpm", port, logs);
  t.udpm_log = logs + "/udpm";
  fs::rename(logs + "/" + run, t.udpm_log);
  t.memq = runInto(what, name + "-memq", "memq", port + 10, logs);
  t.udpm_channels = byChannel(test::readLog(t.udpm_log + "/log.00.lcm"));
  t.memq_channels = byChannel(test::readLog(logs + "/" + run + "/log.00.lcm"));
  EXPECT_EQ(t.udpm_channels.size(), t.memq_channels.size());
  for (const auto& [channel, messages] : t.udpm_channels) {
    EXPECT_TRUE(t.memq_channels.count(channel)) << channel;
    if (t.memq_channels.count(channel)) EXPECT_EQ(messages, t.memq_channels.at(channel)) << channel;
  }
  return t;
}

// The goals phase (issue 41): a GOALS run over udpm and over memq is one run, channel by channel, and
// replayed from its log into the planner, the goal chooser and the predictors it is the same again.
TEST(Processes, AGoalsRunIsOneRunOverUdpmAndMemqAndReplayedFromItsLog) {
  const TwoRuns t = overBoth("experiment base --system GOALS --reps 1 --steps 300 --seed 11", "goals", "it-base-GOALS-s11",
                             7850);
  const json &sa = t.udpm, &sb = t.memq;
  const auto& ca = t.udpm_channels;
  const json& ra = sa["systems"]["GOALS"]["runs"][0];
  EXPECT_EQ(ra["weights_checksum"], sb["systems"]["GOALS"]["runs"][0]["weights_checksum"]);
  EXPECT_EQ(sa["systems"]["GOALS"]["goals"], sb["systems"]["GOALS"]["goals"]);
  ASSERT_TRUE(ca.count(ch::goal.name) && ca.count(ch::goalResult.name));
  const auto replayed = test::runAfford("replay " + t.udpm_log);
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("weights_checksum: " + ra["weights_checksum"].get<std::string>()), std::string::npos)
      << replayed.output;
  const std::string goals = std::to_string(ca.at(ch::goal.name).size());
  EXPECT_NE(replayed.output.find("goals: " + goals + " replayed, " + goals + " recorded, 0 differing"), std::string::npos)
      << replayed.output;
  EXPECT_NE(replayed.output.find("replay equals the record"), std::string::npos) << replayed.output;
}

// The physical table (issue 58): an IMP run in the table world over udpm and over memq is one run, channel by
// channel, its weights the same, and replayed from its log into the eye, the predictors and the motivation it is
// the same again. The truth both are measured against is estimated once (4 trials a cell) in the log root.
TEST(Processes, ATableRunIsOneRunOverUdpmAndMemqAndReplayedFromItsLog) {
  const TwoRuns t = overBoth("experiment table --system IMP --reps 1 --steps 160 --seed 4 --set table.truth.trials=4",
                             "table", "it-table-IMP-s4", 7870);
  const json &sa = t.udpm, &sb = t.memq;
  const auto& ca = t.udpm_channels;
  const json& ra = sa["systems"]["IMP"]["runs"][0];
  EXPECT_EQ(ra["weights_checksum"], sb["systems"]["IMP"]["runs"][0]["weights_checksum"]);
  EXPECT_EQ(sa["actions"], json({"push", "carry", "topple", "roll"}));
  // Measured against the table's truth, which physics decided: not a table of zeros.
  double truth = 0;
  for (const auto& row : sa["systems"]["IMP"]["target"])
    for (double v : row) truth += v;
  EXPECT_GT(truth, 1.0) << sa["systems"]["IMP"]["target"];
  // The hand acted on objects, some actions had their effect, and the scene is the camera's 320 x 240.
  ASSERT_TRUE(ca.count(ch::scene.name));
  scene_t first;
  first.decode(ca.at(ch::scene.name).front().data(), 0, static_cast<int>(ca.at(ch::scene.name).front().size()));
  EXPECT_EQ(first.width, 320);
  EXPECT_EQ(first.height, 240);
  int seen = 0;
  for (const auto& m : ca.at(ch::effect.name)) {
    effect_t e;
    e.decode(m.data(), 0, static_cast<int>(m.size()));
    seen += e.affordance ? 1 : 0;
  }
  EXPECT_GT(seen, 0);
  const auto replayed = test::runAfford("replay " + t.udpm_log);
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("weights_checksum: " + ra["weights_checksum"].get<std::string>()), std::string::npos)
      << replayed.output;
  EXPECT_NE(replayed.output.find("replay equals the record"), std::string::npos) << replayed.output;
}

// A CSV's lines without their last column (wall_seconds).
std::vector<std::string> withoutLastColumn(const fs::path& csv) {
  std::vector<std::string> out;
  std::ifstream in(csv);
  for (std::string line; std::getline(in, line);) out.push_back(line.substr(0, line.rfind(',')));
  return out;
}

// A memq job slot keeps its nodes from one run or test to the next, as a udpm
// slot keeps its processes: intrinsic runs, the switch to the extrinsic phase,
// a logger started for the first recorded run only, the agents' predictions
// kept between tests. Every run and test must still come out as over udpm.
TEST(Processes, AMemqSlotServesItsRunsAndTestsInTurnAsUdpmProcessesDo) {
  std::map<std::string, std::string> out;
  for (const auto& [transport, port] : {std::pair<std::string, int>{"udpm", 7850}, {"memq", 7860}}) {
    out[transport] = test::tempDir("slot-" + transport);
    const auto r = test::runCommand(experimentIn(
        out[transport], "base --system IMP --reps 3 --steps 400 --extrinsic-reps 2 --scenarios scenario1 scenario3"
                        " --jobs 1 --keep-logs first --no-reuse-agents --quiet --run-prefix " + transport +
                        " --transport " + transport + " --base-port " + std::to_string(port)));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const json a = readJson(fs::path(out["udpm"]) / "summary.json"), b = readJson(fs::path(out["memq"]) / "summary.json");
  ASSERT_EQ(a["systems"]["IMP"]["runs"].size(), 3u);
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_EQ(a["systems"]["IMP"]["runs"][i]["weights_checksum"], b["systems"]["IMP"]["runs"][i]["weights_checksum"]) << i;
  std::vector<std::string> ta = withoutLastColumn(fs::path(out["udpm"]) / "extrinsic_IMP.csv"),
                           tb = withoutLastColumn(fs::path(out["memq"]) / "extrinsic_IMP.csv");
  ASSERT_EQ(ta.size(), 13u);  // the header and 3 agents x 2 scenarios x 2 tests
  for (auto& line : tb) line = std::regex_replace(line, std::regex("memq-base"), "udpm-base");  // the run ids' prefix
  EXPECT_EQ(ta, tb);
}

TEST(Processes, RealProcessesSolveAnExtrinsicScenario) {
  const std::string dir = test::tempDir("extrinsic-udpm");
  const auto r = test::runCommand(experimentIn(
      dir, "base --system IMP --reps 1 --steps 6000 --seed 2 --extrinsic-reps 1 --scenarios scenario3 --quiet"
           " --run-prefix ex --base-port 7850"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(fs::path(dir) / "summary.json");
  const json& ex = s["systems"]["IMP"]["extrinsic"];
  EXPECT_EQ(ex["success_rate"]["scenario3"], 1.0);
  EXPECT_EQ(ex["table_metric"]["scenario3"], 1.0);
  EXPECT_EQ(ex["completion_steps"]["scenario3"]["sub_goals"], 3);
  // The test's own log: the planner's looks, queries and decisions.
  const auto events = test::readLog(dir + "/logs/ex-base-IMP-s2-scenario3-e0/log.00.lcm");
  std::map<std::string, int> count;
  for (const auto& e : events) ++count[e.channel];
  EXPECT_GT(count[ch::look.name], 0);
  EXPECT_GT(count[ch::forwardQuery.name], 0);
  EXPECT_EQ(count[ch::forwardQuery.name], count[ch::forwardPrediction.name]);
  EXPECT_EQ(count[ch::decision.name], 3);  // one action per sub-goal
  EXPECT_EQ(count[ch::extrinsicResult.name], 1);

  // The figures and the report from that folder.
  const auto plot = test::runCommand(test::afford("plot " + dir));
  ASSERT_EQ(plot.exit_code, 0) << plot.output;
  for (const char* png : {"fig_affordances.png", "fig_curves_IMP.png", "fig_completion.png"}) {
    const std::string bytes = slurp(fs::path(dir) / png);
    EXPECT_GT(bytes.size(), 10000u) << png;
    EXPECT_EQ(bytes.substr(1, 3), "PNG") << png;
    EXPECT_TRUE(fs::exists(fs::path(dir) / (fs::path(png).stem().string() + ".csv"))) << png;
  }
  const auto rep = test::runCommand(test::afford("report " + dir + " --out " + dir + "/results.md --figures " + dir + "/figs"));
  ASSERT_EQ(rep.exit_code, 0) << rep.output;
  const std::string md = slurp(fs::path(dir) / "results.md");
  EXPECT_NE(md.find("| scenario3 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| IMP | 1.00 (1.0) |"), std::string::npos) << md;  // beside the paper's Table 2, scenario 3
  EXPECT_TRUE(fs::exists(fs::path(dir) / "figs" / "base" / "fig_completion.png"));
}

// The planner comparisons of the paper's section 3.2, end to end at small
// counts (memq): the summary keys outside checks read, and the figures.
TEST(Processes, TheUtilityDesignComparesThePlannersPerBudget) {
  const std::string dir = test::tempDir("design-utility");
  const auto r = test::runCommand(experimentIn(dir, "utility --reps 2 --steps 4000 --extrinsic-reps 3 --jobs 2"
                                                    " --transport memq --keep-logs none --quiet"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(fs::path(dir) / "summary.json");
  EXPECT_EQ(s["systems"].size(), 1u);  // default_systems: IMP only
  const json& u = s["utility"];
  EXPECT_EQ(u["budgets"], json({1, 2, 3, 4, 5}));
  ASSERT_EQ(u["p_values"].size(), 5u);
  ASSERT_EQ(u["goal_mean"].size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(u["n"][k], json({6, 6}));  // 2 agents x 3 tests per planner and budget
    EXPECT_GE(u["utility_mean"][k].get<double>(), 0.0);
    EXPECT_LE(u["utility_mean"][k].get<double>(), 8.0);  // the values sum to 8
  }
  EXPECT_EQ(s["systems"]["IMP"]["extrinsic"]["conditions"].size(), 10u);
  const auto plot = test::runCommand(test::afford("plot " + dir));
  ASSERT_EQ(plot.exit_code, 0) << plot.output;
  for (const char* png : {"fig_utility.png", "fig_stochastic.png"})
    EXPECT_EQ(slurp(fs::path(dir) / png).substr(1, 3), "PNG") << png;
}

TEST(Processes, TheSearchDesignCountsActionsCheckedWithAndWithoutRestriction) {
  const std::string dir = test::tempDir("design-search");
  const auto r = test::runCommand(experimentIn(dir, "search-reduction --reps 1 --steps 4000 --extrinsic-reps 3"
                                                    " --transport memq --keep-logs none --quiet"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(fs::path(dir) / "summary.json");
  const json& q = s["search"];
  // Without restriction every action before the match is checked: never fewer.
  EXPECT_LE(q["restricted_mean"].get<double>(), q["unrestricted_mean"].get<double>());
  EXPECT_GE(q["restricted_mean"].get<double>(), 1.0);
  EXPECT_TRUE(q.contains("p_value"));
}

TEST(Processes, AgentsThatNeverReachTheActionCountAreNotTestedAndTheCommandSaysWhy) {
  const std::string dir = test::tempDir("design-after");
  const auto r = test::runCommand(experimentIn(dir, "forward-models --system IMP --reps 1 --steps 300"
                                                    " --transport memq --keep-logs none --quiet"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("executed fewer than 4000 actions"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("extrinsic.after_actions"), std::string::npos) << r.output;
  const json s = readJson(fs::path(dir) / "summary.json");  // the intrinsic results are kept
  EXPECT_EQ(s["untested_agents"].size(), 1u);
  EXPECT_EQ(s["systems"]["IMP"]["runs"].size(), 1u);
}

TEST(Processes, TheForwardModelDesignTestsTheWeightsSavedAfterTheActionCount) {
  const std::string dir = test::tempDir("design-fm");
  // FIX acts on nearly every step, so 4500 steps reach 4000 actions.
  const auto r = test::runCommand(experimentIn(
      dir, "forward-models --system FIX --reps 1 --steps 4500 --extrinsic-reps 2 --transport memq"
           " --keep-logs none --quiet --run-prefix fm"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(fs::path(dir) / "summary.json");
  EXPECT_EQ(s["after_actions"], 4000);
  EXPECT_EQ(s["systems"]["FIX"]["utility_mean"].size(), 3u);
  // The early checkpoint differs from the final one: the run learned on after it.
  const std::string early = slurp(dir + "/logs/fm-forward-models-FIX-s1/predictors.after-4000-actions.ckpt");
  const std::string last = slurp(dir + "/logs/fm-forward-models-FIX-s1/predictors.ckpt");
  ASSERT_GT(early.size(), 1000u);
  ASSERT_GT(last.size(), 1000u);
  // Both deflated checkpoints of the same network: the same magic and the same plain size (bytes 8-15).
  EXPECT_EQ(early.substr(0, 16), last.substr(0, 16));
  EXPECT_EQ(early.substr(0, 8), "AFFORDCZ");
  EXPECT_NE(early, last);
}

TEST(Processes, ABadValueInAnExtrinsicDesignIsRefusedBeforeAnyRun) {
  const std::string dir = test::tempDir("design-bad");
  fs::copy(std::string(AFFORD_SOURCE_DIR) + "/config", dir + "/config", fs::copy_options::recursive);
  std::ofstream(dir + "/config/experiments/mine.yaml")
      << "extends: utility\nextrinsic:\n  scenarios: [utility]\n  tests: 2\n"
         "  vary:\n    planner.max_attempts: [1, 0]\n";
  const auto r = test::runCommand(test::afford("--config-dir " + dir + "/config experiment mine --out " + dir +
                                               "/out --log-root " + dir + "/logs"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("config key 'planner.max_attempts': value 0 is out of range"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir + "/out"));
}

// Exact replay: a run's log fed into fresh learning processes gives the live
// run's weights and decisions (intrinsic), and the planner's decisions (extrinsic).
TEST(Processes, AReplayedLogReproducesTheLiveRun) {
  const std::string dir = test::tempDir("replay");
  const auto r = test::runCommand(experimentIn(
      dir, "base --system IGN --reps 1 --steps 800 --extrinsic-reps 1 --scenarios scenario2 --transport memq"
           " --keep-logs all --quiet --run-prefix rp"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(fs::path(dir) / "summary.json");
  const std::string live = s["systems"]["IGN"]["runs"][0]["weights_checksum"];

  const auto intrinsic = test::runCommand(test::afford("replay " + dir + "/logs/rp-base-IGN-s1"));
  EXPECT_EQ(intrinsic.exit_code, 0) << intrinsic.output;
  EXPECT_NE(intrinsic.output.find("weights_checksum: " + live), std::string::npos) << intrinsic.output;
  EXPECT_NE(intrinsic.output.find(" 0 differing"), std::string::npos) << intrinsic.output;
  EXPECT_EQ(intrinsic.output.find("decisions: 0 replayed"), std::string::npos) << intrinsic.output;

  const auto extrinsic = test::runCommand(test::afford("replay " + dir + "/logs/rp-base-IGN-s1-scenario2-e0"));
  EXPECT_EQ(extrinsic.exit_code, 0) << extrinsic.output;
  EXPECT_NE(extrinsic.output.find("(extrinsic)"), std::string::npos) << extrinsic.output;
  EXPECT_NE(extrinsic.output.find(" 0 differing"), std::string::npos) << extrinsic.output;

  // A log whose writer died mid-event: replayed up to the last whole event, with a warning.
  const fs::path torn = fs::path(dir) / "torn";
  fs::create_directories(torn);
  std::string bytes = slurp(fs::path(dir) / "logs/rp-base-IGN-s1/log.00.lcm");
  bytes.resize(bytes.size() - 7);
  std::ofstream(torn / "log.00.lcm", std::ios::binary) << bytes;
  const auto cut = test::runCommand(test::afford("replay " + torn.string() + " --into predictors"));
  EXPECT_NE(cut.output.find("incomplete"), std::string::npos) << cut.output;
  EXPECT_NE(cut.output.find("weights_checksum: " + live), std::string::npos) << cut.output;  // the run was over by then
  // The same file named without its folder, from within it.
  const auto bare = test::runCommand("cd " + torn.string() + " && " + test::afford("replay log.00.lcm --into predictors"));
  EXPECT_NE(bare.output.find("weights_checksum: " + live), std::string::npos) << bare.output;

  const auto missing = test::runCommand(test::afford("replay " + dir + "/nosuch"));
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("no run log at"), std::string::npos) << missing.output;
}

// A recording that lost messages (an lcm-logger capture, say): replay names
// the channels and serials missing, replays as far as it can, compares that
// with the record, and does not call it equal. Replay writes nothing into
// the recorded run's folder.
TEST(Processes, AReplayOfARecordingWithGapsNamesThemAndComparesWhatItCan) {
  const std::string dir = test::tempDir("replay-gaps");
  const auto r = test::runCommand(experimentIn(dir, "base --system IMP --reps 1 --steps 600 --transport memq --quiet"
                                                    " --run-prefix gp"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path run = fs::path(dir) / "logs" / "gp-base-IMP-s1";
  std::map<std::string, std::string> before;
  for (const auto& f : fs::directory_iterator(run)) before[f.path().filename().string()] = slurp(f.path());

  // A copy of the log without FOCUS 300..302 and DECISION 400.
  const auto events = test::readLog((run / "log.00.lcm").string());
  const fs::path gaps = fs::path(dir) / "gaps.lcm";
  {
    lcm::LogFile out(gaps.string(), "w");
    int decision = 0, focus = 0, n = 0;
    for (const auto& e : events) {
      if (e.channel == ch::focus.name && (focus++ >= 300 && focus <= 303)) continue;
      if (e.channel == ch::decision.name && decision++ == 400) continue;
      lcm::LogEvent ev;
      ev.eventnum = n++;
      ev.timestamp = 0;
      ev.channel = e.channel;
      ev.datalen = static_cast<int32_t>(e.data.size());
      ev.data = const_cast<std::uint8_t*>(e.data.data());
      out.writeEvent(&ev);
    }
  }
  const auto replay = test::runCommand(test::afford("replay " + gaps.string()));
  EXPECT_EQ(replay.exit_code, 1) << replay.output;
  EXPECT_NE(replay.output.find("missing from the recording: FOCUS serials 300..302"), std::string::npos) << replay.output;
  EXPECT_NE(replay.output.find("missing from the recording: DECISION serial 400"), std::string::npos) << replay.output;
  EXPECT_NE(replay.output.find("weights_checksum: (not reached"), std::string::npos) << replay.output;
  // The motivation decides on the recorded predictions: all 600, compared where the record has them.
  EXPECT_NE(replay.output.find("decisions: 600 replayed, 599 recorded, 0 differing"), std::string::npos) << replay.output;
  EXPECT_NE(replay.output.find("replay equals the record as far as it goes, but the record is missing messages"),
            std::string::npos)
      << replay.output;

  // The whole log replays equal, and nothing in the run's folder changed.
  const auto whole = test::runCommand(test::afford("replay " + run.string()));
  EXPECT_EQ(whole.exit_code, 0) << whole.output;
  for (const auto& [name, bytes] : before) EXPECT_EQ(slurp(run / name), bytes) << name << " changed";
  EXPECT_EQ(std::distance(fs::directory_iterator(run), fs::directory_iterator{}), static_cast<long>(before.size()));
}

struct BadConfigCase {
  const char* name;
  const char* args;
  const char* message;
};

class BadConfig : public ::testing::TestWithParam<BadConfigCase> {};

TEST_P(BadConfig, ExitsNonZeroNamingTheKeyBeforeAnyProcessStarts) {
  const std::string dir = test::tempDir(std::string("badcfg-") + GetParam().name);
  std::string args = GetParam().args;
  if (args.find("CONFIG_DIR") != std::string::npos) {
    // A copy of the shipped config with one key removed.
    fs::copy(std::string(AFFORD_SOURCE_DIR) + "/config", dir + "/config", fs::copy_options::recursive);
    std::string d = slurp(dir + "/config/defaults.yaml");
    const auto at = d.find("  saliency_noise:");
    d.erase(at, d.find('\n', at) - at + 1);
    std::ofstream(dir + "/config/defaults.yaml") << d;
    args.replace(args.find("CONFIG_DIR"), 10, dir + "/config");
  }
  const auto r = test::runCommand(test::afford(args + " --out " + dir + "/out --log-root " + dir + "/logs"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(GetParam().message), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir + "/out")) << "the runner went ahead";
  EXPECT_FALSE(fs::exists(dir + "/logs"));
}

INSTANTIATE_TEST_SUITE_P(
    EachKind, BadConfig,
    ::testing::Values(
        BadConfigCase{"UnknownExperiment", "experiment nosuch", "unknown experiment \"nosuch\""},
        BadConfigCase{"WrongType", "experiment base --set predictors.affordance.learning_rate=fast",
                      "config key 'predictors.affordance.learning_rate': expected a number"},
        BadConfigCase{"OutOfRange", "experiment base --set eye.position_change_threshold=3",
                      "config key 'eye.position_change_threshold': value 3 is out of range"},
        BadConfigCase{"UnknownKey", "experiment base --set eye.colour=1", "config key 'eye.colour': unknown key"},
        BadConfigCase{"MissingKey", "--config-dir CONFIG_DIR experiment base",
                      "config key 'eye.saliency_noise': missing"},
        BadConfigCase{"UnknownSystem", "experiment base --system XYZ", "unknown system \"XYZ\""},
        BadConfigCase{"BadConditionValue", "experiment utility --set planner.kind=both",
                      "config key 'planner.kind': unknown value \"both\""},
        BadConfigCase{"BadMemoryValue", "experiment random-tables --set predictors.replay.sampling=random",
                      "config key 'predictors.replay.sampling': unknown value \"random\""},
        BadConfigCase{"TablesWithoutRandomTables", "experiment base --tables 3",
                      "--tables and --table-seed are for experiments on random tables"},
        BadConfigCase{"ExtrinsicTestsOfRandomTables", "experiment random-tables --extrinsic-reps 2",
                      "random tables have no extrinsic tests"}),
    [](const auto& info) { return std::string(info.param.name); });

// random-tables (issue 11): every condition on every table, each run measured against its own table, drawn by
// (seed, index); the memory condition's runs keep a memory, the paper's do not; the figure is drawn.
TEST(Processes, RandomTablesCompareTheConditionsOnEachTable) {
  const std::string dir = test::tempDir("random-tables");
  const auto r = test::runCommand(experimentIn(
      dir, "random-tables --system IGN --tables 2 --table-seed 9 --steps 300 --transport memq --jobs 2 --keep-logs none"
           " --run-prefix rt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 tables drawn from seed 9"), std::string::npos) << r.output;
  const json s = readJson(fs::path(dir) / "summary.json");
  const json& rt = s["random_tables"];
  const auto objects = test::shippedConfig("random-tables").world.objects;
  ASSERT_EQ(rt["tables"].size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const AffordanceTable want = randomTable(9, k, objects);
    for (std::size_t i = 0; i < objects.size(); ++i)
      for (int a = 0; a < kNumActions; ++a) EXPECT_EQ(rt["tables"][k][i][a].get<double>(), want[i][a]);
  }
  EXPECT_EQ(rt["condition_order"], json({"paper", "memory"}));
  const json& runs = s["systems"]["IGN"]["runs"];
  ASSERT_EQ(runs.size(), 4u);
  std::map<std::string, std::vector<double>> per_condition;
  for (const auto& run : runs) {
    const int k = run["table"].get<int>();
    EXPECT_EQ(run["target"], rt["tables"][k]);
    double mae = 0;
    for (std::size_t i = 0; i < objects.size(); ++i)
      for (int a = 0; a < kNumActions; ++a)
        mae += std::abs(run["affordance"][i][a].get<double>() - run["target"][i][a].get<double>()) / (objects.size() * kNumActions);
    EXPECT_NEAR(run["affordance_mae"].get<double>(), mae, 1e-12);
    const std::string c = run["condition"];
    EXPECT_EQ(run["run_id"].get<std::string>(), "rt-random-tables-t0" + std::to_string(k) + "-" + c + "-IGN-s1");
    if (c == "memory") {
      EXPECT_GT(run["looks"].get<int>(), 0);
      EXPECT_GT(run["revisits"].get<int>(), 0);
    } else {
      EXPECT_EQ(run["looks"].get<int>(), 0);
    }
    per_condition[c].push_back(mae);
  }
  for (const auto& [c, maes] : per_condition) {
    const json& m = rt["mae"][c]["IGN"];
    EXPECT_EQ(m["tables"].get<int>(), 2);
    EXPECT_NEAR(m["worst"].get<double>(), std::max(maes[0], maes[1]), 1e-12) << c;
  }
  const std::string csv = slurp(fs::path(dir) / "random_tables.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5) << csv;  // a header and 4 runs
  const auto plot = test::runCommand(test::afford("plot " + dir));
  EXPECT_EQ(plot.exit_code, 0) << plot.output;
  EXPECT_TRUE(fs::exists(fs::path(dir) / "fig_random_tables.png")) << plot.output;
}

// The memory options over real processes: a run's log replays into fresh predictors and motivation to the same
// weights and memory, decision for decision, and its agent (a checkpoint with a memory) passes an extrinsic test.
TEST(Processes, AMemoryRunReplaysExactlyAndItsAgentIsTested) {
  const std::string dir = test::tempDir("memory-replay");
  const auto r = test::runCommand(experimentIn(
      dir, "base --system IMP --reps 1 --steps 600 --extrinsic-reps 1 --scenarios scenario1 --keep-logs all --quiet"
           " --run-prefix mr --set predictors.replay.enabled=true --set motivation.revisit.enabled=true"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(fs::path(dir) / "summary.json");
  const json& run = s["systems"]["IMP"]["runs"][0];
  EXPECT_GT(run["looks"].get<int>(), 0);
  EXPECT_EQ(run["replayed"].get<std::int64_t>(), 600 * 64);  // every step replays, passes too (step 0 acts: a revisit)
  EXPECT_EQ(s["extrinsic_tests"].get<int>(), 1);  // the checkpoint, memory and all, loaded for the test
  const auto replay = test::runCommand(test::afford("replay " + dir + "/logs/mr-base-IMP-s1"));
  EXPECT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("weights_checksum: " + run["weights_checksum"].get<std::string>()), std::string::npos)
      << replay.output;
  EXPECT_NE(replay.output.find(" 0 differing"), std::string::npos) << replay.output;
}

TEST(Processes, ARunNeverWritesIntoTheLogFolderOfAnotherRun) {
  const std::string dir = test::tempDir("existing");
  fs::create_directories(dir + "/logs/x-base-IMP-s1");
  const auto r = test::runCommand(test::afford("experiment base --system IMP --reps 1 --steps 50 --run-prefix x --out " +
                                               dir + "/out --log-root " + dir + "/logs"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("exists already"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir + "/out"));
}

// A log root that is a file: no run can have its folder there, so the experiment is refused before any run,
// naming the folder and why (not run to the end with a checkpoint it could not write).
TEST(Processes, ALogRootWhereNoRunFolderCanBeMadeIsRefusedBeforeAnyRun) {
  const std::string dir = test::tempDir("no-checkpoint");
  std::ofstream(dir + "/not-a-folder") << "x";
  const auto r = test::runCommand(test::afford("experiment base --system IMP --reps 1 --steps 50 --extrinsic-reps 1"
                                               " --scenarios scenario1 --transport memq --keep-logs none --quiet"
                                               " --run-prefix nc --out " + dir + "/out --log-root " + dir +
                                               "/not-a-folder"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cannot make the log folder " + dir + "/not-a-folder/nc-base-IMP-s1 (Not a directory)"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(fs::path(dir) / "out")) << "a refused experiment leaves no folder";
}

TEST(Processes, AKilledProcessEndsTheRunWithinSecondsNamingIt) {
  const std::string dir = test::tempDir("kill"), said = test::tempDir("kill-said");  // (the experiment's folder is its own)
  const int port = 7840;
  const std::string cmd = experimentIn(
      dir, "base --system IMP --reps 1 --steps 10000000 --keep-logs none --base-port " + std::to_string(port));
  std::system(("sh -c '(" + cmd + " > " + said + "/out.txt 2>&1; echo $? > " + said + "/rc) &'").c_str());
  const fs::path eye_log = fs::path(dir) / "processes" / "slot0" / "eye.log";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (slurp(eye_log).find("configured") == std::string::npos) {
    ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "the run did not start";
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  // Configured for a run of 10^7 steps: from here on it is mid-run.
  const auto killed = std::chrono::steady_clock::now();
  test::runCommand("pkill -9 -f 'afford-eye --lcm-url udpm://239.255.76.67:" + std::to_string(port) + "'");
  while (!fs::exists(fs::path(said) / "rc") || slurp(fs::path(said) / "rc").empty()) {
    ASSERT_LT(std::chrono::steady_clock::now() - killed, std::chrono::seconds(10)) << "the run did not end";
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_NE(std::stoi(slurp(fs::path(said) / "rc")), 0);
  const std::string out = slurp(fs::path(said) / "out.txt");
  EXPECT_NE(out.find("process 'eye'"), std::string::npos) << out;
  EXPECT_NE(out.find("SIGKILL"), std::string::npos) << out;
  // No process of the run is left behind.
  // ([u] keeps pgrep from matching the shell that runs it.)
  EXPECT_NE(test::runCommand("pgrep -f '[u]dpm://239.255.76.67:" + std::to_string(port) + "'").exit_code, 0);
}

}  // namespace
}  // namespace afford

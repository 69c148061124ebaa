// The researcher's workflow (issue 13), through the `afford` command in one
// process (memq): trained agents reused by content, --keep-checkpoints, an
// experiment file outside the config folder (--config), `afford clean`,
// sweeps (--set key=v1,v2, --sweep FILE), shards (--shard i/n) and
// `afford merge`.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <sstream>
#include <nlohmann/json.hpp>

#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Output {
  int status = -1;
  std::string text;  // stdout and stderr
};

Output run(const std::string& args) {
  Output o;
  FILE* p = popen((test::afford(args) + " 2>&1").c_str(), "r");
  std::array<char, 4096> buf{};
  for (std::size_t n; (n = fread(buf.data(), 1, buf.size(), p)) > 0;) o.text.append(buf.data(), n);
  const int st = pclose(p);
  o.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return o;
}

using test::readJson;

const std::string kSmall = " --transport memq --system IMP --reps 2 --steps 300 --extrinsic-reps 1 --scenarios scenario1 --quiet";

std::vector<std::string> checksums(const json& summary) {
  std::vector<std::string> out;
  for (const auto& r : summary["systems"]["IMP"]["runs"]) out.push_back(r["weights_checksum"]);
  return out;
}

// An experiment that extends base and changes only the planner shares base's
// agents: they are taken from the store, not trained again, and everything
// that follows equals a run that trains them afresh.
TEST(Workflow, AnExperimentSharingTheIntrinsicRunsReusesTheStoredAgents) {
  const std::string dir = test::tempDir("reuse");
  const std::string logs = " --log-root " + dir + "/logs";
  Output a = run("experiment base" + kSmall + " --out " + dir + "/base --run-prefix a" + logs);
  ASSERT_EQ(a.status, 0) << a.text;
  // The authors' errors are those after 6000 steps (config/reference.yaml): not beside runs of 300.
  EXPECT_FALSE(readJson(dir + "/base/summary.json")["systems"]["IMP"].contains("reference_affordance_mae"));
  EXPECT_EQ(a.text.find("authors' code"), std::string::npos) << a.text;
  Output b = run("experiment attention" + kSmall + " --out " + dir + "/att --run-prefix b" + logs);
  ASSERT_EQ(b.status, 0) << b.text;
  EXPECT_NE(b.text.find("2 of 2 intrinsic run(s) reuse a stored agent"), std::string::npos) << b.text;
  // ... and the line says that nothing of them runs, and how to run them anew (a fault drill on a group).
  EXPECT_NE(b.text.find("they do not run, nothing of theirs goes on the bus; to run them anew (a fault drill, a check "
                        "that a run reproduces), give --no-reuse-agents"),
            std::string::npos)
      << b.text;
  Output c = run("experiment attention" + kSmall + " --out " + dir + "/att-fresh --run-prefix c --no-reuse-agents" + logs);
  ASSERT_EQ(c.status, 0) << c.text;
  EXPECT_EQ(c.text.find("reuse a stored agent"), std::string::npos) << c.text;

  const json base = readJson(dir + "/base/summary.json"), att = readJson(dir + "/att/summary.json"),
             fresh = readJson(dir + "/att-fresh/summary.json");
  EXPECT_EQ(checksums(att), checksums(base));
  EXPECT_EQ(checksums(att), checksums(fresh));
  EXPECT_EQ(att["systems"]["IMP"]["runs"][0]["reused_from"], "a-base-IMP-s1");
  EXPECT_TRUE(fresh["systems"]["IMP"]["runs"][0]["reused_from"].is_null());
  EXPECT_FALSE(fs::exists(dir + "/logs/b-attention-IMP-s1"));  // not run, so no folder of its own
  // ... and nothing of the stored run's running is said of it: not its log folder, its speed or its memory.
  const json& taken = att["systems"]["IMP"]["runs"][0];
  EXPECT_TRUE(taken["log_dir"].is_null()) << taken.dump();
  EXPECT_EQ(taken["steps_per_second"], 0.0);
  EXPECT_EQ(taken["wall_seconds"], 0.0);
  EXPECT_EQ(taken["log_bytes"], 0);
  EXPECT_TRUE(taken["peak_rss_kb"].empty());
  // The tests from the reused agents: the same outcomes as from agents trained afresh.
  EXPECT_EQ(att["systems"]["IMP"]["extrinsic"]["conditions"], fresh["systems"]["IMP"]["extrinsic"]["conditions"]);
  // Another seed is another agent: trained, not taken.
  Output d = run("experiment attention" + kSmall + " --seed 5 --out " + dir + "/att-seed5 --run-prefix d" + logs);
  ASSERT_EQ(d.status, 0) << d.text;
  EXPECT_EQ(d.text.find("reuse a stored agent"), std::string::npos) << d.text;
}

// A queue (afford experiment A B, or --plan FILE): the experiments run side
// by side on the same slots; an agent two of them share is trained once, by
// the first in the queue's order, and taken by the other once stored; each
// folder holds what the experiment alone would write.
TEST(Workflow, AQueueTrainsASharedAgentOnceAndEachExperimentGetsWhatItWouldAlone) {
  const std::string dir = test::tempDir("queue");
  const std::string small = " --system IMP --reps 2 --steps 300 --extrinsic-reps 1 --scenarios scenario1";
  {
    std::ofstream plan(dir + "/plan.yaml");
    plan << "# attention and base share their agents; late1 trains its own\n"
         << "- attention" << small << "\n- base" << small << "\n- late1" << small << " --seed 3 --out " << dir
         << "/late1-here\n";
  }
  Output q = run("experiment --plan " + dir + "/plan.yaml --transport memq --jobs 2 --quiet --run-prefix q --out " +
                 dir + "/queue --log-root " + dir + "/logs");
  ASSERT_EQ(q.status, 0) << q.text;
  EXPECT_NE(q.text.find("base: 2 intrinsic run(s) take the agent another experiment of the queue trains"),
            std::string::npos) << q.text;
  EXPECT_TRUE(fs::exists(dir + "/logs/q-attention-IMP-s1"));  // attention came first: it trained them
  EXPECT_FALSE(fs::exists(dir + "/logs/q-base-IMP-s1"));
  for (const std::string exp : {"attention", "base"}) {
    Output alone = run("experiment " + exp + small + " --transport memq --quiet --no-reuse-agents --run-prefix a --out " +
                       dir + "/alone-" + exp + " --log-root " + dir + "/logs-alone");
    ASSERT_EQ(alone.status, 0) << alone.text;
    const json a = readJson(dir + "/alone-" + exp + "/summary.json"), b = readJson(dir + "/queue/" + exp + "/summary.json");
    EXPECT_EQ(checksums(a), checksums(b)) << exp;
    EXPECT_EQ(a["systems"]["IMP"]["extrinsic"]["conditions"], b["systems"]["IMP"]["extrinsic"]["conditions"]) << exp;
  }
  EXPECT_EQ(readJson(dir + "/queue/base/summary.json")["systems"]["IMP"]["runs"][0]["reused_from"], "q-attention-IMP-s1");
  EXPECT_TRUE(fs::exists(dir + "/late1-here/summary.json"));  // an entry's own --out
  // Resumed when every experiment finished: nothing to run.
  Output r = run("experiment --plan " + dir + "/plan.yaml --transport memq --resume --quiet --run-prefix q --out " +
                 dir + "/queue --log-root " + dir + "/logs");
  EXPECT_EQ(r.status, 0) << r.text;
  EXPECT_NE(r.text.find("every experiment of the queue finished already"), std::string::npos) << r.text;
}

// Three agents on two slots: the first two train side by side, the third
// takes the first free slot, and the other slot runs the tests of an agent
// already trained meanwhile, before the third is over.
TEST(Workflow, AnAgentsTestsStartAsSoonAsItIsTrained) {
  const std::string dir = test::tempDir("ahead");
  Output o = run("experiment base --transport memq --system IMP --reps 3 --steps 2500 --extrinsic-reps 1 --quiet "
                 "--no-reuse-agents --keep-logs none --jobs 2 --run-prefix h --out " + dir + "/out --log-root " + dir + "/logs");
  ASSERT_EQ(o.status, 0) << o.text;
  std::vector<fs::file_time_type> agents, tests;
  for (const auto& f : fs::directory_iterator(dir + "/out/runs"))
    (f.path().stem().string().find("-scenario") == std::string::npos ? agents : tests).push_back(fs::last_write_time(f));
  ASSERT_EQ(agents.size(), 3u);
  ASSERT_EQ(tests.size(), 15u);
  EXPECT_LT(*std::min_element(tests.begin(), tests.end()), *std::max_element(agents.begin(), agents.end()));
  // And the summary is the one of tests run after every agent (the extrinsic phase finds them kept).
  EXPECT_EQ(readJson(dir + "/out/summary.json")["extrinsic_tests"], 15);
  // One count of the tests for every agent's: [1/15] to [15/15], each once (it restarted at [1/5] per agent).
  std::set<int> counted;
  std::istringstream lines(o.text);
  const std::regex test_line(R"(\[(\d+)/(\d+)\] h-\S+-scenario)");
  std::smatch m;
  for (std::string line; std::getline(lines, line);)
    if (std::regex_search(line, m, test_line)) {
      EXPECT_EQ(m[2], "15") << line;
      EXPECT_TRUE(counted.insert(std::stoi(m[1])).second) << "counted twice: " << line;
    }
  EXPECT_EQ(counted.size(), 15u) << o.text;
  EXPECT_EQ(*counted.rbegin(), 15) << o.text;
}

TEST(Workflow, AQueueRefusesEntriesItCannotRunNamingThem) {
  const std::string dir = test::tempDir("queue-bad");
  const auto refused = [&](const std::string& plan_text, const std::string& says) {
    std::ofstream(dir + "/plan.yaml") << plan_text;
    Output o = run("experiment --plan " + dir + "/plan.yaml --transport memq --out " + dir + "/out --log-root " + dir);
    EXPECT_EQ(o.status, 2) << plan_text << o.text;
    EXPECT_NE(o.text.find(says), std::string::npos) << plan_text << o.text;
    EXPECT_FALSE(fs::exists(dir + "/out")) << plan_text;  // nothing written or started
  };
  refused("- base --jobs 4\n", "plan.yaml entry 1: --jobs is the queue's option");
  refused("- base --steps 100\n- late1 --bogus\n", "plan.yaml entry 2");
  refused("- base --out x\n- late1 --out x\n", "would both write to x");
  refused("- base\n- no-such-experiment\n", "entry 2 (no-such-experiment)");
  refused("base: 1\n", "a YAML list of experiments");
  refused("- [base, 1]\n", "entry 1 is not an argument line");
  Output fifo = run("experiment --plan " + dir + " --transport memq --out " + dir + "/out");  // a folder, not a file
  EXPECT_EQ(fifo.status, 2) << fifo.text;
  EXPECT_NE(fifo.text.find("--plan " + dir + ": not a regular file"), std::string::npos) << fifo.text;
  Output o = run("experiment base late1 --shard 0/2 --run-prefix s --out " + dir + "/out");
  EXPECT_EQ(o.status, 2) << o.text;
  EXPECT_NE(o.text.find("--shard is for one experiment, not a queue"), std::string::npos) << o.text;
}

TEST(Workflow, KeepCheckpointsFirstRemovesTheOthersOnceTheTestsAreDone) {
  const std::string dir = test::tempDir("keep-ckpt");
  Output a = run("experiment base" + kSmall + " --keep-logs none --keep-checkpoints first --no-reuse-agents --out " + dir +
                 "/out --run-prefix k --log-root " + dir + "/logs");
  ASSERT_EQ(a.status, 0) << a.text;
  const json s = readJson(dir + "/out/summary.json");
  const json& runs = s["systems"]["IMP"]["runs"];
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_TRUE(fs::exists(runs[0]["checkpoint"].get<std::string>()));
  EXPECT_TRUE(runs[1]["checkpoint"].is_null());
  EXPECT_FALSE(fs::exists(dir + "/logs/k-base-IMP-s2"));  // nothing else was in it
  EXPECT_EQ(s["systems"]["IMP"]["extrinsic"]["success_rate"].size(), 1u);  // the tests ran before
  Output bad = run("experiment base" + kSmall + " --keep-checkpoints some --out " + dir + "/bad --log-root " + dir + "/logs");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.text.find("--keep-checkpoints must be all, first or none"), std::string::npos) << bad.text;
}

TEST(Workflow, AnExperimentFileOutsideTheConfigFolderExtendsAShippedOne) {
  const std::string dir = test::tempDir("config-file");
  std::ofstream(dir + "/slow-leak.yaml") << "extends: base\ndescription: base with a slower leak\n"
                                            "systems:\n  IMP:\n    motivation: {leak: 0.05}\n";
  Output a = run("experiment --config " + dir + "/slow-leak.yaml" + kSmall + " --keep-logs none --out " + dir +
                 "/out --run-prefix f --log-root " + dir + "/logs");
  ASSERT_EQ(a.status, 0) << a.text;
  const json s = readJson(dir + "/out/summary.json");
  EXPECT_EQ(s["experiment"], "slow-leak");
  EXPECT_EQ(s["experiment_file"], dir + "/slow-leak.yaml");
  EXPECT_FALSE(s["systems"]["IMP"].contains("reference_affordance_mae"));  // the paper's numbers are base's, not its
  EXPECT_EQ(s["systems"]["IMP"]["runs"][0]["run_id"], "f-slow-leak-IMP-s1");
  Output shown = run("config " + dir + "/slow-leak.yaml");
  ASSERT_EQ(shown.status, 0) << shown.text;
  EXPECT_NE(shown.text.find("leak: 0.05"), std::string::npos) << shown.text;
  EXPECT_NE(shown.text.find("experiment: slow-leak"), std::string::npos) << shown.text;

  Output missing = run("experiment --config " + dir + "/nothing.yaml" + kSmall + " --out " + dir + "/m");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.text.find("experiment file " + dir + "/nothing.yaml does not exist"), std::string::npos) << missing.text;
  Output both = run("experiment base --config " + dir + "/slow-leak.yaml" + kSmall + " --out " + dir + "/m");
  EXPECT_EQ(both.status, 2);
  EXPECT_NE(both.text.find("NAME or --config FILE, not both"), std::string::npos) << both.text;
  std::ofstream(dir + "/broken.yaml") << "extends: no-such-experiment\n";
  Output broken = run("experiment --config " + dir + "/broken.yaml" + kSmall + " --out " + dir + "/m");
  EXPECT_EQ(broken.status, 2);
  EXPECT_NE(broken.text.find("unknown experiment \"no-such-experiment\""), std::string::npos) << broken.text;
}

TEST(Workflow, CleanListsByExperimentAndRemovesOnlyWithDelete) {
  const std::string dir = test::tempDir("clean");
  const std::string logs = " --log-root " + dir + "/logs";
  ASSERT_EQ(run("experiment base" + kSmall + " --out " + dir + "/a --run-prefix a" + logs).status, 0);
  ASSERT_EQ(run("experiment multi-step" + kSmall + " --out " + dir + "/b --run-prefix b" + logs).status, 0);
  Output dry = run("clean --experiment multi-step" + logs);
  ASSERT_EQ(dry.status, 0) << dry.text;
  EXPECT_NE(dry.text.find("would remove"), std::string::npos) << dry.text;
  EXPECT_EQ(dry.text.find("a-base"), std::string::npos) << dry.text;
  EXPECT_NE(dry.text.find("b-multi-step-IMP-s1-c0"), std::string::npos) << dry.text;
  EXPECT_TRUE(fs::exists(dir + "/logs/b-multi-step-IMP-s1-c0-scenario1-e0"));
  Output del = run("clean --experiment multi-step --delete" + logs);
  ASSERT_EQ(del.status, 0) << del.text;
  for (const auto& d : fs::directory_iterator(dir + "/logs"))
    EXPECT_EQ(d.path().filename().string().find("b-multi-step"), std::string::npos) << d.path();
  EXPECT_TRUE(fs::exists(dir + "/logs/a-base-IMP-s1"));
  Output none = run("clean" + logs);
  EXPECT_EQ(none.status, 2);
  EXPECT_NE(none.text.find("choose folders with"), std::string::npos) << none.text;
  Output everything = run("clean --all --delete" + logs);
  ASSERT_EQ(everything.status, 0) << everything.text;
  EXPECT_TRUE(fs::is_empty(dir + "/logs"));
}

// Without a terminal, progress comes as plain lines: each job slot's run and
// step out of its total (from the processes' heartbeats), and the time left.
TEST(Workflow, ProgressLinesNameEachSlotsRunStepAndTheTimeLeft) {
  const std::string dir = test::tempDir("progress");
  Output a = run("experiment base --transport memq --system IMP --reps 3 --steps 3000 -j 2 --quiet --keep-logs none "
                 "--no-reuse-agents --progress lines --progress-every 0 --run-prefix g --out " + dir + "/out --log-root " +
                 dir + "/logs");
  ASSERT_EQ(a.status, 0) << a.text;
  bool mid_run = false, left = false;
  std::istringstream lines(a.text);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("progress: intrinsic runs: ", 0) != 0) continue;
    const auto at = line.find("g-base-IMP-s1 step ");
    if (at != std::string::npos) {
      const long step = std::stol(line.substr(at + 19));
      EXPECT_NE(line.find("/3000 ("), std::string::npos) << line;
      mid_run |= step > 0 && step < 3000;
    }
    left |= line.find(" of 3 done") != std::string::npos && line.find(" left (") != std::string::npos;
    EXPECT_NE(line.find("slot 1: "), std::string::npos) << line;  // a part per job slot
  }
  EXPECT_TRUE(mid_run) << a.text;
  EXPECT_TRUE(left) << a.text;
  Output quiet = run("experiment base --transport memq --system IMP --reps 1 --steps 300 --quiet --keep-logs none "
                     "--no-reuse-agents --progress none --progress-every 0 --run-prefix h --out " + dir +
                     "/q --log-root " + dir + "/logs");
  ASSERT_EQ(quiet.status, 0) << quiet.text;
  EXPECT_EQ(quiet.text.find("progress:"), std::string::npos) << quiet.text;
}

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Each condition of a 2 x 2 sweep is the experiment with those values set:
// the same weights as a run given the condition's values alone, summarised in
// a folder of its own and in one summary.json and CSV files that name it.
TEST(Workflow, ASweepRunsTheCrossProductAndEachConditionIsItsSettings) {
  const std::string dir = test::tempDir("sweep");
  const std::string logs = " --log-root " + dir + "/logs";
  Output a = run("experiment base" + kSmall + " --keep-logs none --set motivation.leak=0.1,0.3"
                 " --set predictors.affordance.learning_rate=0.05,0.1 -j 2 --out " + dir + "/sweep --run-prefix s" + logs);
  ASSERT_EQ(a.status, 0) << a.text;
  const json s = readJson(dir + "/sweep/summary.json");
  ASSERT_EQ(s["sweep"]["conditions"].size(), 4u);
  const std::string c = "motivation.leak=0.3,predictors.affordance.learning_rate=0.05";
  EXPECT_EQ(s["sweep"]["conditions"][2]["name"], c);
  ASSERT_TRUE(s["conditions"].contains(c));
  for (const auto& r : s["conditions"][c]["systems"]["IMP"]["runs"]) EXPECT_EQ(r["sweep_condition"], c);
  EXPECT_EQ(s["conditions"][c]["systems"]["IMP"]["runs"][0]["run_id"], "s-c2-base-IMP-s1");
  // Its own folder is an experiment folder like any other.
  const json own = readJson(dir + "/sweep/conditions/" + c + "/summary.json");
  EXPECT_EQ(own["systems"]["IMP"]["runs"][1]["weights_checksum"],
            s["conditions"][c]["systems"]["IMP"]["runs"][1]["weights_checksum"]);
  // The condition alone gives the same agents and tests.
  Output alone = run("experiment base" + kSmall + " --keep-logs none --no-reuse-agents --set motivation.leak=0.3"
                     " --set predictors.affordance.learning_rate=0.05 --out " + dir + "/alone --run-prefix x" + logs);
  ASSERT_EQ(alone.status, 0) << alone.text;
  const json one = readJson(dir + "/alone/summary.json");
  EXPECT_EQ(checksums(one), checksums(s["conditions"][c]));
  EXPECT_EQ(one["systems"]["IMP"]["extrinsic"], s["conditions"][c]["systems"]["IMP"]["extrinsic"]);
  // The conditions differ (the sweep is not four copies of one run).
  EXPECT_NE(checksums(s["conditions"][s["sweep"]["conditions"][0]["name"].get<std::string>()]), checksums(one));
  // One CSV of every condition, its first column naming it.
  const std::string csv = readText(dir + "/sweep/curves_IMP.csv");
  EXPECT_EQ(csv.rfind("sweep_condition,system,", 0), 0u) << csv.substr(0, 80);
  for (const auto& cond : s["sweep"]["conditions"])
    EXPECT_NE(csv.find("\"" + cond["name"].get<std::string>() + "\",IMP,"), std::string::npos) << cond["name"];

  // Figures: each condition's own, and the conditions side by side.
  Output plotted = run("plot " + dir + "/sweep");
  ASSERT_EQ(plotted.status, 0) << plotted.text;
  EXPECT_TRUE(fs::exists(dir + "/sweep/fig_sweep_mae.png"));
  EXPECT_TRUE(fs::exists(dir + "/sweep/fig_sweep_success.png"));
  EXPECT_TRUE(fs::exists(dir + "/sweep/conditions/" + c + "/fig_affordances.png"));
  EXPECT_NE(readText(dir + "/sweep/fig_sweep_mae.csv").find("IMP,3,2,"), std::string::npos);  // condition 3, 2 runs

  // The report takes the sweep's folder: each condition as an experiment folder, and the comparison.
  Output report = run("report " + dir + "/sweep --out " + dir + "/report/r.md");
  ASSERT_EQ(report.status, 0) << report.text;
  const std::string md = readText(dir + "/report/r.md");
  EXPECT_NE(md.find("`--set motivation.leak=0.3`, `--set predictors.affordance.learning_rate=0.05`"), std::string::npos) << md;
  EXPECT_NE(md.find("sweep condition `" + c + "`"), std::string::npos) << md;
  EXPECT_TRUE(fs::exists(dir + "/report/r/base-sweep-sweep/fig_sweep_mae.png"));
  EXPECT_TRUE(fs::exists(dir + "/report/r/base-motivation.leak-0.3-predictors.affordance.learning_rate-0.05/fig_affordances.png"));

  // A sweep file asks for the same conditions.
  std::ofstream(dir + "/sweep.yaml") << "motivation.leak: [0.1, 0.3]\npredictors.affordance.learning_rate: [0.05, 0.1]\n";
  Output f = run("experiment base" + kSmall + " --keep-logs none --sweep " + dir + "/sweep.yaml --out " + dir +
                 "/file --run-prefix f" + logs);
  ASSERT_EQ(f.status, 0) << f.text;
  EXPECT_NE(f.text.find("8 of 8 intrinsic run(s) reuse"), std::string::npos) << f.text;  // the same 8 agents
  const json sf = readJson(dir + "/file/summary.json");
  EXPECT_EQ(sf["sweep"]["conditions"], s["sweep"]["conditions"]);
  EXPECT_EQ(checksums(sf["conditions"][c]), checksums(one));

  // Bad sweeps are errors naming the key.
  Output twice = run("experiment base" + kSmall + " --set motivation.leak=0.1,0.2 --sweep " + dir +
                     "/sweep.yaml --out " + dir + "/bad");
  EXPECT_EQ(twice.status, 2);
  EXPECT_NE(twice.text.find("config key 'motivation.leak' is swept twice"), std::string::npos) << twice.text;
  Output unknown = run("experiment base" + kSmall + " --set eye.colour=1,2 --out " + dir + "/bad");
  EXPECT_EQ(unknown.status, 2);
  EXPECT_NE(unknown.text.find("sweep condition 'eye.colour=1': config key 'eye.colour': unknown key"), std::string::npos)
      << unknown.text;
  EXPECT_FALSE(fs::exists(dir + "/bad"));
}

// The forward-model design tests the checkpoints saved after 4000 actions. With
// --keep-checkpoints none, shards keep theirs until the merge has planned the
// tests from them; the merge then removes them, as one machine does.
TEST(Workflow, ShardsOfTheForwardModelDesignMergeWithTheirTestsWhateverCheckpointsAreKept) {
  const std::string dir = test::tempDir("shards-fm");
  // The design tests the weights saved after its action count (4000 in the paper; 500 here, to be short).
  std::ofstream(dir + "/forward-models-500.yaml") << "extends: forward-models\ndescription: forward-models after "
                                                     "500 actions\nextrinsic:\n  after_actions: 500\n";
  const std::string plan = "experiment --config " + dir + "/forward-models-500.yaml --transport memq --system FIX "
                           "--reps 2 --steps 700 --extrinsic-reps 1 --scenarios scenario1 --quiet --keep-logs none "
                           "--keep-checkpoints none --no-reuse-agents --run-prefix f";
  Output whole = run(plan + " --out " + dir + "/whole --log-root " + dir + "/logs-whole");
  ASSERT_EQ(whole.status, 0) << whole.text;
  std::string shards;
  for (int i = 0; i < 2; ++i) {
    const std::string out = dir + "/shard" + std::to_string(i);
    Output s = run(plan + " --shard " + std::to_string(i) + "/2 --out " + out + " --log-root " + dir + "/logs");
    ASSERT_EQ(s.status, 0) << s.text;
    shards += " " + out;
  }
  Output m = run("merge" + shards + " --quiet --out " + dir + "/merged");
  ASSERT_EQ(m.status, 0) << m.text;
  const json a = readJson(dir + "/whole/summary.json"), b = readJson(dir + "/merged/summary.json");
  EXPECT_GT(b["extrinsic_tests"].get<int>(), 0);
  EXPECT_FALSE(b.contains("untested_agents") && !b["untested_agents"].empty()) << b["untested_agents"];
  EXPECT_EQ(test::withoutTimingsAndPaths(a), test::withoutTimingsAndPaths(b));
  for (const auto& entry : b["systems"]["FIX"]["runs"]) EXPECT_TRUE(entry["checkpoint"].is_null()) << entry["run_id"];
}

// Four shards, then `afford merge`: the summary and CSV files of one machine
// running it all, apart from timings and paths; a sweep shards too.
TEST(Workflow, ShardsMergeIntoTheSummaryOfTheWholeExperiment) {
  const std::string dir = test::tempDir("shards");
  const std::string plan = "experiment base --transport memq --system all --reps 2 --steps 300 --extrinsic-reps 1 "
                           "--scenarios scenario1 scenario2 --quiet --keep-logs none --run-prefix p";
  Output whole = run(plan + " --out " + dir + "/whole --log-root " + dir + "/logs-whole");
  ASSERT_EQ(whole.status, 0) << whole.text;
  std::string shards;
  for (int i = 0; i < 4; ++i) {
    const std::string out = dir + "/shard" + std::to_string(i);
    Output s = run(plan + " --shard " + std::to_string(i) + "/4 --out " + out + " --log-root " + dir + "/logs");
    ASSERT_EQ(s.status, 0) << s.text;
    EXPECT_NE(s.text.find("shard " + std::to_string(i) + "/4: " + (i < 2 ? "2" : "1") + " of the 6"), std::string::npos)
        << s.text;
    shards += " " + out;
  }
  Output missing = run("merge" + shards.substr(0, shards.rfind(' ')) + " --out " + dir + "/merged");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.text.find("shard(s) 3/4 missing"), std::string::npos) << missing.text;
  EXPECT_FALSE(fs::exists(dir + "/merged"));
  Output m = run("merge" + shards + " --quiet --out " + dir + "/merged");
  ASSERT_EQ(m.status, 0) << m.text;
  const json a = readJson(dir + "/whole/summary.json"), b = readJson(dir + "/merged/summary.json");
  EXPECT_EQ(b["merged_from"].size(), 4u);
  EXPECT_EQ(test::withoutTimingsAndPaths(a), test::withoutTimingsAndPaths(b));
  for (const char* f : {"curves_FIX.csv", "affordance_IGN.csv", "curves_IMP.csv"})
    EXPECT_EQ(readText(dir + "/whole/" + f), readText(dir + "/merged/" + f)) << f;
  // A merge cut short (its state left running, no summary yet) resumes as a merge: it gathers the shards again.
  json state = readJson(dir + "/merged/experiment.json");
  state["state"] = "running";
  std::ofstream(dir + "/merged/experiment.json") << state.dump(2);
  fs::remove(dir + "/merged/summary.json");
  Output again = run("experiment --resume --quiet --out " + dir + "/merged");
  ASSERT_EQ(again.status, 0) << again.text;
  EXPECT_NE(again.text.find("merging 4 shard(s)"), std::string::npos) << again.text;
  EXPECT_EQ(test::withoutTimingsAndPaths(readJson(dir + "/merged/summary.json")), test::withoutTimingsAndPaths(a));

  // Shards of another experiment do not merge with these.
  Output other = run("experiment base --transport memq --system IMP --reps 2 --steps 300 --quiet --keep-logs none "
                     "--run-prefix q --shard 3/4 --out " + dir + "/other --log-root " + dir + "/logs");
  ASSERT_EQ(other.status, 0) << other.text;
  Output mixed = run("merge" + shards.substr(0, shards.rfind(' ')) + " " + dir + "/other --out " + dir + "/mixed");
  EXPECT_EQ(mixed.status, 2);
  EXPECT_NE(mixed.text.find("are shards of different experiments"), std::string::npos) << mixed.text;
  Output no_prefix = run("experiment base --transport memq --shard 0/2 --out " + dir + "/np");
  EXPECT_EQ(no_prefix.status, 2);
  EXPECT_NE(no_prefix.text.find("--shard needs --run-prefix"), std::string::npos) << no_prefix.text;
  Output bad = run("experiment base --transport memq --shard 2/2 --run-prefix z --out " + dir + "/np");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.text.find("--shard must be i/n with 0 <= i < n"), std::string::npos) << bad.text;

  // A sweep in two shards.
  const std::string sweep = "experiment base" + kSmall + " --keep-logs none --no-reuse-agents --set motivation.leak=0.1,0.3 "
                            "--log-root " + dir + "/sweep-logs";
  ASSERT_EQ(run(sweep + " --run-prefix w --out " + dir + "/sweep").status, 0);
  ASSERT_EQ(run(sweep + " --run-prefix v --shard 0/2 --out " + dir + "/sw0").status, 0);
  ASSERT_EQ(run(sweep + " --run-prefix v --shard 1/2 --out " + dir + "/sw1").status, 0);
  Output sm = run("merge " + dir + "/sw0 " + dir + "/sw1 --quiet --out " + dir + "/sw");
  ASSERT_EQ(sm.status, 0) << sm.text;
  const json sw = readJson(dir + "/sw/summary.json"), full = readJson(dir + "/sweep/summary.json");
  for (const auto& cond : full["sweep"]["conditions"]) {
    const std::string name = cond["name"];
    EXPECT_EQ(checksums(sw["conditions"][name]), checksums(full["conditions"][name])) << name;
    EXPECT_EQ(sw["conditions"][name]["systems"]["IMP"]["extrinsic"], full["conditions"][name]["systems"]["IMP"]["extrinsic"]);
  }
}

}  // namespace
}  // namespace afford

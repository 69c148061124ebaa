// What a newcomer trips on (issue 38), through the `afford` command: an
// experiment folder is never mixed with another experiment, `afford clean`
// leaves alone what it cannot attribute or what is in use, a test that failed
// to run is no result, and errors say what was wrong and where.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "experiment/state.hpp"
#include "processes/logger/logger.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using Output = test::CommandResult;
const auto run = test::runAfford;
using test::readJson;
using test::slurp;

void spit(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

const std::string kTiny = " --transport memq --system IMP --reps 1 --quiet --progress none";

// A second experiment into a finished one's folder is refused, naming the ways
// on; with --replace the folder holds the second only (no CSV, figure or test
// of the first); a folder afford did not make is never written into.
TEST(Newcomer, AFinishedExperimentsFolderIsRefusedOrReplacedWholeNeverMixed) {
  const std::string dir = test::tempDir("replace");
  const std::string out = dir + "/out", logs = " --log-root " + dir + "/logs";
  ASSERT_EQ(run("experiment base" + kTiny + " --steps 200 --extrinsic-reps 1 --scenarios scenario1 --out " + out + logs)
                .exit_code,
            0);
  ASSERT_EQ(run("plot " + out).exit_code, 0);
  ASSERT_TRUE(fs::exists(out + "/extrinsic_IMP.csv") && fs::exists(out + "/fig_completion.png"));
  const std::string before = slurp(out + "/summary.json");

  Output again = run("experiment base" + kTiny + " --steps 100 --out " + out + logs);
  EXPECT_EQ(again.exit_code, 2) << again.output;
  EXPECT_NE(again.output.find("--out " + out + " holds a finished experiment (base"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("choose another --out"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("--replace"), std::string::npos) << again.output;
  EXPECT_EQ(slurp(out + "/summary.json"), before);  // nothing written

  Output replaced = run("experiment base" + kTiny + " --steps 100 --replace --out " + out + logs);
  ASSERT_EQ(replaced.exit_code, 0) << replaced.output;
  EXPECT_EQ(readJson(out + "/summary.json")["steps"], 100);
  for (const char* gone : {"extrinsic_IMP.csv", "fig_completion.png", "fig_completion.csv", "fig_affordances.gp"})
    EXPECT_FALSE(fs::exists(fs::path(out) / gone)) << gone;

  spit(out + "/notes.txt", "my notes");
  Output foreign = run("experiment base" + kTiny + " --steps 100 --replace --out " + out + logs);
  EXPECT_EQ(foreign.exit_code, 2) << foreign.output;
  EXPECT_NE(foreign.output.find("files afford did not write (notes.txt)"), std::string::npos) << foreign.output;
  EXPECT_EQ(slurp(out + "/notes.txt"), "my notes");
  EXPECT_EQ(readJson(out + "/summary.json")["steps"], 100);

  spit(dir + "/mine/draft.md", "a draft");
  Output other = run("experiment base" + kTiny + " --steps 100 --out " + dir + "/mine" + logs);
  EXPECT_EQ(other.exit_code, 2) << other.output;
  EXPECT_NE(other.output.find("is not empty and holds no afford experiment (it holds draft.md)"), std::string::npos)
      << other.output;
  EXPECT_FALSE(fs::exists(dir + "/mine/summary.json"));
  EXPECT_NE(run("experiment base --resume --replace --out " + out).output.find("--replace"), std::string::npos);
}

// Without --run-prefix, two experiments of one log root in the same second
// take different prefixes: the second gets "-2".
TEST(Newcomer, DefaultRunIdsOfOneSecondDoNotCollide) {
  const std::string dir = test::tempDir("prefixes");
  std::vector<std::string> ids;
  for (int k = 0; k < 3; ++k) {
    Output o = run("experiment base" + kTiny + " --steps 5 --keep-logs none --no-reuse-agents --out " + dir + "/o" +
                   std::to_string(k) + " --log-root " + dir + "/logs");
    ASSERT_EQ(o.exit_code, 0) << o.output;
    ids.push_back(readJson(dir + "/o" + std::to_string(k) + "/summary.json")["systems"]["IMP"]["runs"][0]["run_id"]);
  }
  EXPECT_NE(ids[0], ids[1]);
  EXPECT_NE(ids[1], ids[2]);
  EXPECT_NE(ids[0], ids[2]);
  // Each is reserved in the log root, so that another runner passes it over.
  for (const auto& e : fs::directory_iterator(dir + "/logs/.prefixes"))
    EXPECT_TRUE(std::regex_match(e.path().filename().string(), std::regex(R"(\d{8}-\d{6}(-\d+)?)")))
        << e.path();
}

// --steps 0 and --reps 0 are refused, not read as "the experiment's"; a negative seed is named as the
// option, and a name nearly right with the one meant.
TEST(Newcomer, CountsOutOfRangeAndNamesNearlyRightAreRefusedNamingWhatWasMeant) {
  const std::string dir = test::tempDir("zero");
  Output steps = run("experiment base --transport memq --steps 0 --out " + dir + "/a");
  EXPECT_EQ(steps.exit_code, 2) << steps.output;
  EXPECT_NE(steps.output.find("--steps must be at least 1, not 0"), std::string::npos) << steps.output;
  Output reps = run("experiment base --transport memq --reps 0 --out " + dir + "/b");
  EXPECT_EQ(reps.exit_code, 2) << reps.output;
  EXPECT_NE(reps.output.find("--reps must be at least 1, not 0"), std::string::npos) << reps.output;
  Output seed = run("experiment base --transport memq --seed -1 --out " + dir + "/c");
  EXPECT_NE(seed.output.find("--seed must be 0 or more, not -1"), std::string::npos) << seed.output;
  // A zero where zero means nothing is refused, not read as "the default".
  Output stall = run("experiment base --transport memq --stall-seconds 0 --out " + dir + "/f");
  EXPECT_EQ(stall.exit_code, 2) << stall.output;
  EXPECT_NE(stall.output.find("--stall-seconds must be more than 0, not 0"), std::string::npos) << stall.output;
  Output jobs = run("experiment base --transport memq --jobs 0 --out " + dir + "/g");
  EXPECT_NE(jobs.output.find("--jobs must be at least 1, not 0"), std::string::npos) << jobs.output;
  EXPECT_FALSE(fs::exists(dir + "/a/summary.json") || fs::exists(dir + "/b/summary.json") ||
               fs::exists(dir + "/f/summary.json"));
  // A name nearly right is named with the one meant.
  Output name = run("experiment basee --out " + dir + "/d");
  EXPECT_NE(name.output.find("unknown experiment \"basee\"; did you mean \"base\"?"), std::string::npos) << name.output;
  Output system = run("experiment base --system imp --out " + dir + "/e");
  EXPECT_NE(system.output.find("did you mean IMP? (systems are written in capitals)"), std::string::npos) << system.output;
}

// A typo in one's own experiment file names the file, its block and the key
// meant; in a system's block, that block; on --set, the setting.
TEST(Newcomer, AConfigTypoNamesTheFileTheBlockAndTheClosestKey) {
  const std::string dir = test::tempDir("typo");
  spit(dir + "/mine.yaml", "extends: base\nmotivation:\n  leek: 0.3\n");
  Output file = run("experiment --config " + dir + "/mine.yaml --transport memq --out " + dir + "/o");
  EXPECT_EQ(file.exit_code, 2) << file.output;
  EXPECT_NE(file.output.find("experiment file " + dir + "/mine.yaml, block motivation: config key 'motivation.leek': "
                           "unknown key; did you mean 'motivation.leak'?"),
            std::string::npos)
      << file.output;
  spit(dir + "/sys.yaml", "extends: base\nsystems:\n  IMP:\n    motivation:\n      leak: fast\n");
  Output block = run("experiment --config " + dir + "/sys.yaml --system IMP --transport memq --out " + dir + "/o");
  EXPECT_NE(block.output.find("experiment file " + dir + "/sys.yaml, block systems.IMP: config key 'motivation.leak': "
                            "expected a number"),
            std::string::npos)
      << block.output;
  Output set = run("experiment base --set motivaton.leak=0.2 --transport memq --out " + dir + "/o");
  EXPECT_NE(set.output.find("no map 'motivaton'; did you mean 'motivation'?"), std::string::npos) << set.output;
  Output value = run("experiment base --set motivation.leak=fast --transport memq --out " + dir + "/o");
  EXPECT_NE(value.output.find("--set motivation.leak=fast: config key 'motivation.leak': expected a number"),
            std::string::npos)
      << value.output;
}

// A test that failed to run is no result: its scenario shows "-", not 0.00,
// and the console says how many failed and why (here the predictors cannot
// read the stored agent's checkpoint, damaged since it was stored).
TEST(Newcomer, TestsThatFailedToRunAreNotCountedAsUnsolved) {
  const std::string dir = test::tempDir("failed-tests");
  const std::string logs = " --log-root " + dir + "/logs";
  ASSERT_EQ(run("experiment base" + kTiny + " --steps 100 --out " + dir + "/a" + logs).exit_code, 0);
  for (const auto& agent : fs::directory_iterator(dir + "/logs/agents"))
    fs::resize_file(agent.path() / "predictors.ckpt", 100);
  Output o = run("experiment base --transport memq --system IMP --reps 1 --steps 100 --progress none "
                 "--extrinsic-reps 1 --scenarios scenario1 scenario2 --out " + dir + "/b" + logs);
  EXPECT_EQ(o.exit_code, 1) << o.output;
  const json ex = readJson(dir + "/b/summary.json")["systems"]["IMP"]["extrinsic"];
  EXPECT_EQ(ex["table_metric"].size(), 0u) << ex.dump();
  EXPECT_EQ(ex["success_rate"].size(), 0u) << ex.dump();
  ASSERT_EQ(ex["failed_tests"].size(), 2u) << ex.dump();
  EXPECT_NE(ex["failed_tests"][0]["error"].get<std::string>().find("predictors.ckpt"), std::string::npos) << ex.dump();
  EXPECT_EQ(o.output.find("0.00 (1.0)"), std::string::npos) << o.output;
  EXPECT_TRUE(std::regex_search(o.output, std::regex(R"(IMP +- \(1\.0\) +- \(1\.0\))"))) << o.output;
  EXPECT_NE(o.output.find("IMP: 2 test(s) failed to run and are not counted"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("2 extrinsic test(s) failed to run"), std::string::npos) << o.output;
  EXPECT_EQ(slurp(dir + "/b/extrinsic_IMP.csv").find("scenario1"), std::string::npos);  // no row of a non-result
}

// Run folders are offered only when attributable and not in use: a group's
// folder (its key, its live pids), a run whose experiment is running (it holds
// its folder's lock) and a folder nothing attributes are left alone, and said.
TEST(Newcomer, CleanLeavesAloneGroupsRunningExperimentsAndWhatItCannotAttribute) {
  const std::string dir = test::tempDir("clean-alone");
  const fs::path logs = fs::path(dir) / "logs";
  spit(logs / "demo/lcm-url", "udpm://239.255.76.67:7700?ttl=0\n");
  spit(logs / "demo/bus.key", "key");
  // The group's eye: this test process, with its start time as procs.sh records it.
  std::ifstream stat("/proc/self/stat");
  std::string line;
  std::getline(stat, line);
  std::istringstream fields(line.substr(line.rfind(')') + 2));
  std::vector<std::string> f{std::istream_iterator<std::string>(fields), {}};
  spit(logs / "demo/eye.pid", std::to_string(getpid()) + "\n");
  spit(logs / "demo/eye.started", f.at(19) + "\n");
  spit(logs / "mystery/data.bin", "?");
  spit(logs / "r-running/run.json", json{{"run_id", "r-running"}, {"experiment", "base"}, {"out_dir", dir + "/busy"}}.dump());
  spit(logs / "r-done/run.json", json{{"run_id", "r-done"}, {"experiment", "base"}, {"out_dir", dir + "/done"}}.dump());
  spit(fs::path(dir) / "busy/.lock", "");
  const int lock = open((dir + "/busy/.lock").c_str(), O_RDWR);
  ASSERT_EQ(flock(lock, LOCK_EX | LOCK_NB), 0);  // as the runner of busy/ holds it

  Output dry = run("clean --all --delete --log-root " + logs.string());
  ASSERT_EQ(dry.exit_code, 0) << dry.output;
  EXPECT_NE(dry.output.find("removed") , std::string::npos) << dry.output;
  EXPECT_FALSE(fs::exists(logs / "r-done"));
  for (const char* kept : {"demo", "mystery", "r-running"}) EXPECT_TRUE(fs::exists(logs / kept)) << kept;
  EXPECT_NE(dry.output.find("/demo: a scripts/procs.sh group (running: eye)"), std::string::npos) << dry.output;
  EXPECT_NE(dry.output.find("/mystery: nothing in it says whose it is"), std::string::npos) << dry.output;
  EXPECT_NE(dry.output.find("/r-running: its experiment is running (in " + dir + "/busy)"), std::string::npos)
      << dry.output;
  close(lock);  // the experiment is over: its run may go
  Output after = run("clean --all --delete --log-root " + logs.string());
  EXPECT_FALSE(fs::exists(logs / "r-running")) << after.output;
  EXPECT_TRUE(fs::exists(logs / "demo") && fs::exists(logs / "mystery")) << after.output;
}

// What is in use says so, and is never offered: a log a logger is writing (it holds the folder, whatever its
// experiment), the runs of an experiment that stopped before it finished (the resume command said), a study's
// trials (by their runs and by the trial folders); a log without a run.json that is incomplete. Once the log is
// closed and the experiment finished, the run goes.
TEST(Newcomer, CleanLeavesAloneALogBeingWrittenAResumableExperimentsRunsAndAStudysTrials) {
  const std::string dir = test::tempDir("clean-in-use");
  const fs::path logs = fs::path(dir) / "logs";
  const auto state = [&](const fs::path& out, const std::string& how) {
    ExperimentState s;
    s.experiment = "base";
    s.cwd = "/home/me/afford";
    s.state = how;
    s.resume = "afford experiment --resume --out " + out.string();
    if (how == "interrupted") s.interruptions.push_back({"SIGINT", "intrinsic", {}});
    fs::create_directories(out);
    writeState(out, s);
  };
  const auto runOf = [&](const std::string& id, const fs::path& out) {
    spit(logs / id / "run.json", json{{"run_id", id}, {"experiment", "base"}, {"out_dir", out.string()}}.dump());
    spit(logs / id / "predictors.ckpt", "weights");
  };
  state(fs::path(dir) / "done", "finished");
  state(fs::path(dir) / "cut", "interrupted");
  state(fs::path(dir) / "gone", "running");  // its runner was killed: it holds no lock
  state(fs::path(dir) / "study/trials/0002", "finished");
  spit(fs::path(dir) / "study/study.json", "{}");
  runOf("r-closing", fs::path(dir) / "done");
  runOf("r-cut", fs::path(dir) / "cut");
  runOf("r-gone", fs::path(dir) / "gone");
  runOf("r-trial", fs::path(dir) / "study/trials/0002");
  spit(logs / "r-by-hand/manifest.json", json{{"run_id", "r-by-hand"}, {"experiment", "base"}}.dump());
  auto log = std::make_unique<RunLog>((logs / "r-closing").string(), json{{"run_id", "r-closing"}, {"experiment", "base"}});

  Output listed = run("clean --all --log-root " + logs.string());
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_EQ(listed.output.find("would remove  "), std::string::npos) << listed.output;
  const auto said = [&](const std::string& folder, const std::string& why) {
    EXPECT_NE(listed.output.find("/" + folder + ": " + why), std::string::npos) << folder << "\n" << listed.output;
  };
  said("r-closing", "a log is being written in it (a logger holds it");
  said("r-cut", "its experiment (in " + dir + "/cut) stopped before it finished (interrupted by SIGINT): `afford "
                "experiment --resume --out " + dir + "/cut` (in /home/me/afford) continues it");
  said("r-gone", "its experiment (in " + dir + "/gone) stopped before it finished (its runner ended before it "
                 "finished): `afford experiment --resume --out " + dir + "/gone`");
  said("r-trial", "a trial of the study in " + dir + "/study (" + dir + "/study/trials/0002): afford tune keeps");
  said("r-by-hand", "its log is incomplete and no run.json names its experiment");
  Output trials = run("clean --all --log-root " + dir + "/study/trials");
  EXPECT_NE(trials.output.find("/0002: a trial of the study in " + dir + "/study: afford tune keeps its trials"),
            std::string::npos) << trials.output;

  log->close();  // the log closed, its experiment finished: the run may go
  Output after = run("clean --all --delete --log-root " + logs.string());
  EXPECT_FALSE(fs::exists(logs / "r-closing")) << after.output;
  for (const char* kept : {"r-cut", "r-gone", "r-trial", "r-by-hand"})
    EXPECT_TRUE(fs::exists(logs / kept)) << kept << "\n" << after.output;
}

// Names a person reads: the experiments' list in one column however long a
// name, the completion fit with its sign.
TEST(Newcomer, TheListAndTheFitReadAsWritten) {
  const std::string dir = test::tempDir("reading");
  Output list = run("experiments");
  ASSERT_EQ(list.exit_code, 0);
  std::istringstream lines(list.output);
  std::set<std::size_t> columns;  // where each description starts
  for (std::string l; std::getline(lines, l);) {
    const auto name_end = l.find(' ');
    columns.insert(l.find_first_not_of(' ', name_end));
  }
  EXPECT_EQ(columns.size(), 1u) << list.output;
  Output o = run("experiment base --transport memq --system IMP --reps 1 --progress none --steps 100 --extrinsic-reps 1 "
                 "--scenarios scenario1 --out " + dir + "/out --log-root " + dir + "/logs");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("(paper, IMP: 1.364 x^2 - 0.808 x)"), std::string::npos) << o.output;
  EXPECT_EQ(o.output.find(" x^2 -0."), std::string::npos) << o.output;
}

// afford plot: with one run per system the final predictions are bars (a
// box of one value is a flat line); the curves tell apart the three objects
// of a colour by their lines' dashes, all along them.
TEST(Newcomer, PlotsOfOneRunShowBarsAndCurvesOfOneColourDifferAllAlong) {
  const std::string dir = test::tempDir("plots");
  ASSERT_EQ(run("experiment base" + kTiny + " --steps 600 --out " + dir + "/out --log-root " + dir + "/logs").exit_code, 0);
  Output p = run("plot " + dir + "/out");
  ASSERT_EQ(p.exit_code, 0) << p.output;
  const std::string boxes = slurp(dir + "/out/fig_affordances.gp");
  EXPECT_NE(boxes.find("$11 == 1 ? $4 : NaN):7 with boxes"), std::string::npos) << boxes;
  EXPECT_NE(boxes.find("a filled bar: the prediction of the one run"), std::string::npos) << boxes;
  std::istringstream csv(slurp(dir + "/out/fig_affordances.csv"));
  std::string header, row;
  std::getline(csv, header);
  EXPECT_EQ(header.substr(header.rfind(',') + 1), "n");
  while (std::getline(csv, row)) EXPECT_EQ(row.substr(row.rfind(',') + 1), "1") << row;
  const std::string curves = slurp(dir + "/out/fig_curves_IMP.gp");
  std::set<std::string> red_dashes;
  for (const char* object : {"red square", "red circle", "red rectangle"}) {
    std::smatch m;
    ASSERT_TRUE(std::regex_search(curves, m, std::regex(std::string("dt (\\S+) title '") + object + "'"))) << curves;
    red_dashes.insert(m[1]);
  }
  EXPECT_EQ(red_dashes.size(), 3u) << curves;
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

// A typo in every section of an experiment file, and in a file it extends, and on --set: the file (and the
// one that extends it) named, and the key meant, a swap of two letters counting as one.
TEST(Newcomer, ATypoInAnySectionNamesTheFileAndTheKeyMeant) {
  const std::string dir = test::tempDir("typos");
  const std::vector<std::pair<std::string, std::string>> typos = {
      {"extrinsic: {generate: {sead: 71}}", "'extrinsic.generate.sead': unknown key; did you mean 'extrinsic.generate.seed'?"},
      {"extrinsic: {tsets: 2}", "'extrinsic.tsets': unknown key; did you mean 'extrinsic.tests'?"},
      {"tables: {cuont: 3}", "'tables.cuont': unknown key; did you mean 'tables.count'?"},
      {"default_system: [IMP]", "unknown block 'default_system'; did you mean 'default_systems'?"},
      {"run: {stpes: 100}", "'run.stpes': unknown key; did you mean 'run.steps'?"},
      {"world:\n  objects:\n    - {name: red square, shape: square, colr: red, position: [0.2, 0.2], appears_at: 0, "
       "affordance: [1.0, 1.0, 0.0, 1.0]}",
       "'world.objects[0].colr': unknown key; did you mean 'world.objects[0].colour'?"},
      {"motivation: {laek: 0.3}", "'motivation.laek': unknown key; did you mean 'motivation.leak'?"},
  };
  int k = 0;
  for (const auto& [text, said] : typos) {
    const std::string file = dir + "/typo" + std::to_string(k) + ".yaml", child = dir + "/child" + std::to_string(k) + ".yaml";
    spit(file, "extends: base\n" + text + "\n");
    spit(child, "extends: typo" + std::to_string(k++) + ".yaml\n");
    for (const std::string& given : {file, child}) {
      Output r = run("experiment --config " + given + " --system IMP --transport memq --out " + dir + "/o");
      EXPECT_EQ(r.exit_code, 2) << text << ": " << r.output;
      EXPECT_NE(r.output.find("experiment file " + file), std::string::npos) << text << ": " << r.output;
      EXPECT_NE(r.output.find(said), std::string::npos) << text << ": " << r.output;
      if (given == child) {
        EXPECT_NE(r.output.find("(extended by " + child + ")"), std::string::npos) << text << ": " << r.output;
      }
    }
  }
  spit(dir + "/extend.yaml", "extend: base\n");
  Output extend = run("experiment --config " + dir + "/extend.yaml --transport memq --out " + dir + "/o");
  EXPECT_NE(extend.output.find("unknown block 'extend'; did you mean 'extends'?"), std::string::npos) << extend.output;
  Output set = run("experiment base --set run.stpes=3 --transport memq --out " + dir + "/o");
  EXPECT_NE(set.output.find("config key 'run.stpes': unknown key; did you mean 'run.steps'?"), std::string::npos)
      << set.output;
  EXPECT_FALSE(fs::exists(dir + "/o/summary.json"));
}

// The console's summary says "in brackets the paper's" where the paper's numbers are beside the results, and
// not where an experiment of one's own has none.
TEST(Newcomer, TheSummarySaysThePapersNumbersAreInBracketsOnlyWhereTheyAre) {
  const std::string dir = test::tempDir("brackets");
  spit(dir + "/mine.yaml", "extends: base\n");
  const auto summary = [&](const std::string& experiment, const std::string& name) {
    Output r = run("experiment " + experiment + " --system IMP --reps 1 --steps 50 --transport memq --keep-logs none "
                   "--extrinsic-reps 1 --scenarios scenario1 --out " + dir + "/" + name + " --log-root " + dir + "/" +
                   name + "-logs");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return r.output;
  };
  const std::string paper = summary("base", "paper"), mine = summary(dir + "/mine.yaml", "mine");
  EXPECT_NE(paper.find("solved; in brackets the paper's; then the raw share"), std::string::npos) << paper;
  EXPECT_NE(mine.find("solved; then the raw share"), std::string::npos) << mine;
  EXPECT_EQ(mine.find("in brackets the paper's"), std::string::npos) << mine;
}

// A zero given is a zero: --extrinsic-reps 0 runs no test even where the experiment file asks for tests; left
// out, the file's count holds (one test here).
TEST(Newcomer, ZeroExtrinsicRepsRunsNoTestsWhereTheExperimentAsksForThem) {
  namespace fs = std::filesystem;
  const std::string dir = test::tempDir("zero-reps");
  spit(dir + "/asks.yaml", "extends: base\nextrinsic: {scenarios: [scenario1], tests: 1}\n");
  const auto runs = [&](const std::string& name, const std::string& more) {
    const test::CommandResult r = test::runAfford(
        "experiment --config " + dir + "/asks.yaml --system IMP --reps 1 --steps 50 --transport memq --keep-logs none "
        "--quiet --run-prefix z --out " + dir + "/" + name + " --log-root " + dir + "/" + name + "-logs " + more);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    int n = 0;
    for (const auto& f : fs::directory_iterator(dir + "/" + name + "/runs")) n += f.path().extension() == ".json";
    return n;
  };
  EXPECT_EQ(runs("zero", "--extrinsic-reps 0"), 1) << "--extrinsic-reps 0 ran tests";
  EXPECT_EQ(test::readJson(dir + "/zero/experiment.json")["options"]["extrinsic_tests"], 0);
  EXPECT_EQ(runs("design", ""), 2) << "left out, the experiment's own test";
  EXPECT_FALSE(test::readJson(dir + "/design/experiment.json")["options"].contains("extrinsic_tests"));
}

// Without --out, each experiment writes a new folder out/NAME (a file's stem for an experiment file; out/NAME-2
// if that is taken): a second one never meets the first's folder, as it did when both wrote out/.
TEST(Newcomer, WithoutOutEachExperimentWritesAFolderOfItsOwnInOut) {
  namespace fs = std::filesystem;
  const std::string dir = test::tempDir("default-out");
  spit(dir + "/mine.yaml", "extends: base\n");
  const std::string common = " --system IMP --reps 1 --steps 30 --extrinsic-reps 0 --transport memq --quiet"
                             " --keep-logs none --log-root logs";
  for (const std::string what : {"base", "late1", "--config mine.yaml", "base"}) {
    const auto r = test::runCommand("cd " + dir + " && " + test::afford("experiment " + what + common));
    EXPECT_EQ(r.exit_code, 0) << what << ": " << r.output;
  }
  for (const char* name : {"base", "late1", "mine", "base-2"})
    EXPECT_TRUE(fs::exists(dir + "/out/" + name + "/summary.json")) << name;
  EXPECT_FALSE(fs::exists(dir + "/out/summary.json"));
}

// `afford watch` finding what runs reads files of the log root and the experiment's folder: a FIFO or a huge
// file in their place is refused with the file named, never waited on (a FIFO's open waits for a writer).
TEST(Newcomer, WatchFindingARunIsNotHeldByFilesInItsWay) {
  namespace fs = std::filesystem;
  const std::string dir = test::tempDir("watch-files");
  fs::create_directories(dir + "/out");
  const int lock = ::open((dir + "/out/.lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);  // "it runs"
  ASSERT_GE(lock, 0);
  ASSERT_EQ(::flock(lock, LOCK_EX), 0);
  ASSERT_EQ(::mkfifo((dir + "/out/bus.json").c_str(), 0600), 0);
  const auto out = test::runCommand("timeout 20 " + test::afford("watch --out " + dir + "/out"));
  EXPECT_NE(out.exit_code, 124) << "held by a FIFO: " << out.output;
  EXPECT_NE(out.output.find("bus.json does not read"), std::string::npos) << out.output;
  ::close(lock);

  fs::create_directories(dir + "/logs/g");
  ASSERT_EQ(::mkfifo((dir + "/logs/g/lcm-url").c_str(), 0600), 0);
  const auto group = test::runCommand("timeout 20 " + test::afford("watch --group g --log-root " + dir + "/logs"));
  EXPECT_NE(group.exit_code, 124) << "held by a FIFO: " << group.output;
  EXPECT_NE(group.output.find("no scripts/procs.sh group 'g'"), std::string::npos) << group.output;
  fs::remove(dir + "/logs/g/lcm-url");
  spit(dir + "/logs/g/lcm-url", "udpm://239.255.76.67:7700?ttl=0\n");
  ASSERT_EQ(::mkfifo((dir + "/logs/g/eye.pid").c_str(), 0600), 0);
  spit(dir + "/logs/g/eye.started", "12345\n");
  const auto pids = test::runCommand("timeout 20 " + test::afford("watch --group g --log-root " + dir + "/logs"));
  EXPECT_NE(pids.exit_code, 124) << "held by a FIFO: " << pids.output;
  EXPECT_NE(pids.output.find("no process of the group runs"), std::string::npos) << pids.output;

  // A log folder whose manifest.json is a FIFO: afford explain of the log root goes on past it.
  fs::create_directories(dir + "/logs/r-base-IMP-s1-scenario1-e0");
  ASSERT_EQ(::mkfifo((dir + "/logs/r-base-IMP-s1-scenario1-e0/manifest.json").c_str(), 0600), 0);
  spit(dir + "/logs/r-base-IMP-s1-scenario1-e0/log.00.lcm", "");
  const auto explain = test::runCommand("timeout 20 " + test::afford("explain " + dir + "/logs"));
  EXPECT_NE(explain.exit_code, 124) << "held by a FIFO: " << explain.output;

  // A --token-file that is a FIFO is refused naming the option.
  ASSERT_EQ(::mkfifo((dir + "/token").c_str(), 0600), 0);
  const auto token = test::runCommand("timeout 20 " + test::afford("watch --lcm-url 'udpm://239.255.76.67:7700?ttl=0' "
                                                                   "--port 0 --token-file " + dir + "/token"));
  EXPECT_NE(token.exit_code, 124) << "held by a FIFO: " << token.output;
  EXPECT_NE(token.output.find("--token-file"), std::string::npos) << token.output;
}

}  // namespace
}  // namespace afford

// Releases (CHANGELOG.md): every program says the version it is, and what it writes says the version that
// wrote it; a folder written before versions were kept there (0.1.0) reads as before.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>

#include "afford/version.hpp"
#include "experiment/stored/state_file.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {
namespace fs = std::filesystem;

TEST(Versions, EveryProgramSaysTheVersionItIs) {
  const std::string version = affordVersion();
  const test::CommandResult front = test::runAfford("--version");
  EXPECT_EQ(front.exit_code, 0) << front.output;
  EXPECT_EQ(front.output, "afford " + version + "\n");
  for (const std::string process : {"environment", "eye", "predictors", "motivation", "planner", "logger", "viewer"}) {
    const test::CommandResult r =
        test::runCommand(std::string(AFFORD_BIN_DIR) + "/afford-" + process + " --version");
    EXPECT_EQ(r.exit_code, 0) << process << ": " << r.output;
    EXPECT_EQ(r.output, "afford-" + process + " " + version + "\n");
  }
}

// One version: CMakeLists.txt's project(), python/pyproject.toml's, and what the build says it is.
TEST(Versions, TheBuildThePythonPackageAndTheProjectSayOneVersion) {
  const std::string cmake = test::slurp(std::string(AFFORD_SOURCE_DIR) + "/CMakeLists.txt");
  const std::string pyproject = test::slurp(std::string(AFFORD_SOURCE_DIR) + "/python/pyproject.toml");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(cmake, m, std::regex(R"re(project\(afford VERSION ([0-9]+\.[0-9]+\.[0-9]+))re")));
  const std::string version = m[1];
  ASSERT_TRUE(std::regex_search(pyproject, m, std::regex(R"re(\nversion = "([^"]+)")re")));
  EXPECT_EQ(m[1], version) << "python/pyproject.toml";
  EXPECT_EQ(std::string(affordVersion()).rfind(version + "+", 0), 0u) << affordVersion();
  const std::string changelog = test::slurp(std::string(AFFORD_SOURCE_DIR) + "/CHANGELOG.md");
  EXPECT_NE(changelog.find("\n## " + version + " - "), std::string::npos)
      << "CHANGELOG.md has no section for " << version << " (or it is still Unreleased)";
}

// A one-run FIX experiment of 50 steps and no test, run into DIR/out with its logs in DIR/logs.
void smallExperiment(const std::string& dir, const std::string& prefix) {
  const test::CommandResult r =
      test::runAfford("experiment base --system FIX --reps 1 --steps 50 --extrinsic-reps 0 --transport memq --quiet "
                      "--keep-logs none --run-prefix " + prefix + " --out " + dir + "/out --log-root " + dir + "/logs");
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

TEST(Versions, AnExperimentFolderSaysTheVersionThatWroteIt) {
  const std::string dir = test::tempDir("versions");
  smallExperiment(dir, "v");
  if (HasFatalFailure()) return;
  EXPECT_EQ(test::readJson(dir + "/out/experiment.json")["afford_version"], affordVersion());
  EXPECT_EQ(test::readJson(dir + "/out/summary.json")["afford_version"], affordVersion());
  EXPECT_EQ(readState(dir + "/out").afford_version, std::optional<std::string>(affordVersion()));
  EXPECT_EQ(test::readJson(dir + "/out/runs/v-base-FIX-s1.json")["afford_version"], affordVersion());
  EXPECT_EQ(test::readJson(dir + "/logs/v-base-FIX-s1/run.json")["afford_version"], affordVersion());
  // The agent it trained, kept for reuse; its checkpoint says the release too (test_predictors.cpp).
  int agents = 0;
  for (const auto& agent : fs::directory_iterator(dir + "/logs/agents")) {
    EXPECT_EQ(test::readJson(agent.path() / "outcome.json")["afford_version"], affordVersion());
    ++agents;
  }
  EXPECT_EQ(agents, 1);
}

TEST(Versions, AnExperimentStateOf010WithoutAVersionReadsAsBefore) {
  const std::string dir = test::tempDir("versions-010");
  smallExperiment(dir, "w");
  if (HasFatalFailure()) return;
  // As 0.1.0 wrote it: the same keys, without afford_version.
  nlohmann::json state = test::readJson(dir + "/out/experiment.json");
  state.erase("afford_version");
  std::ofstream(dir + "/out/experiment.json") << state.dump(2);
  const fs::path outcome = dir + "/out/runs/w-base-FIX-s1.json";
  nlohmann::json kept = test::readJson(outcome);
  kept.erase("afford_version");
  std::ofstream(outcome) << kept.dump();
  const ExperimentState read = readState(dir + "/out");
  EXPECT_FALSE(read.afford_version.has_value());
  EXPECT_EQ(read.state, "finished");
  const test::CommandResult report = test::runAfford("report " + dir + "/out --out " + dir + "/report.md");
  EXPECT_EQ(report.exit_code, 0) << report.output;
}

// An experiment run in FOLDER as `--out exp --log-root LOG_ROOT ...`, then marked as an interruption leaves it.
void startedAndInterrupted(const std::string& folder, const std::string& log_root, const std::string& more) {
  fs::create_directories(folder);
  const test::CommandResult r = test::runCommand(
      "cd " + folder + " && " +
      test::afford("experiment base --system FIX --reps 1 --steps 50 --transport memq --quiet --keep-logs none "
                   "--run-prefix m --out exp --log-root " + log_root + " " + more));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json state = test::readJson(folder + "/exp/experiment.json");
  state["state"] = "interrupted";
  std::ofstream(folder + "/exp/experiment.json") << state.dump(2);
}

// A folder kept elsewhere (another machine, a repository's test data) with its logs inside it resumes there:
// an experiment started in DIR/a as `--out exp --log-root exp/logs`, cut in its extrinsic phase (its test not
// finished), and its folder moved to DIR/b/<name>.
void cutAndMove(const std::string& dir, const std::string& name) {
  startedAndInterrupted(dir + "/a", "exp/logs", "--extrinsic-reps 1 --scenarios scenario1");
  fs::create_directories(dir + "/b");
  fs::remove(dir + "/a/exp/runs/m-base-FIX-s1-scenario1-e0.json");
  fs::rename(dir + "/a/exp", dir + "/b/" + name);
}

void expectFinishedThere(const std::string& dir, const std::string& folder, const test::CommandResult& resumed) {
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_EQ(test::readJson(folder + "/experiment.json")["state"], "finished");
  EXPECT_TRUE(fs::exists(folder + "/runs/m-base-FIX-s1-scenario1-e0.json")) << resumed.output;
  // The run folder is the experiment's where it is now; nothing was written where it was.
  EXPECT_EQ(test::readJson(folder + "/logs/m-base-FIX-s1/run.json")["out_dir"], fs::absolute(folder).string());
  EXPECT_FALSE(fs::exists(dir + "/a/exp")) << "the resumed experiment wrote where the folder was";
}

TEST(Versions, AnInterruptedExperimentMovedWithItsLogsResumesWhereItIsNow) {
  const std::string dir = test::tempDir("versions-moved");
  cutAndMove(dir, "exp");
  const test::CommandResult resumed =
      test::runCommand("cd " + dir + "/b && " + test::afford("experiment --resume --out exp --quiet"));
  expectFinishedThere(dir, dir + "/b/exp", resumed);
}

TEST(Versions, AMovedExperimentResumesUnderAnotherNameGivenFromElsewhere) {
  // Its paths are spelt otherwise now (absolute, another name): its agent's checkpoint, named by the kept
  // outcome and by the stored plan as exp/logs/..., is found where the folder is.
  const std::string dir = test::tempDir("versions-renamed");
  cutAndMove(dir, "renamed");
  fs::create_directories(dir + "/c");
  const test::CommandResult resumed = test::runCommand(
      "cd " + dir + "/c && " + test::afford("experiment --resume --out " + dir + "/b/renamed --quiet"));
  expectFinishedThere(dir, dir + "/b/renamed", resumed);
  const nlohmann::json state = test::readJson(dir + "/b/renamed/experiment.json");
  ASSERT_TRUE(state.contains("moved")) << state.dump(2);
  EXPECT_EQ(state["moved"][0]["from"], "exp/logs");
  EXPECT_EQ(state["moved"][0]["to"], dir + "/b/renamed/logs");
  EXPECT_TRUE(fs::is_empty(dir + "/c")) << "the resumed experiment wrote in the folder it was resumed from";
}

TEST(Versions, AMovedExperimentWhoseLogRootStayedBehindIsRefusedNamingIt) {
  // Its log root was relative to a folder that is gone, and outside the experiment's own: nothing to follow.
  const std::string dir = test::tempDir("versions-behind");
  startedAndInterrupted(dir + "/a", "logs", "--extrinsic-reps 0");
  fs::rename(dir + "/a/exp", dir + "/exp");
  fs::remove_all(dir + "/a");
  const test::CommandResult resumed =
      test::runCommand("cd " + dir + " && " + test::afford("experiment --resume --out exp --quiet"));
  EXPECT_EQ(resumed.exit_code, 2) << resumed.output;
  EXPECT_NE(resumed.output.find("--log-root 'logs' is relative to that folder"), std::string::npos) << resumed.output;
  EXPECT_NE(resumed.output.find(dir + "/a, which is gone"), std::string::npos) << resumed.output;
}

TEST(Versions, AnExperimentOf010Or020ReadsItsExtrinsicRepsOfZeroAsNotGiven) {
  // 0.1.0 and 0.2.0 kept `extrinsic_reps`, 0 for "the experiment's count"; from 0.3.0 `extrinsic_tests`,
  // absent when not given and 0 for none.
  const std::string dir = test::tempDir("versions-reps");
  smallExperiment(dir, "r");
  if (HasFatalFailure()) return;
  EXPECT_EQ(readState(dir + "/out").options.plan.extrinsic_reps, std::optional<int>(0));
  nlohmann::json state = test::readJson(dir + "/out/experiment.json");
  state["options"].erase("extrinsic_tests");
  for (const auto& [kept, read] : {std::pair{0, std::optional<int>()}, {3, std::optional<int>(3)}}) {
    state["options"]["extrinsic_reps"] = kept;
    std::ofstream(dir + "/out/experiment.json") << state.dump(2);
    EXPECT_EQ(readState(dir + "/out").options.plan.extrinsic_reps, read) << "kept as " << kept;
  }
}

}  // namespace
}  // namespace afford

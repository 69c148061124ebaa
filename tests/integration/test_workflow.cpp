// The researcher's workflow (issue 13), through the `afford` command in one
// process (memq): trained agents reused by content, --keep-checkpoints, an
// experiment file outside the config folder (--config), `afford clean`.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support.hpp"

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

json readJson(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

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
  Output b = run("experiment attention" + kSmall + " --out " + dir + "/att --run-prefix b" + logs);
  ASSERT_EQ(b.status, 0) << b.text;
  EXPECT_NE(b.text.find("2 of 2 intrinsic run(s) reuse a stored agent"), std::string::npos) << b.text;
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
  // The tests from the reused agents: the same outcomes as from agents trained afresh.
  EXPECT_EQ(att["systems"]["IMP"]["extrinsic"]["conditions"], fresh["systems"]["IMP"]["extrinsic"]["conditions"]);
  // Another seed is another agent: trained, not taken.
  Output d = run("experiment attention" + kSmall + " --seed 5 --out " + dir + "/att-seed5 --run-prefix d" + logs);
  ASSERT_EQ(d.status, 0) << d.text;
  EXPECT_EQ(d.text.find("reuse a stored agent"), std::string::npos) << d.text;
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

}  // namespace
}  // namespace afford

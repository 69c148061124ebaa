// An experiment on a one-node Slurm cluster (issue 13): munge, slurmctld and
// slurmd on localhost (tests/cluster/slurm-local.sh, every file in the test's
// folder), the experiment submitted by scripts/slurm-submit.sh as a job array
// of 4 shards over udpm (each job in a network namespace of its own, two at a
// time on this node's 2 CPUs, all on the same UDP ports) and a merge job
// after them; the merged summary must equal the same experiment run here. Then a study
// (afford tune) by two array tasks sharing its journal file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kScript = std::string(AFFORD_SOURCE_DIR) + "/tests/cluster/slurm-local.sh";

// Started in the constructor, stopped (every daemon and job gone) in the destructor, whatever the test did.
class LocalCluster {
 public:
  explicit LocalCluster(const std::string& dir) : dir_(dir) {
    const test::CommandResult r = test::runCommand(kScript + " start " + dir_);
    started_ = r.exit_code == 0;
    output_ = r.output;
    std::ifstream env(dir_ + "/env.sh");
    for (std::string line; started_ && std::getline(env, line);)
      if (line.rfind("export SLURM_CONF=", 0) == 0) conf_ = line.substr(18);
  }
  ~LocalCluster() { test::runCommand(kScript + " stop " + dir_); }
  bool started() const { return started_ && !conf_.empty(); }
  const std::string& output() const { return output_; }
  // `command` with the cluster's configuration.
  std::string with(const std::string& command) const { return "SLURM_CONF=" + conf_ + " " + command; }

 private:
  std::string dir_, conf_, output_;
  bool started_ = false;
};

json readJson(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

TEST(Cluster, SlurmArrayOfShardsMergesIntoTheLocalRunsSummary) {
  const std::string dir = test::tempDir("slurm");
  const std::string experiment =
      "base --system IMP --reps 4 --steps 400 --extrinsic-reps 1 --scenarios scenario1 scenario2 --keep-logs none --quiet";
  const test::CommandResult local = test::runCommand(
      test::afford("experiment " + experiment + " --run-prefix p --out " + dir + "/local --log-root " + dir + "/local-logs"));
  ASSERT_EQ(local.exit_code, 0) << local.output;

  LocalCluster cluster(dir + "/cluster");
  ASSERT_TRUE(cluster.started()) << cluster.output();
  const test::CommandResult submitted = test::runCommand(cluster.with(
      std::string(AFFORD_SOURCE_DIR) + "/scripts/slurm-submit.sh --shards 4 --afford " + AFFORD_BIN_DIR +
      "/afford --run-prefix p --out " + dir + "/out --log-root " + dir + "/logs -- " + experiment));
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(submitted.output, m, std::regex("merge job ([0-9]+)"))) << submitted.output;
  const std::string merge_job = m[1];
  // The merge job ends after the shards. The controller grants a job that depends on it once it has ended, and
  // tells salloc, whose `true` then ends that job too; bounded in case the cluster hangs.
  const test::CommandResult after =
      test::runCommand(cluster.with("timeout 300 salloc --quiet --dependency=afterany:" + merge_job + " true"));
  ASSERT_EQ(after.exit_code, 0) << "waiting for the merge job " << merge_job << ": " << after.output;
  const test::CommandResult merge_state = test::runCommand(cluster.with("scontrol show job " + merge_job));
  EXPECT_NE(merge_state.output.find("JobState=COMPLETED"), std::string::npos) << merge_state.output;
  std::string merge_out;
  {
    std::ifstream in(dir + "/out/slurm/merge.out");
    merge_out.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_TRUE(fs::exists(dir + "/out/summary.json")) << merge_out;
  for (int i = 0; i < 4; ++i) {
    const json shard = readJson(dir + "/out/shard-" + std::to_string(i) + "/summary.json");
    EXPECT_EQ(shard["shard"]["index"], i);
    EXPECT_EQ(shard["systems"]["IMP"]["runs"].size(), 1u);  // one of the 4 runs each
    EXPECT_EQ(shard["network"], "private network namespace (loopback only)");
  }
  const json merged = readJson(dir + "/out/summary.json"), whole = readJson(dir + "/local/summary.json");
  EXPECT_EQ(merged["merged_from"].size(), 4u);
  EXPECT_EQ(merged["systems"]["IMP"]["runs"].size(), 4u);
  EXPECT_EQ(test::withoutTimingsAndPaths(merged), test::withoutTimingsAndPaths(whole));

  // A study (afford tune) on the same cluster: two array tasks, each a worker of the one study in --out, and a
  // report job after them. Together they run the study's trials, each once.
  const test::CommandResult tuned = test::runCommand(cluster.with(
      std::string(AFFORD_SOURCE_DIR) + "/scripts/slurm-submit.sh --tune --shards 2 --afford " + AFFORD_BIN_DIR +
      "/afford --out " + dir + "/study -- base --param motivation.leak=log:0.01:0.9 --trials 4 --steps 3000 "
      "--keep-logs none"));
  ASSERT_EQ(tuned.exit_code, 0) << tuned.output;
  ASSERT_TRUE(std::regex_search(tuned.output, m, std::regex("report job ([0-9]+)"))) << tuned.output;
  const std::string report_job = m[1];
  const test::CommandResult reported =
      test::runCommand(cluster.with("timeout 300 salloc --quiet --dependency=afterany:" + report_job + " true"));
  ASSERT_EQ(reported.exit_code, 0) << "waiting for the report job " << report_job << ": " << reported.output;
  std::ifstream trials_csv(dir + "/study/trials.csv");
  std::string header, line;
  ASSERT_TRUE(std::getline(trials_csv, header)) << "no trials.csv in " << dir << "/study";
  std::set<std::string> numbers, workers;
  int finished = 0;
  while (std::getline(trials_csv, line)) {
    numbers.insert(line.substr(0, line.find(',')));
    finished += line.find(",COMPLETE,") != std::string::npos || line.find(",PRUNED,") != std::string::npos;
    if (std::regex_search(line, m, std::regex(",([^,]+:[0-9]+),"))) workers.insert(m[1]);
  }
  EXPECT_EQ(finished, 4) << header;
  EXPECT_EQ(numbers, (std::set<std::string>{"0", "1", "2", "3"}));
  EXPECT_EQ(workers.size(), 2u) << "both workers took trials";
  EXPECT_TRUE(fs::exists(dir + "/study/report.md"));
}

}  // namespace
}  // namespace afford

// `afford experiment` stopped by SIGINT or SIGTERM, then `--resume`d: what
// finished is summarised, the cut run's log is closed incomplete, no process
// is left, and the resumed experiment ends with the summary of an
// uninterrupted one. Real processes over udpm in the runner's private network
// namespace (needs root or user namespaces), and memq. Ports 7960-7979.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

json readJson(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

// Polls `done` every 5 ms until it holds or `seconds` pass.
bool waitFor(const std::function<bool()>& done, double seconds) {
  const auto until = Clock::now() + std::chrono::duration<double>(seconds);
  while (!done()) {
    if (Clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// `afford ARGS` in the background, as a shell runs a job: a process group of
// its own (a terminal's Ctrl-C goes to that group), output into a file.
class Job {
 public:
  Job(const std::string& args, const std::string& output) : output_(output) {
    pid_ = fork();
    if (pid_ == 0) {
      setpgid(0, 0);
      const std::string command = "exec " + test::afford(args) + " >" + output + " 2>&1";
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    setpgid(pid_, pid_);
  }
  ~Job() {
    if (pid_ > 0 && status_ < 0) {  // a test that failed early: leave nothing running
      kill(-pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  // What the terminal does on Ctrl-C: the signal to every process of the job's group.
  void signalGroup(int sig) const { kill(-pid_, sig); }
  // What `kill PID` does.
  void signal(int sig) const { kill(pid_, sig); }
  bool running() {
    if (status_ >= 0) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) != pid_) return true;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return false;
  }
  // The exit status, or -1 if it has not ended within `seconds`.
  int wait(double seconds) {
    waitFor([this] { return !running(); }, seconds);
    return status_;
  }
  std::string output() const { return slurp(output_); }

 private:
  pid_t pid_ = -1;
  int status_ = -1;
  std::string output_;
};

// summary.json without what the clock, the host or the paths decide (as
// tests/restart/test_restart.sh compares them).
json results(const fs::path& dir) {
  std::function<json(const json&)> strip = [&](const json& j) {
    if (j.is_object()) {
      json o = json::object();
      for (const auto& [k, v] : j.items())
        if (k != "wall_seconds" && k != "run_seconds" && k != "steps_per_second" && k != "log_bytes" &&
            k != "log_bytes_per_step" && k != "log_dir" && k != "checkpoint" && k != "transport" && k != "network" &&
            k != "afford_version" && k != "peak_rss_kb")
          o[k] = strip(v);
      return o;
    }
    if (j.is_array()) {
      json a = json::array();
      for (const auto& v : j) a.push_back(strip(v));
      return a;
    }
    return j;
  };
  return strip(readJson(dir / "summary.json"));
}

// A CSV file, without its wall_seconds column (extrinsic_<S>.csv: each test's wall time).
std::string csvWithoutWallTimes(const fs::path& p) {
  std::istringstream in(slurp(p));
  std::string out;
  for (std::string line; std::getline(in, line);) {
    if (p.filename().string().rfind("extrinsic_", 0) == 0) line = line.substr(0, line.rfind(','));
    out += line + "\n";
  }
  return out;
}

void expectSameResults(const fs::path& resumed, const fs::path& uninterrupted) {
  EXPECT_EQ(results(resumed), results(uninterrupted)) << "summaries differ";
  int csvs = 0;
  for (const auto& f : fs::directory_iterator(uninterrupted)) {
    if (f.path().extension() != ".csv") continue;
    ++csvs;
    EXPECT_EQ(csvWithoutWallTimes(resumed / f.path().filename()), csvWithoutWallTimes(f.path()))
        << f.path().filename();
  }
  EXPECT_GE(csvs, 2);
}

// A cut run's folder: its manifest says incomplete, and so does replay.
void expectIncompleteLog(const fs::path& dir) {
  const json m = readJson(dir / "manifest.json");
  EXPECT_EQ(m["complete"], false);
  EXPECT_NE(m.value("incomplete", "").find("the run did not end"), std::string::npos) << m.dump();
  const auto replay = test::runCommand(test::afford("replay " + dir.string()));
  EXPECT_NE(replay.output.find("the log is incomplete"), std::string::npos) << replay.output;
}

TEST(Interrupt, CtrlCOverUdpmKeepsTheFinishedRunsAndResumeCompletesTheExperiment) {
  const fs::path dir = test::tempDir("interrupt-udpm");
  const std::string plan = "base --system IMP --reps 3 --steps 4000 --quiet --run-prefix int";
  Job job("experiment " + plan + " --base-port 7960 --out " + (dir / "out").string() + " --log-root " +
              (dir / "logs").string(),
          (dir / "first.txt").string());
  // Once the first run is kept and the second is well under way: its log holds
  // ~1400 of its 4000 steps (~3.5 KB each), so its processes have reported a step.
  ASSERT_TRUE(waitFor([&] { return fs::exists(dir / "out/runs/int-base-IMP-s1.json") || !job.running(); }, 60))
      << job.output();
  const fs::path second_log = dir / "logs/int-base-IMP-s2/log.00.lcm";
  ASSERT_TRUE(waitFor(
      [&] {
        std::error_code ec;
        const auto bytes = fs::file_size(second_log, ec);
        return (!ec && bytes > 5'000'000) || !job.running();
      },
      30))
      << job.output();
  ASSERT_TRUE(job.running()) << job.output();
  job.signalGroup(SIGINT);
  ASSERT_EQ(job.wait(30), 130) << job.output();

  const std::string said = job.output();
  EXPECT_NE(said.find("interrupted by SIGINT"), std::string::npos) << said;
  EXPECT_NE(said.find("kept: 1 of 3 intrinsic run(s) finished"), std::string::npos) << said;
  EXPECT_NE(said.find("experiment --resume --out " + (dir / "out").string()), std::string::npos) << said;
  // No process of the group is left.
  EXPECT_NE(test::runCommand("pgrep -f '[u]dpm://239.255.76.67:7960'").exit_code, 0);

  const json s = readJson(dir / "out/summary.json");
  ASSERT_EQ(s["systems"]["IMP"]["runs"].size(), 1u);
  EXPECT_EQ(s["systems"]["IMP"]["runs"][0]["run_id"], "int-base-IMP-s1");
  EXPECT_FALSE(s["systems"]["IMP"].contains("failed_runs"));
  const json& cut = s["interrupted"];
  EXPECT_EQ(cut["signal"], "SIGINT");
  EXPECT_EQ(cut["phase"], "intrinsic");
  ASSERT_EQ(cut["cut"].size(), 1u);
  EXPECT_EQ(cut["cut"][0]["run_id"], "int-base-IMP-s2");
  EXPECT_NE(cut["cut"][0]["where"].get<std::string>().find("interrupted at step"), std::string::npos);
  EXPECT_EQ(cut["not_started"], json::array({"int-base-IMP-s3"}));
  EXPECT_NE(slurp(dir / "out/curves_IMP.csv").find("int-base-IMP-s1"), std::string::npos);
  EXPECT_EQ(slurp(dir / "out/curves_IMP.csv").find("int-base-IMP-s2"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "out/affordance_IMP.csv"));
  expectIncompleteLog(dir / "logs/int-base-IMP-s2");

  const auto resumed = test::runCommand(test::afford("experiment --resume --out " + (dir / "out").string()));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("1 of 3 run(s) finished already"), std::string::npos) << resumed.output;
  expectIncompleteLog(dir / "logs/int-base-IMP-s2.cut-1");  // moved aside, kept as it was
  EXPECT_FALSE(readJson(dir / "out/summary.json").contains("interrupted"));

  const auto whole = test::runCommand(test::afford("experiment " + plan + " --transport memq --keep-logs none --out " +
                                                   (dir / "whole").string() + " --log-root " +
                                                   (dir / "whole-logs").string()));
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  expectSameResults(dir / "out", dir / "whole");
}

TEST(Interrupt, SigtermDuringTheExtrinsicTestsOverMemqKeepsThemAndResumeCompletesThem) {
  const fs::path dir = test::tempDir("interrupt-memq");
  // Tests that run longer than a moment (a larger budget), so one is under way when the signal comes.
  const std::string plan =
      "base --system IMP --reps 1 --steps 2000 --extrinsic-reps 3 --scenarios scenario3 --scenarios scenario5"
      " --set planner.budget=400 --quiet --run-prefix term --transport memq";
  Job job("experiment " + plan + " --out " + (dir / "out").string() + " --log-root " + (dir / "logs").string(),
          (dir / "first.txt").string());
  // Once the first test is kept and the second is under way.
  ASSERT_TRUE(waitFor(
      [&] { return fs::exists(dir / "out/runs/term-base-IMP-s1-scenario3-e0.json") || !job.running(); }, 60))
      << job.output();
  ASSERT_TRUE(waitFor(
      [&] { return fs::exists(dir / "logs/term-base-IMP-s1-scenario3-e1/manifest.json") || !job.running(); }, 30))
      << job.output();
  ASSERT_TRUE(job.running()) << job.output();
  job.signal(SIGTERM);
  ASSERT_EQ(job.wait(30), 143) << job.output();

  const std::string said = job.output();
  EXPECT_NE(said.find("interrupted by SIGTERM during the extrinsic phase"), std::string::npos) << said;
  EXPECT_NE(said.find("to resume"), std::string::npos) << said;
  const json s = readJson(dir / "out/summary.json");
  EXPECT_EQ(s["systems"]["IMP"]["runs"].size(), 1u);  // the trained agent
  const json& cut = s["interrupted"];
  EXPECT_EQ(cut["signal"], "SIGTERM");
  EXPECT_EQ(cut["phase"], "extrinsic");
  EXPECT_EQ(cut["planned"], 6);
  EXPECT_EQ(cut["finished"], 1);
  EXPECT_EQ(s["extrinsic_tests"], 1);
  ASSERT_EQ(cut["cut"].size(), 1u);
  const std::string cut_id = cut["cut"][0]["run_id"];
  EXPECT_EQ(cut_id, "term-base-IMP-s1-scenario3-e1");
  EXPECT_EQ(cut["not_started"].size(), 4u);
  // The extrinsic CSV: a header and the finished test.
  const std::string csv = slurp(dir / "out/extrinsic_IMP.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 2) << csv;
  EXPECT_NE(csv.find("IMP,term-base-IMP-s1,1001000,scenario3,"), std::string::npos) << csv;
  expectIncompleteLog(dir / "logs" / cut_id);

  const auto resumed = test::runCommand(test::afford("experiment --resume --out " + (dir / "out").string()));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(fs::exists(dir / "logs" / (cut_id + ".cut-1")));

  const auto whole = test::runCommand(test::afford("experiment " + plan + " --out " + (dir / "whole").string() +
                                                   " --log-root " + (dir / "whole-logs").string()));
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  expectSameResults(dir / "out", dir / "whole");
}

// Planning a table experiment may estimate the table's truth first (a minute): a signal then stops it between
// two of its cells, says so, and leaves no truth, no output folder and no run behind.
TEST(Interrupt, SigtermWhileATablesTruthIsEstimatedStopsItWritingNothing) {
  const fs::path dir = test::tempDir("interrupt-truth");
  Job job("experiment table --system IMP --reps 1 --steps 20 --set table.truth.trials=20 --quiet --transport memq --out " +
              (dir / "out").string() +
              " --log-root " + (dir / "logs").string(),
          (dir / "first.txt").string());
  ASSERT_TRUE(waitFor([&] { return job.output().find("estimating the table's truth") != std::string::npos || !job.running(); },
                      60))
      << job.output();
  ASSERT_TRUE(job.running()) << job.output();
  job.signal(SIGTERM);
  const int status = job.wait(60);  // after the cell under way (20 trials, a fraction of a second)
  EXPECT_NE(status, 0) << job.output();
  EXPECT_NE(status, -1) << "still running a minute after SIGTERM\n" << job.output();
  EXPECT_NE(job.output().find("interrupted while estimating the table's truth: nothing written"), std::string::npos)
      << job.output();
  EXPECT_TRUE(!fs::exists(dir / "logs/truth") || fs::is_empty(dir / "logs/truth")) << "a truth was written";
  EXPECT_FALSE(fs::exists(dir / "out")) << "an output folder was made";
}

// A finished experiment resumed again (a script's rerun, a requeued job) has nothing left to do: it says so,
// succeeds, and its folder stays as it was.
TEST(Interrupt, ResumeRefusesAFolderWithoutAnExperimentAndAChangedPlanAndLeavesAFinishedOneAsItWas) {
  const fs::path dir = test::tempDir("interrupt-refuse");
  const std::string logs = " --log-root " + (dir / "logs").string();

  fs::create_directories(dir / "empty");
  const auto none = test::runCommand(test::afford("experiment --resume --out " + (dir / "empty").string()));
  EXPECT_EQ(none.exit_code, 2) << none.output;
  EXPECT_NE(none.output.find("holds no experiment to resume"), std::string::npos) << none.output;

  const auto done = test::runCommand(test::afford("experiment base --system IMP --reps 1 --steps 50 --quiet"
                                                  " --transport memq --keep-logs none --run-prefix fin --out " +
                                                  (dir / "done").string() + logs));
  ASSERT_EQ(done.exit_code, 0) << done.output;
  const std::string summary = slurp(dir / "done/summary.json");
  const auto written = fs::last_write_time(dir / "done/summary.json");
  const auto again = test::runCommand(test::afford("experiment --resume --out " + (dir / "done").string()));
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("nothing to resume"), std::string::npos) << again.output;
  EXPECT_EQ(slurp(dir / "done/summary.json"), summary);
  EXPECT_EQ(fs::last_write_time(dir / "done/summary.json"), written);

  // An interrupted one (runs far too long to finish).
  const std::string out = (dir / "cut").string();
  Job job("experiment base --system IMP --reps 2 --steps 10000000 --transport memq --keep-logs none --run-prefix cut"
          " --out " + out + logs,
          (dir / "cut.txt").string());
  ASSERT_TRUE(waitFor([&] { return fs::exists(dir / "cut/experiment.json") || !job.running(); }, 30)) << job.output();
  job.signalGroup(SIGINT);
  ASSERT_EQ(job.wait(30), 130) << job.output();
  for (const auto& [args, option] :
       {std::pair{"--reps 3", "--reps"}, {"--steps 50", "--steps"}, {"stochastic", "the experiment name"},
        {"--set motivation.leak=0.2", "--set"}, {"--run-prefix other", "--run-prefix"}}) {
    const auto r = test::runCommand(test::afford("experiment --resume " + std::string(args) + " --out " + out));
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_NE(r.output.find(std::string(option) + " '"), std::string::npos) << args << ": " << r.output;
    EXPECT_NE(r.output.find("differs from the stored experiment's"), std::string::npos) << r.output;
  }
  // Nor does a new experiment replace it.
  const auto fresh = test::runCommand(test::afford("experiment base --system IMP --reps 1 --steps 50 --transport memq"
                                                   " --run-prefix new --out " + out + logs));
  EXPECT_EQ(fresh.exit_code, 2) << fresh.output;
  EXPECT_NE(fresh.output.find("did not finish"), std::string::npos) << fresh.output;
  EXPECT_EQ(readJson(dir / "cut/experiment.json")["state"], "interrupted");
}

}  // namespace
}  // namespace afford

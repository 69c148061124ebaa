// afford-bench boundaries: the cost of starting and ending runs, as a user
// waits for it, with logs kept (--keep-logs all) and without (none).
//   extrinsic: one IMP agent trained on the base test, then K tests of each
//     scenario, one at a time: tests per second over the extrinsic phase (from
//     the runner's "extrinsic phase:" line to the command's exit) and each
//     test's own wall time (extrinsic_IMP.csv: set-up included);
//   short: R intrinsic runs of S steps: runs per minute from the whole
//     command's wall time, and each run's wall and START..RESULT time
//     (summary.json);
//   main: the wall time of the README's main job after the build
//     (`afford experiment base --system IMP --reps 1 --extrinsic-reps 3`).
// Checks the floors over udpm with logs kept, and writes boundaries.json.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench.hpp"

namespace afford::bench {

using nlohmann::json;

namespace {

// The floors on the project's 2-core machine (udpm, logs kept).
constexpr double kMaxMedianTestSeconds = 0.15;
constexpr double kMaxTestSeconds = 0.5;
constexpr double kMaxMainJobSeconds = 15;

std::string keepLogs(bool kept) { return kept ? "all" : "none"; }
std::string logsLabel(bool kept) { return kept ? "kept" : "none"; }

json distribution(const std::vector<double>& v) {
  const double sum = std::accumulate(v.begin(), v.end(), 0.0);
  return {{"n", v.size()},
          {"median", quantile(v, 0.5)},
          {"p90", quantile(v, 0.9)},
          {"max", quantile(v, 1.0)},
          {"mean", v.empty() ? 0.0 : sum / v.size()},
          {"sum", sum}};
}

// Each test's wall_seconds, the last column of extrinsic_<S>.csv.
std::vector<double> testWalls(const fs::path& csv) {
  std::ifstream in(csv);
  if (!in) throw std::runtime_error("no " + csv.string());
  std::string line;
  std::getline(in, line);
  if (line.substr(line.rfind(',') + 1) != "wall_seconds")
    throw std::runtime_error(csv.string() + ": the last column is not wall_seconds");
  std::vector<double> walls;
  while (std::getline(in, line))
    if (!line.empty()) walls.push_back(std::stod(line.substr(line.rfind(',') + 1)));
  return walls;
}

// From the runner's "extrinsic phase:" line to the command's exit, in s.
double extrinsicPhaseSeconds(const Finished& f) {
  std::ifstream in(f.stderr_path);
  std::string line;
  while (std::getline(in, line))
    if (line.find("] extrinsic phase: ") != std::string::npos)
      return std::fmod(f.ended_at_of_day - stampOfDay(line) + 86400.0, 86400.0);  // past midnight too
  throw std::runtime_error("no \"extrinsic phase:\" line in " + f.stderr_path.string());
}

json extrinsicFigures(const std::string& afford, const BoundaryOptions& o, const std::string& transport, bool kept) {
  const Finished f = runExperiment(afford,
                                   "base --system IMP --quiet --run-prefix bench --jobs 1 --reps 1 --steps " +
                                       std::to_string(o.train_steps) + " --extrinsic-reps " + std::to_string(o.tests) +
                                       " --keep-logs " + keepLogs(kept) + " --transport " + transport,
                                   fs::path(o.out) / ("extrinsic-" + transport + "-" + logsLabel(kept)));
  const std::vector<double> walls = testWalls(f.out / "extrinsic_IMP.csv");
  const auto tests = f.summary.at("extrinsic_tests").get<std::size_t>();
  if (walls.size() != tests)
    throw std::runtime_error(f.out.string() + ": " + std::to_string(walls.size()) + " rows in extrinsic_IMP.csv, " +
                             std::to_string(tests) + " tests in summary.json");
  const double phase = extrinsicPhaseSeconds(f);
  return {{"transport", transport},
          {"logs", logsLabel(kept)},
          {"tests", tests},
          {"phase_seconds", phase},
          {"tests_per_second", tests / phase},
          {"test_wall_seconds", distribution(walls)},
          {"command_wall_seconds", f.wall_seconds}};
}

json shortRunFigures(const std::string& afford, const BoundaryOptions& o, const std::string& transport, bool kept) {
  const Finished f = runExperiment(afford,
                                   "base --system IMP --quiet --run-prefix bench --jobs 1 --reps " +
                                       std::to_string(o.runs) + " --steps " + std::to_string(o.run_steps) +
                                       " --keep-logs " + keepLogs(kept) + " --transport " + transport,
                                   fs::path(o.out) / ("short-" + transport + "-" + logsLabel(kept)));
  std::vector<double> wall, run;
  for (const auto& r : f.summary.at("systems").at("IMP").at("runs")) {
    wall.push_back(r.at("wall_seconds").get<double>());
    run.push_back(o.run_steps / r.at("steps_per_second").get<double>());  // START to RESULT
  }
  if (static_cast<int>(wall.size()) != o.runs)
    throw std::runtime_error(f.out.string() + ": " + std::to_string(wall.size()) + " runs in summary.json, not " +
                             std::to_string(o.runs));
  return {{"transport", transport},
          {"logs", logsLabel(kept)},
          {"runs", o.runs},
          {"steps", o.run_steps},
          {"command_wall_seconds", f.wall_seconds},
          {"runs_per_minute", 60.0 * o.runs / f.wall_seconds},
          {"run_wall_seconds", distribution(wall)},
          {"run_seconds", distribution(run)}};
}

json mainJobFigures(const std::string& afford, const BoundaryOptions& o) {
  // The README's command (scripts/main.sh after setup), logs under the benchmark's folder.
  const std::string args = "base --system IMP --reps 1 --extrinsic-reps 3";
  const Finished f = runExperiment(afford, args, fs::path(o.out) / "main");
  const std::vector<double> walls = testWalls(f.out / "extrinsic_IMP.csv");
  return {{"command", "afford experiment " + args},
          {"wall_seconds", f.wall_seconds},
          {"intrinsic_run_wall_seconds", f.summary.at("systems").at("IMP").at("runs").at(0).at("wall_seconds")},
          {"extrinsic_phase_seconds", extrinsicPhaseSeconds(f)},
          {"test_wall_seconds", distribution(walls)}};
}

json check(const std::string& what, double value, double limit) {
  return {{"check", what}, {"value", value}, {"limit", limit}, {"pass", value <= limit}};
}

bool wants(const std::vector<std::string>& list, const std::string& item) {
  return std::find(list.begin(), list.end(), item) != list.end();
}

}  // namespace

int boundariesBench(const BoundaryOptions& o) {
  const std::string afford = affordBeside();
  fs::create_directories(o.out);
  json j = {{"options",
             {{"tests", o.tests},
              {"train_steps", o.train_steps},
              {"runs", o.runs},
              {"run_steps", o.run_steps},
              {"transports", o.transports},
              {"parts", o.parts}}},
            {"hardware_threads", std::thread::hardware_concurrency()},
            {"extrinsic", json::array()},
            {"short_runs", json::array()},
            {"checks", json::array()}};
  for (const auto& t : o.transports)
    for (const bool kept : {true, false}) {
      if (wants(o.parts, "extrinsic")) j["extrinsic"].push_back(extrinsicFigures(afford, o, t, kept));
      if (wants(o.parts, "short")) j["short_runs"].push_back(shortRunFigures(afford, o, t, kept));
    }
  if (wants(o.parts, "main")) j["main_job"] = mainJobFigures(afford, o);

  if (!j["extrinsic"].empty()) {
    std::printf("extrinsic tests: base, IMP, one agent of %d steps, %d test(s) of each scenario, one at a time\n",
                o.train_steps, o.tests);
    std::printf("  %-9s %-5s %6s %8s %9s %9s %9s   (test: its own wall time, set-up included)\n", "transport", "logs",
                "tests", "tests/s", "median s", "p90 s", "max s");
    for (const auto& e : j["extrinsic"]) {
      const json& w = e["test_wall_seconds"];
      std::printf("  %-9s %-5s %6d %8.1f %9.3f %9.3f %9.3f\n", e["transport"].get<std::string>().c_str(),
                  e["logs"].get<std::string>().c_str(), e["tests"].get<int>(), e["tests_per_second"].get<double>(),
                  w["median"].get<double>(), w["p90"].get<double>(), w["max"].get<double>());
    }
  }
  if (!j["short_runs"].empty()) {
    std::printf("short runs: base, IMP, %d run(s) of %d steps, one at a time\n", o.runs, o.run_steps);
    std::printf("  %-9s %-5s %9s %10s %14s %11s %14s\n", "transport", "logs", "runs/min", "command s",
                "run wall med s", "p90 / max", "START..RESULT");
    for (const auto& r : j["short_runs"]) {
      const json& w = r["run_wall_seconds"];
      std::printf("  %-9s %-5s %9.0f %10.2f %14.3f %5.3f/%5.3f %12.3f s\n", r["transport"].get<std::string>().c_str(),
                  r["logs"].get<std::string>().c_str(), r["runs_per_minute"].get<double>(),
                  r["command_wall_seconds"].get<double>(), w["median"].get<double>(), w["p90"].get<double>(),
                  w["max"].get<double>(), r["run_seconds"]["median"].get<double>());
    }
  }
  if (j.contains("main_job"))
    std::printf("main job (`%s`, udpm, logs kept): %.2f s (intrinsic run %.2f s, extrinsic phase %.2f s)\n",
                j["main_job"]["command"].get<std::string>().c_str(), j["main_job"]["wall_seconds"].get<double>(),
                j["main_job"]["intrinsic_run_wall_seconds"].get<double>(),
                j["main_job"]["extrinsic_phase_seconds"].get<double>());

  // The floors: over udpm with logs kept, where measured.
  for (const auto& e : j["extrinsic"])
    if (e["transport"] == "udpm" && e["logs"] == "kept") {
      j["checks"].push_back(check("median extrinsic test, s (udpm, logs kept)",
                                  e["test_wall_seconds"]["median"].get<double>(), kMaxMedianTestSeconds));
      j["checks"].push_back(check("slowest extrinsic test, s (udpm, logs kept)",
                                  e["test_wall_seconds"]["max"].get<double>(), kMaxTestSeconds));
    }
  if (j.contains("main_job"))
    j["checks"].push_back(check("main job after the build, s", j["main_job"]["wall_seconds"].get<double>(),
                                kMaxMainJobSeconds));
  bool all_pass = true;
  std::printf("floors (%zu of 3 measured):\n", j["checks"].size());
  for (const auto& c : j["checks"]) {
    all_pass = all_pass && c["pass"].get<bool>();
    std::printf("  %s  %-44s %7.3f (at most %g)\n", c["pass"].get<bool>() ? "PASS" : "FAIL",
                c["check"].get<std::string>().c_str(), c["value"].get<double>(), c["limit"].get<double>());
  }
  std::ofstream(fs::path(o.out) / "boundaries.json") << j.dump(2) << "\n";
  std::printf("figures: %s\n", (fs::path(o.out) / "boundaries.json").c_str());
  return all_pass ? 0 : 1;
}

}  // namespace afford::bench

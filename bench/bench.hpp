// afford-bench: what its modes share. Each mode runs `afford experiment ...`
// commands as a user would, times each whole command, and reads the figures
// from the summary.json and CSV files it writes (docs/results-schema.md).
#pragma once
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace afford::bench {

namespace fs = std::filesystem;

// One finished `afford experiment` command.
struct Finished {
  fs::path out;                  // its --out: summary.json, CSV files, logs/
  nlohmann::json summary;        // out/summary.json
  double wall_seconds = 0;       // the whole command, from the caller's fork to its exit
  double ended_at_of_day = 0;    // local time of day when it ended, in s (to compare with its log's stamps)
  fs::path stderr_path;          // the runner's log
};

// Runs `AFFORD experiment ARGS --out OUT --log-root OUT/logs` after emptying
// OUT, its stdout and stderr into files beside OUT; exits the benchmark with a
// message when the command fails.
Finished runExperiment(const std::string& afford, const std::string& args, const fs::path& out);

// The `afford` executable beside this one.
std::string affordBeside();

// The q-quantile (0..1) of values, linear between the nearest ranks (q = 0.5: the median).
double quantile(std::vector<double> values, double q);

// The local time of day, in s, of a runner log line's "[HH:MM:SS.mmm]" stamp; throws if it has none.
double stampOfDay(const std::string& line);

// The modes (afford-bench and afford-bench boundaries).
struct IntrinsicOptions {
  int steps = 6000;
  int reps = 3;
  std::string out = "out/bench";
};
int intrinsicBench(const IntrinsicOptions& o);

struct BoundaryOptions {
  int tests = 20;                                  // extrinsic tests per scenario
  int train_steps = 6000;                          // intrinsic steps of the agent they test
  int runs = 50;                                   // short intrinsic runs ...
  int run_steps = 50;                              // ... of this many steps
  std::vector<std::string> transports{"udpm", "memq"};
  std::vector<std::string> parts{"extrinsic", "short", "main"};
  std::string out = "out/bench-boundaries";
};
int boundariesBench(const BoundaryOptions& o);

struct ReplayOptions {
  std::string experiment = "base";
  std::string system = "IMP";
  int steps = 6000;
  int reps = 3;                                    // seeds 1..reps, the same with the options off and on
  std::vector<std::string> transports{"udpm", "memq"};
  double floor = 0.7;                              // issue 11: steps/s with replay at least 0.7 of without
  std::string out = "out/bench-replay";
};
int replayBench(const ReplayOptions& o);

struct AuthOptions {
  int steps = 6000;
  int reps = 3;                                    // seeds 1..reps, each without and with a key
  double floor = 0.9;                              // issue 23: steps/s with a key at least 0.9 of without
  std::string out = "out/bench-auth";
};
int authBench(const AuthOptions& o);

}  // namespace afford::bench

// afford-bench replay: what the memory options of issue 11 (experience replay
// and revisits, docs/model.md#memory) cost. Runs `afford experiment` with the
// options off and on, with the same seeds, over each transport, and reports
// intrinsic steps per second, their ratio against the floor (on / off >= 0.7),
// the predictors' peak memory and the checkpoint's size.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>

#include "bench.hpp"

namespace afford::bench {

using nlohmann::json;

namespace {

struct Figures {
  double steps_per_second = 0;
  long predictors_peak_kb = 0;     // the predictors process over udpm, the one process over memq
  std::uintmax_t checkpoint_bytes = 0;
  int looks = 0;
};

Figures measure(const std::string& afford, const ReplayOptions& o, const std::string& transport, bool memory,
                const fs::path& out) {
  std::string args = o.experiment + " --system " + o.system + " --quiet --run-prefix bench --jobs 1 --keep-logs none --steps " +
                     std::to_string(o.steps) + " --reps " + std::to_string(o.reps) + " --transport " + transport;
  if (memory) args += " --set predictors.replay.enabled=true --set motivation.revisit.enabled=true";
  const Finished run = runExperiment(afford, args, out);
  Figures f;
  const json& runs = run.summary["systems"][o.system]["runs"];
  for (const auto& r : runs) {
    f.steps_per_second += r["steps_per_second"].get<double>() / runs.size();
    for (auto& [name, kb] : r["peak_rss_kb"].items())
      if (name == "predictors" || transport == "memq") f.predictors_peak_kb = std::max(f.predictors_peak_kb, kb.get<long>());
    std::error_code ec;
    f.checkpoint_bytes = std::max(f.checkpoint_bytes, fs::file_size(r["checkpoint"].get<std::string>(), ec));
    f.looks = std::max(f.looks, r.value("looks", 0));
  }
  return f;
}

}  // namespace

int replayBench(const ReplayOptions& o) {
  const std::string afford = affordBeside();
  std::printf("the memory options of issue 11 (replay and revisits), %s %s: %d runs x %d steps per transport and "
              "setting (steps/s from START to RESULT); floor: on / off >= %.2f\n",
              o.experiment.c_str(), o.system.c_str(), o.reps, o.steps, o.floor);
  std::printf("  %-6s %12s %12s %7s  %s\n", "", "off steps/s", "on steps/s", "ratio", "predictors peak RSS (MB) off/on; checkpoint (MB) off/on");
  bool pass = true;
  json j = {{"experiment", o.experiment}, {"system", o.system}, {"steps", o.steps}, {"reps", o.reps}, {"floor", o.floor}};
  for (const auto& transport : o.transports) {
    const Figures off = measure(afford, o, transport, false, fs::path(o.out) / (transport + "-off"));
    const Figures on = measure(afford, o, transport, true, fs::path(o.out) / (transport + "-on"));
    const double ratio = on.steps_per_second / off.steps_per_second;
    pass = pass && ratio >= o.floor;
    std::printf("  %-6s %12.0f %12.0f %7.2f  %.1f / %.1f; %.1f / %.1f (%d looks)  %s\n", transport.c_str(),
                off.steps_per_second, on.steps_per_second, ratio, off.predictors_peak_kb / 1024.0,
                on.predictors_peak_kb / 1024.0, off.checkpoint_bytes / 1048576.0, on.checkpoint_bytes / 1048576.0,
                on.looks, ratio >= o.floor ? "PASS" : "FAIL");
    j[transport] = {{"off_steps_per_second", off.steps_per_second},
                    {"on_steps_per_second", on.steps_per_second},
                    {"ratio", ratio},
                    {"off_predictors_peak_kb", off.predictors_peak_kb},
                    {"on_predictors_peak_kb", on.predictors_peak_kb},
                    {"off_checkpoint_bytes", off.checkpoint_bytes},
                    {"on_checkpoint_bytes", on.checkpoint_bytes},
                    {"looks", on.looks}};
  }
  std::ofstream(fs::path(o.out) / "bench.json") << j.dump(2) << "\n";
  return pass ? 0 : 1;
}

}  // namespace afford::bench

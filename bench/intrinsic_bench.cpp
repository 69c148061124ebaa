// afford-bench, first mode: intrinsic-phase throughput over udpm (real
// processes) and memq (the same cores in one process), their ratio, log bytes
// per step and peak memory per process. Runs `afford experiment base` once per
// transport with the same seeds and reads the figures from its summary.json.
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
  double log_bytes_per_step = 0;
  std::map<std::string, long> peak_rss_kb;  // max over runs
  std::string checksum;
};

Figures measure(const std::string& afford, const std::string& transport, int steps, int reps, const fs::path& out) {
  const Finished run = runExperiment(afford,
                                     "base --system IMP --quiet --run-prefix bench --jobs 1 --keep-logs all --steps " +
                                         std::to_string(steps) + " --reps " + std::to_string(reps) + " --transport " +
                                         transport,
                                     out);
  Figures f;
  const json& runs = run.summary["systems"]["IMP"]["runs"];
  for (const auto& r : runs) {
    f.steps_per_second += r["steps_per_second"].get<double>() / runs.size();
    f.log_bytes_per_step += r["log_bytes_per_step"].get<double>() / runs.size();
    for (auto& [name, kb] : r["peak_rss_kb"].items()) f.peak_rss_kb[name] = std::max(f.peak_rss_kb[name], kb.get<long>());
    f.checksum += r["weights_checksum"].get<std::string>() + " ";
  }
  return f;
}

}  // namespace

int intrinsicBench(const IntrinsicOptions& o) {
  const int steps = o.steps, reps = o.reps;
  const std::string& out = o.out;
  const std::string afford = affordBeside();

  const Figures memq = measure(afford, "memq", steps, reps, fs::path(out) / "memq");
  const Figures udpm = measure(afford, "udpm", steps, reps, fs::path(out) / "udpm");
  long udpm_total = 0;
  for (const auto& [name, kb] : udpm.peak_rss_kb) udpm_total += kb;
  const double ratio = udpm.steps_per_second / memq.steps_per_second;

  std::printf("intrinsic phase, base test, IMP: %d runs x %d steps per transport (steps/s from START to RESULT)\n", reps,
              steps);
  std::printf("  %-6s %10s %16s  %s\n", "", "steps/s", "log bytes/step", "peak RSS (MB)");
  std::printf("  %-6s %10.0f %16.0f  one process: %.1f\n", "memq", memq.steps_per_second, memq.log_bytes_per_step,
              memq.peak_rss_kb.begin()->second / 1024.0);
  std::string per;
  for (const auto& [name, kb] : udpm.peak_rss_kb) {
    char b[64];
    std::snprintf(b, sizeof b, "%s %.1f, ", name.c_str(), kb / 1024.0);
    per += b;
  }
  std::printf("  %-6s %10.0f %16.0f  %sgroup %.1f\n", "udpm", udpm.steps_per_second, udpm.log_bytes_per_step,
              per.c_str(), udpm_total / 1024.0);
  std::printf("udpm / memq throughput: %.2f (target >= 0.6)\n", ratio);
  std::printf("log per step: %.1f KB (target < 10 KB); udpm group peak RSS: %.0f MB (target < 300 MB)\n",
              udpm.log_bytes_per_step / 1024.0, udpm_total / 1024.0);
  std::printf("same weights on both transports: %s\n", memq.checksum == udpm.checksum ? "yes" : "NO");
  json j = {{"steps", steps},
            {"reps", reps},
            {"memq_steps_per_second", memq.steps_per_second},
            {"udpm_steps_per_second", udpm.steps_per_second},
            {"ratio", ratio},
            {"log_bytes_per_step", udpm.log_bytes_per_step},
            {"udpm_peak_rss_kb", udpm.peak_rss_kb},
            {"udpm_group_peak_rss_kb", udpm_total},
            {"memq_peak_rss_kb", memq.peak_rss_kb}};
  std::ofstream(fs::path(out) / "bench.json") << j.dump(2) << "\n";
  return memq.checksum == udpm.checksum ? 0 : 1;
}

}  // namespace afford::bench

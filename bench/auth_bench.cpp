// afford-bench auth: what an authenticated bus costs (docs/security.md).
// Runs `afford experiment base` over udpm (real processes) without a key and
// with one (--bus-key: every message tagged, every one checked), alternating,
// with the same seeds, and reports intrinsic steps per second, their ratio
// against the floor (with / without >= 0.9, exit 1 below it), and the time to
// tag one message of each size the run sends most (measured here, in-process).
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "afford/auth.hpp"
#include "bench.hpp"

namespace afford::bench {

using nlohmann::json;

namespace {

double stepsPerSecond(const std::string& afford, const AuthOptions& o, int seed, const std::string& key,
                      const fs::path& out) {
  std::string args = "base --system IMP --quiet --run-prefix bench --jobs 1 --keep-logs none --no-reuse-agents --steps " +
                     std::to_string(o.steps) + " --reps 1 --seed " + std::to_string(seed) + " --transport udpm";
  if (!key.empty()) args += " --bus-key " + key;
  const Finished run = runExperiment(afford, args, out);
  return run.summary["systems"]["IMP"]["runs"][0]["steps_per_second"].get<double>();
}

// Microseconds to tag (or check) one message of `size` bytes.
double tagMicros(const BusKey& key, std::size_t size) {
  std::vector<std::uint8_t> m(size, 0x5A);
  const int n = 20000;
  const auto t0 = std::chrono::steady_clock::now();
  std::uint8_t sink = 0;
  for (int i = 0; i < n; ++i) {
    m[0] = static_cast<std::uint8_t>(i);
    sink ^= key.tag("SCENE", m.data(), m.size())[0];
  }
  const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / n;
  volatile std::uint8_t keep = sink;  // the loop's result is used: the compiler keeps the loop
  (void)keep;
  return us;
}

}  // namespace

int authBench(const AuthOptions& o) {
  const std::string afford = affordBeside();
  fs::create_directories(o.out);
  const std::string key_file = (fs::path(o.out) / "bus.key").string();
  fs::remove(key_file);
  BusKey::writeNew(key_file);
  const BusKey key = BusKey::fromFile(key_file);

  std::printf("an authenticated bus (--bus-key), base test, IMP, over udpm: %d runs x %d steps each way, alternating "
              "(steps/s from START to RESULT); floor: with / without >= %.2f\n",
              o.reps, o.steps, o.floor);
  std::vector<double> without, with;
  for (int r = 1; r <= o.reps; ++r) {
    without.push_back(stepsPerSecond(afford, o, r, "", fs::path(o.out) / ("without-" + std::to_string(r))));
    with.push_back(stepsPerSecond(afford, o, r, key_file, fs::path(o.out) / ("with-" + std::to_string(r))));
    std::printf("  seed %d: %8.0f steps/s without a key, %8.0f with one\n", r, without.back(), with.back());
  }
  double a = 0, b = 0;
  for (double v : without) a += v / without.size();
  for (double v : with) b += v / with.size();
  const double ratio = b / a;
  const bool pass = ratio >= o.floor;
  std::printf("  mean: %8.0f without, %8.0f with: ratio %.3f  %s\n", a, b, ratio, pass ? "PASS" : "FAIL");
  std::printf("tagging one message (keyed BLAKE2b, 32-byte tag), in this process:\n");
  json sizes = json::object();
  for (std::size_t size : {std::size_t{200}, std::size_t{1400}, std::size_t{14000}, std::size_t{70000}}) {
    const double us = tagMicros(key, size);
    std::printf("  %6zu bytes: %6.2f us\n", size, us);
    sizes[std::to_string(size)] = us;
  }
  const json j = {{"steps", o.steps},  {"reps", o.reps},        {"floor", o.floor},         {"without", without},
                  {"with", with},      {"ratio", ratio},        {"pass", pass},             {"tag_us_by_size", sizes}};
  std::ofstream(fs::path(o.out) / "auth.json") << j.dump(2) << "\n";
  return pass ? 0 : 1;
}

}  // namespace afford::bench

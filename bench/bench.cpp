#include "bench.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <stdexcept>

namespace afford::bench {

using nlohmann::json;

static double nowOfDay() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  std::tm local{};
  localtime_r(&t, &local);
  const double frac = std::chrono::duration<double>(now - std::chrono::system_clock::from_time_t(t)).count();
  return local.tm_hour * 3600.0 + local.tm_min * 60.0 + local.tm_sec + frac;
}

Finished runExperiment(const std::string& afford, const std::string& args, const fs::path& out) {
  fs::remove_all(out);
  fs::create_directories(out);
  Finished f;
  f.out = out;
  f.stderr_path = out.string() + ".stderr";
  const std::string cmd = afford + " experiment " + args + " --out " + out.string() + " --log-root " +
                          (out / "logs").string() + " >" + out.string() + ".stdout 2>" + f.stderr_path.string();
  const auto t0 = std::chrono::steady_clock::now();
  const int rc = std::system(cmd.c_str());
  f.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  f.ended_at_of_day = nowOfDay();
  if (rc != 0) {
    std::fprintf(stderr, "afford-bench: `%s` failed; see %s\n", cmd.c_str(), f.stderr_path.c_str());
    std::exit(1);
  }
  std::ifstream in(out / "summary.json");
  f.summary = json::parse(in);
  return f;
}

std::string affordBeside() { return (fs::read_symlink("/proc/self/exe").parent_path() / "afford").string(); }

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double at = q * (values.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (at - lo) * (values[hi] - values[lo]);
}

double stampOfDay(const std::string& line) {
  int h = 0, m = 0, s = 0, ms = 0;
  if (std::sscanf(line.c_str(), "[%2d:%2d:%2d.%3d]", &h, &m, &s, &ms) != 4)
    throw std::runtime_error("no [HH:MM:SS.mmm] stamp in \"" + line + "\"");
  return h * 3600.0 + m * 60.0 + s + ms / 1000.0;
}

}  // namespace afford::bench

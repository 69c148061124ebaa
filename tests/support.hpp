// Helpers shared by the tests.
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afford/config.hpp"
#include "afford/prediction_t.hpp"
#include "afford/run_result_t.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford::test {

// The protocol of the shipped defaults (what processes use between runs).
// A summary.json without what may differ between two runs of the same plan:
// timings, memory, paths, the network, and which shards it came from.
inline nlohmann::json withoutTimingsAndPaths(nlohmann::json j) {
  static const std::set<std::string> drop = {"wall_seconds", "steps_per_second", "run_seconds", "peak_rss_kb",
                                             "log_dir", "checkpoint", "merged_from", "shard", "network"};
  if (j.is_object()) {
    nlohmann::json out = nlohmann::json::object();
    for (auto& [k, v] : j.items())
      if (!drop.count(k)) out[k] = withoutTimingsAndPaths(v);
    return out;
  }
  if (j.is_array())
    for (auto& v : j) v = withoutTimingsAndPaths(v);
  return j;
}

inline ProtocolConfig shippedProtocol() { return loadProtocol(std::string(AFFORD_SOURCE_DIR) + "/config"); }

// The effective config of one run of a shipped experiment.
// The options of issue 11 (docs/model.md#memory): replay and revisits, with their shipped values.
inline const std::vector<std::string> kMemoryOptions = {"predictors.replay.enabled=true", "motivation.revisit.enabled=true"};

inline RunConfig shippedConfig(const std::string& experiment = "base", System system = System::IMP,
                               std::int64_t seed = 1, std::vector<std::string> settings = {}) {
  RunRequest req{experiment, system, seed, std::nullopt, std::move(settings)};
  return parseRunConfig(effectiveConfig(std::string(AFFORD_SOURCE_DIR) + "/config", req));
}
inline std::string shippedConfigYaml(const std::string& experiment, System system, std::int64_t seed,
                                     std::int64_t steps, std::vector<std::string> settings = {}) {
  RunRequest req{experiment, system, seed, steps, std::move(settings)};
  return emitYaml(effectiveConfig(std::string(AFFORD_SOURCE_DIR) + "/config", req));
}

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

inline CommandResult runCommand(const std::string& command) {
  CommandResult r;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), p)) r.output += buf.data();
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline std::string afford(const std::string& args) { return std::string(AFFORD_BIN_DIR) + "/afford " + args; }
// `afford ARGS`, its exit code and output.
inline CommandResult runAfford(const std::string& args) { return runCommand(afford(args)); }

// A file's text ("" if it cannot be read); a JSON file parsed.
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
inline nlohmann::json readJson(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

struct Event {
  std::string channel;
  std::vector<std::uint8_t> data;
};

inline std::vector<Event> readLog(const std::string& path) {
  std::vector<Event> out;
  lcm::LogFile log(path, "r");
  if (!log.good()) return out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const auto* d = static_cast<const std::uint8_t*>(ev->data);
    out.push_back({ev->channel, std::vector<std::uint8_t>(d, d + ev->datalen)});
  }
  return out;
}

// A recorded message without what names its request (run_config_t.request): two requests of one run, with
// the same configuration and seed, record the same messages but for these bytes. RUN_CONFIG: its `request`;
// RUN_CONTROL: its `config_digest`; a run message (a serial): its `prev_digest`, which chains from the request;
// and every message's digest, which covers them. Each is set to zero.
inline std::vector<std::uint8_t> withoutRequest(const std::string& channel, std::vector<std::uint8_t> b) {
  if (b.size() < 12 + 8) return b;
  const std::size_t id = (std::size_t{b[8]} << 24) | (std::size_t{b[9]} << 16) | (std::size_t{b[10]} << 8) | b[11];
  const std::size_t after_id = 12 + id;  // the run id's bytes, NUL included; then step (8)
  const auto zero = [&](std::size_t at) {
    if (at + 8 <= b.size()) std::fill(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + 8), 0);
  };
  if (channel == "RUN_CONFIG")
    zero(after_id + 8);  // request
  else if (channel == "RUN_CONTROL")
    zero(after_id + 8 + 1);  // config_digest, after the command
  else if (channel != "STATUS" && channel != "RESEND")
    zero(after_id + 8 + 8);  // prev_digest, after the serial
  zero(b.size() - 8);
  return b;
}

// Training reports carried by the PREDICTION and RESULT events of a run.
inline int trainingReports(const std::vector<Event>& events) {
  int n = 0;
  for (const auto& e : events) {
    if (e.channel == "PREDICTION") {
      prediction_t p;
      p.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
      n += p.n_trained;
    } else if (e.channel == "RESULT") {
      run_result_t r;
      r.decode(e.data.data(), 0, static_cast<int>(e.data.size()));
      n += r.n_trained;
    }
  }
  return n;
}

// The folders tempDir made, removed when the test program exits (a whole
// suite run made 3.7 GB of them); AFFORD_KEEP_TEST_DIRS=1 keeps them for a look.
struct TempDirs {
  std::vector<std::filesystem::path> dirs;
  ~TempDirs() {
    if (std::getenv("AFFORD_KEEP_TEST_DIRS")) return;
    for (const auto& d : dirs) {
      std::error_code ec;
      std::filesystem::remove_all(d, ec);
    }
  }
};
inline TempDirs& tempDirs() {
  static TempDirs t;
  return t;
}

inline std::string tempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("afford-test-" + name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  tempDirs().dirs.push_back(dir);
  return dir.string();
}

}  // namespace afford::test

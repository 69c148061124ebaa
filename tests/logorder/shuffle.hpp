// A run's log interleaved anew, as the protocol allows a logger to record it
// (docs/processes-and-channels.md, "Reliable delivery"): every channel keeps
// its own order, each message is there once, but the channels run ahead of
// each other by up to `window` steps, each by a lag that wanders as it would
// after losses and RESENDs. The log's times stay where they were in the file
// (a logger stamps a message when it writes it), and the log can be split into
// segments (log.00.lcm, log.01.lcm, ...), as a restarted logger leaves it.
// Used by the tests of the tools that read logs (tests/logorder) and by
// shuffle-log (the same, as a command, for the Python and shell tests).
#pragma once
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afford/edge.hpp"
#include "afford/logfile.hpp"
#include "afford/logging.hpp"
#include "afford/protocol.hpp"
#include "experiment/replay/replay.hpp"

namespace afford::testing {

struct ShuffleOptions {
  std::int64_t window = 100;  // the most steps one channel runs ahead of another
  std::uint64_t seed = 1;
  int segments = 1;           // files written: log.00.lcm, ...
  bool config_too = false;    // the RUN_CONFIG interleaved too (a logger writes it first; another tool may not)
};

struct ShuffleReport {
  std::int64_t events = 0;
  std::int64_t moved = 0;       // events not at their place in the log given
  std::int64_t most_ahead = 0;  // the most steps a message came after one of a later step
};

// The step each event is of: its own for a run message, else the one before it's (control channels stay near
// their place).
inline std::vector<std::int64_t> stepsOf(const std::vector<LogEvent>& events) {
  std::vector<std::int64_t> steps;
  std::int64_t step = 0;
  for (const LogEvent& e : events) {
    RunHeader h;
    if (isSerialChannel(e.channel) && peekRunHeader(e.data.data(), e.data.size(), h)) step = h.step;
    steps.push_back(step);
  }
  return steps;
}

// The most steps a run message comes after a message of a later step.
inline std::int64_t mostAhead(const std::vector<LogEvent>& events) {
  std::int64_t top = 0, most = 0;
  for (const LogEvent& e : events) {
    RunHeader h;
    if (!isSerialChannel(e.channel) || !peekRunHeader(e.data.data(), e.data.size(), h)) continue;
    top = std::max(top, h.step);
    most = std::max(most, top - h.step);
  }
  return most;
}

// The events of `events` from `start` on in a new interleaving (each channel in its own order).
inline std::vector<LogEvent> interleaved(const std::vector<LogEvent>& events, std::size_t start,
                                         const ShuffleOptions& o) {
  std::mt19937_64 rng(o.seed);
  const double w = static_cast<double>(o.window);
  std::uniform_real_distribution<double> wander(-w / 8, w / 8), uniform(0, 1);
  const std::vector<std::int64_t> steps = stepsOf(events);
  std::map<std::string, double> lag;
  std::vector<std::pair<double, double>> key(events.size());  // (step + the channel's lag, a tie's draw)
  for (std::size_t i = start; i < events.size(); ++i) {
    auto [it, fresh] = lag.emplace(events[i].channel, w * uniform(rng));
    if (!fresh) it->second = std::clamp(it->second + wander(rng), 0.0, w);
    key[i] = {static_cast<double>(steps[i]) + it->second, uniform(rng)};
  }
  std::vector<std::size_t> order(events.size() - start);
  std::iota(order.begin(), order.end(), start);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return key[a] < key[b]; });
  // Each channel's places in the new interleaving take its events in their own order.
  std::map<std::string, std::vector<std::size_t>> own;
  for (std::size_t i = start; i < events.size(); ++i) own[events[i].channel].push_back(i);
  std::map<std::string, std::size_t> taken;
  std::vector<LogEvent> out;
  for (std::size_t place : order) {
    const std::string& c = events[place].channel;
    out.push_back(events[own[c][taken[c]++]]);
  }
  return out;
}

// Writes the log at `in` (a folder of segments or one file), interleaved anew, into the new folder `out` (with
// the run's run.json beside, if any, and its manifest.json naming the segments written and counting the last).
inline ShuffleReport shuffleLog(const std::filesystem::path& in, const std::filesystem::path& out,
                                const ShuffleOptions& o) {
  namespace fs = std::filesystem;
  auto quiet = makeLogger("shuffle", "off");
  std::vector<LogEvent> events = readRecordedLog(in, *quiet).events;
  // What comes up to the first RUN_CONFIG stays first: a run's log begins with it.
  std::size_t start = 0;
  while (!o.config_too && start < events.size() && events[start].channel != ch::runConfig.name) ++start;
  if (!o.config_too) start = std::min(start + 1, events.size());
  std::vector<LogEvent> shuffled(events.begin(), events.begin() + static_cast<std::ptrdiff_t>(start));
  for (LogEvent& e : interleaved(events, start, o)) shuffled.push_back(std::move(e));
  ShuffleReport r;
  r.events = static_cast<std::int64_t>(events.size());
  for (std::size_t i = 0; i < events.size(); ++i) {
    r.moved += shuffled[i].data != events[i].data;
    shuffled[i].utime = events[i].utime;  // the log's times stay in the file's order
  }
  r.most_ahead = mostAhead(shuffled);
  fs::create_directories(out);
  const int segments = std::max(1, o.segments);
  nlohmann::json names = nlohmann::json::array();
  std::int64_t last_events = 0, last_bytes = 0;  // the last segment's, as a logger's manifest counts them
  for (int s = 0; s < segments; ++s) {
    char name[32];
    std::snprintf(name, sizeof name, "log.%02d.lcm", s);
    names.push_back(name);
    LogWriter w(out / name);
    const std::size_t from = shuffled.size() * s / segments, to = shuffled.size() * (s + 1) / segments;
    last_events = static_cast<std::int64_t>(to - from), last_bytes = 0;
    for (std::size_t i = from; i < to; ++i) {
      w.write(shuffled[i].channel, shuffled[i].data.data(), shuffled[i].data.size(), shuffled[i].utime);
      last_bytes += static_cast<std::int64_t>(shuffled[i].data.size());
    }
    w.close();
  }
  if (fs::is_directory(in) && fs::exists(in / "run.json")) fs::copy_file(in / "run.json", out / "run.json");
  if (fs::is_directory(in) && fs::exists(in / "manifest.json")) {  // naming the segments written
    std::ifstream from(in / "manifest.json");
    nlohmann::json m = nlohmann::json::parse(from);
    m["segments"] = names;
    m["events"] = last_events;
    m["payload_bytes"] = last_bytes;
    std::ofstream(out / "manifest.json") << m.dump(2) << "\n";
  }
  return r;
}

}  // namespace afford::testing

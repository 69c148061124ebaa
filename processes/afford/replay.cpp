#include "afford/replay.hpp"

#include <lcm/eventlog.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include "afford/channels.hpp"
#include "afford/logging.hpp"
#include "afford/config.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_result_t.hpp"
#include "motivation/node.hpp"
#include "planner/node.hpp"
#include "predictors/node.hpp"

namespace afford {
namespace fs = std::filesystem;

bool ReplayResult::ok() const {
  const bool weights = recorded_checksum.empty() || weights_checksum.empty() || weights_checksum == recorded_checksum;
  return weights && decisions_differing == 0 && decisions == decisions_recorded;
}

namespace {

struct Event {
  std::string channel;
  std::vector<std::uint8_t> data;
};

// Every complete event of one log file, in order; `torn` gets the bytes of an
// incomplete last event.
std::vector<Event> readLogFile(const fs::path& file, std::int64_t& torn) {
  lcm_eventlog_t* in = lcm_eventlog_create(file.c_str(), "r");
  if (!in) throw std::runtime_error("cannot open the log " + file.string());
  std::vector<Event> out;
  const auto size = static_cast<std::int64_t>(fs::file_size(file));
  for (;;) {
    const long before = std::ftell(in->f);
    lcm_eventlog_event_t* e = lcm_eventlog_read_next_event(in);
    if (!e) {
      if (before >= 0 && before < size) torn += size - before;
      break;
    }
    out.push_back({std::string(e->channel, e->channellen),
                   std::vector<std::uint8_t>(static_cast<std::uint8_t*>(e->data),
                                             static_cast<std::uint8_t*>(e->data) + e->datalen)});
    lcm_eventlog_free_event(e);
  }
  lcm_eventlog_destroy(in);
  return out;
}

// The log's segments in order (log.00.lcm, log.01.lcm, ...), or the one file given.
std::vector<fs::path> segments(const fs::path& dir) {
  if (fs::is_regular_file(dir)) return {dir};
  if (!fs::is_directory(dir)) throw std::runtime_error("no run log at " + dir.string());
  std::vector<fs::path> files;
  for (const auto& f : fs::directory_iterator(dir))
    if (f.path().extension() == ".lcm") files.push_back(f.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("no .lcm file in " + dir.string());
  return files;
}

// One fresh process on its own bus, fed the recorded events it does not publish itself.
struct Replayed {
  std::string name;
  std::unique_ptr<lcm::LCM> bus;
  std::unique_ptr<NodeBase> node;
  std::set<std::string> outputs;  // channels it publishes: the record's copies are not fed back
  std::vector<std::vector<std::uint8_t>> decisions;  // what it published on DECISION
  std::string checksum;           // what it published on RESULT

  void feed(const Event& e) {
    if (outputs.count(e.channel)) return;
    bus->publish(e.channel, e.data.data(), static_cast<unsigned>(e.data.size()));
    settle();
  }
  void settle() {
    while (bus->handleTimeout(0) > 0) {
    }
    node->tick();
    while (bus->handleTimeout(0) > 0) {
    }
  }
};

class Tap {  // records what a replayed process publishes
 public:
  explicit Tap(Replayed& r) : r_(r) {}
  void onDecision(const lcm::ReceiveBuffer* b, const std::string&) {
    const auto* p = static_cast<const std::uint8_t*>(b->data);
    r_.decisions.emplace_back(p, p + b->data_size);
  }
  void onResult(const lcm::ReceiveBuffer* b, const std::string&) {
    run_result_t m;
    if (m.decode(b->data, 0, b->data_size) > 0) r_.checksum = m.weights_checksum;
  }

 private:
  Replayed& r_;
};

}  // namespace

ReplayResult replayRun(const ReplayOptions& o, spdlog::logger& log) {
  ReplayResult result;
  std::vector<Event> events;
  for (const auto& f : segments(o.log_dir)) {
    std::int64_t torn = 0;
    auto part = readLogFile(f, torn);
    if (torn > 0) log.warn("{}: the last event is incomplete ({} bytes): replaying up to the one before", f.string(), torn);
    result.torn_bytes += torn;
    events.insert(events.end(), std::make_move_iterator(part.begin()), std::make_move_iterator(part.end()));
  }
  // The run: from its RUN_CONFIG (the first one, or the one of --run) to the next run's.
  // Our logger's logs start with it; a plain lcm-logger recording may hold
  // heartbeats before it and other runs after it.
  std::size_t begin = events.size(), end = events.size();
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (events[i].channel != channel::kRunConfig) continue;
    run_config_t rc;
    if (rc.decode(events[i].data.data(), 0, static_cast<int>(events[i].data.size())) < 0)
      throw std::runtime_error(o.log_dir + ": a RUN_CONFIG cannot be decoded (event " + std::to_string(i) + ")");
    if (begin == events.size()) {
      if (!o.run_id.empty() && rc.run_id != o.run_id) continue;
      begin = i;
      result.run_id = rc.run_id;
      result.extrinsic = parseRunConfigText(rc.config_yaml).phase == Phase::Extrinsic;
    } else if (rc.run_id != result.run_id) {
      end = i;
      break;
    }
  }
  if (begin == events.size())
    throw std::runtime_error(o.log_dir + (o.run_id.empty() ? std::string(": no RUN_CONFIG in the log, so nothing configures a replay")
                                                            : ": no RUN_CONFIG of run '" + o.run_id + "' in the log"));
  events = std::vector<Event>(std::make_move_iterator(events.begin() + static_cast<std::ptrdiff_t>(begin)),
                              std::make_move_iterator(events.begin() + static_cast<std::ptrdiff_t>(end)));
  result.events = static_cast<std::int64_t>(events.size());
  std::vector<std::string> into = o.into;
  if (into.empty()) into = {"predictors", result.extrinsic ? "planner" : "motivation"};

  std::vector<std::unique_ptr<Replayed>> procs;
  std::vector<std::unique_ptr<Tap>> taps;
  for (const auto& name : into) {
    auto r = std::make_unique<Replayed>();
    r->name = name;
    r->bus = std::make_unique<lcm::LCM>("memq://");
    auto logger = makeLogger("replay-" + name, "warn");
    if (name == "predictors") {
      r->node = std::make_unique<PredictorsNode>(*r->bus, logger, /*async_effects=*/false);
      r->outputs = {channel::kPrediction, channel::kAffordanceTable, channel::kResult, channel::kForwardPrediction,
                    channel::kStatus};
    } else if (name == "motivation") {
      r->node = std::make_unique<MotivationNode>(*r->bus, logger);
      r->outputs = {channel::kDecision, channel::kStatus};
    } else if (name == "planner") {
      r->node = std::make_unique<PlannerNode>(*r->bus, logger);
      r->outputs = {channel::kLook, channel::kForwardQuery, channel::kDecision, channel::kExtrinsicResult,
                    channel::kStatus};
    } else {
      throw std::runtime_error("--into: unknown process \"" + name + "\" (predictors, motivation or planner)");
    }
    auto tap = std::make_unique<Tap>(*r);
    r->bus->subscribe(channel::kDecision, &Tap::onDecision, tap.get());
    r->bus->subscribe(channel::kResult, &Tap::onResult, tap.get());
    taps.push_back(std::move(tap));
    procs.push_back(std::move(r));
  }

  std::vector<const Event*> recorded_decisions;
  for (const Event& e : events) {
    if (e.channel == channel::kDecision) recorded_decisions.push_back(&e);
    if (e.channel == channel::kResult) {
      run_result_t m;
      if (m.decode(e.data.data(), 0, static_cast<int>(e.data.size())) > 0) result.recorded_checksum = m.weights_checksum;
    }
    for (auto& p : procs) p->feed(e);
  }

  for (auto& p : procs) {
    if (p->name == "predictors") result.weights_checksum = p->checksum;
    if (p->name == "motivation" || p->name == "planner") {
      // Only the process that decided in this phase is compared.
      const bool decided_here = (p->name == "planner") == result.extrinsic;
      if (!decided_here) continue;
      result.decisions = static_cast<std::int64_t>(p->decisions.size());
      result.decisions_recorded = static_cast<std::int64_t>(recorded_decisions.size());
      for (std::size_t i = 0; i < std::min(p->decisions.size(), recorded_decisions.size()); ++i)
        result.decisions_differing += p->decisions[i] != recorded_decisions[i]->data;
    }
  }
  return result;
}

}  // namespace afford

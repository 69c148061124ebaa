#include "experiment/replay/replay.hpp"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include <fstream>
#include <nlohmann/json.hpp>

#include "afford/affordance_table_t.hpp"
#include "afford/bus.hpp"
#include "afford/protocol.hpp"
#include "experiment/run/host.hpp"
#include "afford/processes.hpp"
#include "afford/config.hpp"
#include "afford/edge.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/logging.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_result_t.hpp"
#include "motivation/component.hpp"
#include "predictors/affordance.hpp"
#include "logger/logger.hpp"
#include "afford/process_main.hpp"

namespace afford {
namespace fs = std::filesystem;

bool ReplayResult::consistent() const {
  const bool weights = recorded_checksum.empty() || weights_checksum.empty() || weights_checksum == recorded_checksum;
  return weights && decisions_differing == 0 && dropped == 0;
}

bool ReplayResult::ok() const {
  return consistent() && gaps.empty() && incomplete.empty() &&
         (!decider_skipped.empty() || decisions == decisions_recorded) &&
         (recorded_checksum.empty() || !weights_checksum.empty());
}

std::vector<fs::path> logSegments(const fs::path& dir) {
  if (fs::is_regular_file(dir)) return {dir};
  if (!fs::is_directory(dir)) throw std::runtime_error("no run log at " + dir.string());
  std::vector<fs::path> files;
  for (const auto& f : fs::directory_iterator(dir))
    if (f.path().extension() == ".lcm") files.push_back(f.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("no .lcm file in " + dir.string());
  return files;
}

LogLimits logLimits(const ProtocolConfig& protocol) {
  LogLimits l;
  l.event_bytes = protocol.bus.max_message_bytes;
  return l;
}

RecordedLog readRecordedLog(const fs::path& log_path, spdlog::logger& log, const BusKey* key) {
  const LogLimits limits = logLimits(loadProtocol(defaultConfigDir()));
  RecordedLog out;
  for (const auto& f : logSegments(log_path)) {
    LogFileContents part = readLogFile(f, limits);
    if (key) {  // a recording of a keyed bus: only what carries the key's tag, without it
      std::vector<LogEvent> tagged;
      for (LogEvent& e : part.events) {
        if (key->verify(e.channel, e.data.data(), e.data.size())) {
          e.data.resize(e.data.size() - BusKey::kTrailerBytes);
          tagged.push_back(std::move(e));
        } else if (out.untagged++ < 10) {
          log.warn("{}: offset {}: a {} event without a valid tag of the key: skipped", f.string(), e.offset,
                   e.channel);
        }
      }
      part.events = std::move(tagged);
    }
    for (const LogProblem& p : part.problems) log.warn("{}: offset {}: {}: skipped", f.string(), p.offset, p.what);
    if (part.problem_count > static_cast<std::int64_t>(part.problems.size()))
      log.warn("{}: {} more malformed parts skipped", f.string(),
               part.problem_count - static_cast<std::int64_t>(part.problems.size()));
    if (part.torn_bytes > 0)
      log.warn("{}: the last event is incomplete ({} bytes): reading up to the one before", f.string(), part.torn_bytes);
    out.torn_bytes += part.torn_bytes;
    out.malformed += part.problem_count;
    out.skipped_bytes += part.skipped_bytes;
    out.events.insert(out.events.end(), std::make_move_iterator(part.events.begin()),
                      std::make_move_iterator(part.events.end()));
  }
  return out;
}

RunEvents runEventsOf(std::vector<LogEvent> events, const std::string& run_id, const std::string& where,
                      spdlog::logger& log) {
  // Our logger's logs start with the RUN_CONFIG; a plain lcm-logger recording
  // may hold heartbeats before it, other runs around it, and forged datagrams.
  const ProtocolConfig observer = loadProtocol(defaultConfigDir());
  RunEvents out;
  std::size_t begin = events.size();
  for (std::size_t i = 0; i < events.size() && begin == events.size(); ++i) {
    if (events[i].channel != ch::runConfig.name) continue;
    run_config_t rc;
    std::string why;
    if (!decodeChecked(events[i].data.data(), events[i].data.size(), BoundsContext{&observer, nullptr}, rc, why)) {
      ++out.refused_configs;
      log.warn("{}: the RUN_CONFIG event at offset {} is refused ({}): skipped", where, events[i].offset, why);
      continue;
    }
    if (!run_id.empty() && rc.run_id != run_id) continue;
    begin = i;
    out.config = rc;
  }
  if (begin == events.size())
    throw std::runtime_error(
        where + (run_id.empty() ? std::string(": no RUN_CONFIG that the edge accepts in the log, so nothing says how "
                                              "the run was configured")
                                : ": no RUN_CONFIG of run '" + run_id + "' that the edge accepts in the log"));
  // The run's own events from there on: those whose run id is the run's.
  const int name_bytes = observer.limits.name_bytes;
  out.events.push_back(std::move(events[begin]));
  for (std::size_t i = begin + 1; i < events.size(); ++i) {
    std::string id;
    if (!peekRunId(events[i].data.data(), events[i].data.size(), name_bytes, id)) continue;
    if (id == out.config.run_id || (id.empty() && events[i].channel == ch::status.name))
      out.events.push_back(std::move(events[i]));
  }
  return out;
}

namespace {
void keepPublished(const lcm::ReceiveBuffer* rbuf, const std::string& channel, std::vector<LogEvent>* out) {
  LogEvent e;
  e.channel = channel;
  const auto* bytes = static_cast<const std::uint8_t*>(rbuf->data);
  e.data.assign(bytes, bytes + rbuf->data_size);
  e.utime = rbuf->recv_utime;
  out->push_back(std::move(e));
}
}  // namespace

ReplayedProcess::ReplayedProcess(const std::string& process, const ProtocolConfig& protocol, bool extrinsic,
                                 const HostOptions& options)
    : name_(process), bus_(std::make_unique<lcm::LCM>("memq://")) {
  node_ = makeNode(process, *bus_, makeLogger("replay-" + process, "warn"), protocol, options);
  for (const auto& ch : channelsOf(process, extrinsic)) {
    outputs_.insert(ch);
    bus_->subscribeFunction(ch, &keepPublished, &published_);
  }
}

ReplayedProcess::~ReplayedProcess() = default;

void ReplayedProcess::feed(const LogEvent& e) {
  if (outputs_.count(e.channel)) return;  // the record's copies of its own messages: it makes them
  bus_->publish(e.channel, e.data.data(), static_cast<unsigned>(e.data.size()));
  pumpBus(*bus_, 0, INT_MAX);
  node_->tick();
  pumpBus(*bus_, 0, INT_MAX);
}

namespace {

// A recorded event as its channel's type would take it (bounds, fields, digest); "" or why not.
std::string checkRecorded(const LogEvent& e, const BoundsContext& ctx) {
  std::string why;
  withChannel(e.channel, [&](const auto& c) {
    typename std::decay_t<decltype(c)>::Message msg;
    if (decodeChecked(e.data.data(), e.data.size(), ctx, msg, why)) why.clear();
  });
  return why;  // (another channel: not ours to judge)
}

}  // namespace

namespace {
// More messages than any run publishes on a channel (a run of 100,000,000 steps publishes a few per step).
constexpr std::int64_t kMostSerials = std::int64_t{1} << 40;
}  // namespace

std::vector<LogGap> recordingGaps(const std::vector<LogEvent>& events, const std::string& run_id, bool extrinsic,
                                  const BoundsContext& ctx) {
  std::map<std::string, std::set<std::int64_t>> had;
  std::map<std::string, std::int64_t> claimed;
  for (const LogEvent& e : events) {
    if (isSerialChannel(e.channel)) {
      RunHeader h;
      // (a serial no publisher reaches is a forgery's: counting up to it would overflow)
      if (peekRunHeader(e.data.data(), static_cast<std::uint32_t>(e.data.size()), h) && h.run_id == run_id &&
          h.serial >= 0 && h.serial < kMostSerials)
        had[e.channel].insert(h.serial);
    } else if (e.channel == ch::status.name) {
      process_status_t st;
      std::string why;
      if (!decodeChecked(e.data.data(), e.data.size(), ctx, st, why) || st.counts_run != run_id) continue;
      for (int i = 0; i < st.n_channels; ++i)
        if (publisherOf(st.channels[i], extrinsic) == st.process)
          claimed[st.channels[i]] = std::max(claimed[st.channels[i]], std::min(st.counts[i], kMostSerials));
    }
  }
  std::vector<LogGap> gaps;
  std::set<std::string> channels;
  for (const auto& [c, s] : had) channels.insert(c);
  for (const auto& [c, n] : claimed) channels.insert(c);
  for (const auto& c : channels) {
    const std::set<std::int64_t>& s = had[c];
    const std::int64_t end = std::max(s.empty() ? 0 : *s.rbegin() + 1, claimed.count(c) ? claimed[c] : 0);
    std::int64_t next = 0;
    for (std::int64_t serial : s) {
      if (serial > next) gaps.push_back({c, next, serial - 1});
      next = serial + 1;
    }
    if (end > next) gaps.push_back({c, next, end - 1});
  }
  return gaps;
}

std::string manifestIncomplete(const fs::path& log, std::vector<LogGap>& missing) {
  const fs::path manifest = (fs::is_directory(log) ? log : log.parent_path()) / "manifest.json";
  if (!fs::exists(manifest)) return "";
  std::ifstream in(manifest);
  const nlohmann::json m = nlohmann::json::parse(in, nullptr, false);
  if (m.is_discarded()) return "its manifest.json cannot be read";
  if (m.value("complete", true)) return "";
  if (m.contains("missing") && m["missing"].is_object())
    for (const auto& [channel, range] : m["missing"].items())
      if (range.is_object() && range.contains("first") && range.contains("last"))
        missing.push_back({channel, range["first"].get<std::int64_t>(), range["last"].get<std::int64_t>()});
  return m.value("incomplete", std::string("its manifest says it is not complete"));
}

namespace {

// The processes a run is replayed into: --into, else the predictors and the
// process that decided in its phase (a motivation not built in cannot be).
std::vector<std::string> processesToReplay(const ReplayOptions& o, const RunConfig& config, ReplayResult& result) {
  std::vector<std::string> into = o.into;
  const auto kinds = motivationKinds();
  const bool own_motivation = std::find(kinds.begin(), kinds.end(), config.motivation.kind) == kinds.end();
  if (into.empty()) {
    into = {"predictors"};
    if (result.extrinsic)
      into.push_back("planner");
    else if (own_motivation)
      result.decider_skipped = "motivation.kind '" + config.motivation.kind +
                               "' is not one of afford's own (a class in Python or a program of one's own "
                               "decided): its recorded decisions are fed to the predictors";
    else
      into.push_back("motivation");
  } else if (own_motivation && !result.extrinsic && std::find(into.begin(), into.end(), "motivation") != into.end()) {
    throw std::runtime_error("--into motivation: the run's motivation.kind '" + config.motivation.kind +
                             "' is not one of afford's own (a class in Python or a program of one's own "
                             "decided), so it cannot be replayed here; replay --into predictors");
  }
  const auto affordance_kinds = affordanceKinds();
  if (std::find(into.begin(), into.end(), "predictors") != into.end() &&
      std::find(affordance_kinds.begin(), affordance_kinds.end(), config.predictors.affordance_kind) ==
          affordance_kinds.end())
    throw std::runtime_error("the run's predictors.affordance.kind '" + config.predictors.affordance_kind +
                             "' is not one of afford's own (a program of one's own, or Python, registered it), so "
                             "its predictors cannot be replayed here" +
                             (result.extrinsic || own_motivation ? std::string() : "; replay --into motivation"));
  for (const auto& name : into)
    if (name != "predictors" && name != "motivation" && name != "planner")
      throw std::runtime_error("--into: unknown process \"" + name + "\" (predictors, motivation or planner)");
  return into;
}

// What the replayed processes published, against the recording: the
// predictors' checksum, and the decisions of the process that decided in
// this phase, serial by serial.
void compareWithRecording(const std::vector<std::unique_ptr<ReplayedProcess>>& procs,
                          const std::map<std::int64_t, const LogEvent*>& recorded_decisions, const BoundsContext& ctx,
                          ReplayResult& result) {
  for (auto& p : procs) {
    if (p->name() == "predictors")
      for (const LogEvent& e : p->published()) {
        run_result_t m;
        std::string why;
        if (e.channel == ch::result.name && decodeChecked(e.data.data(), e.data.size(), ctx, m, why))
          result.weights_checksum = m.weights_checksum;
      }
    if (p->name() == "motivation" || p->name() == "planner") {
      // Only the process that decided in this phase is compared.
      const bool decided_here = (p->name() == "planner") == result.extrinsic;
      if (!decided_here) continue;
      result.decisions_recorded = static_cast<std::int64_t>(recorded_decisions.size());
      // Compared serial by serial: a recording may lack some (its gaps). Each
      // serial once: a process publishes one again when a peer asks for it.
      std::set<std::int64_t> seen;
      for (const LogEvent& d : p->published()) {
        RunHeader h;
        if (d.channel != ch::decision.name ||
            !peekRunHeader(d.data.data(), static_cast<std::uint32_t>(d.data.size()), h) || !seen.insert(h.serial).second)
          continue;
        ++result.decisions;
        auto it = recorded_decisions.find(h.serial);
        if (it != recorded_decisions.end()) result.decisions_differing += d.data != it->second->data;
      }
    }
  }
}

}  // namespace

ReplayResult replayRun(const ReplayOptions& o, spdlog::logger& log) {
  ReplayResult result;
  const std::shared_ptr<const BusKey> key = o.bus_key.empty() ? nullptr : busKeyFrom(o.bus_key);
  RecordedLog recorded = readRecordedLog(o.log_dir, log, key.get());
  result.torn_bytes = recorded.torn_bytes;
  result.malformed = recorded.malformed;
  result.untagged = recorded.untagged;
  std::vector<LogGap> manifest_missing;
  result.incomplete = manifestIncomplete(o.log_dir, manifest_missing);
  // The run: from its RUN_CONFIG (the first one, or the one of --run) to the next run's.
  RunEvents run = runEventsOf(std::move(recorded.events), o.run_id, o.log_dir, log);
  result.refused_configs = run.refused_configs;
  std::vector<LogEvent> events = std::move(run.events);
  run_config_t config_msg = std::move(run.config);
  result.run_id = config_msg.run_id;
  result.events = static_cast<std::int64_t>(events.size());
  const RunConfig config = parseRunConfigText(config_msg.config_yaml);
  result.extrinsic = config.phase == Phase::Extrinsic;
  const BoundsContext ctx{&config.protocol, &config};

  // The replayed processes write nothing: no checkpoint goes into the recorded run's folder.
  {
    YAML::Node node = YAML::Load(config_msg.config_yaml);
    node["run"]["checkpoint"] = "";
    node["run"]["checkpoint_after_actions"] = 0;
    config_msg.config_yaml = emitYaml(node);
    std::vector<std::uint8_t> bytes = sealed(config_msg);
    events.front().data = std::move(bytes);
  }
  result.gaps = recordingGaps(events, result.run_id, result.extrinsic, ctx);
  for (const auto& g : manifest_missing) {  // what the logger knew it never got, beyond the last recorded
    const bool known = std::any_of(result.gaps.begin(), result.gaps.end(), [&](const ReplayResult::Gap& h) {
      return h.channel == g.channel && h.first <= g.first && h.last >= g.last;
    });
    if (!known) result.gaps.push_back(g);
  }

  const fs::path log_folder = fs::is_directory(o.log_dir) ? fs::path(o.log_dir) : fs::path(o.log_dir).parent_path();
  fs::path run_folder = fs::absolute(log_folder).lexically_normal();
  if (!run_folder.has_filename()) run_folder = run_folder.parent_path();  // a trailing '/'
  const std::string log_root = run_folder.parent_path().string();
  std::vector<std::unique_ptr<ReplayedProcess>> procs;
  for (const auto& name : processesToReplay(o, config, result)) {
    // The predictors load an extrinsic run's agent only from the log root the log is in.
    HostOptions host;
    host.single_thread = true;
    host.log_root = log_root;
    procs.push_back(std::make_unique<ReplayedProcess>(name, config.protocol, result.extrinsic, host));
  }

  std::map<std::int64_t, const LogEvent*> recorded_decisions;  // by serial: a recording may hold repeats
  for (const LogEvent& e : events) {
    if (const std::string why = checkRecorded(e, ctx); !why.empty()) {
      ++result.dropped;
      log.warn("{}: a recorded message is refused: {}", e.channel, why);
    }
    RunHeader h;
    if ((e.channel == ch::decision.name || e.channel == ch::result.name) &&
        peekRunHeader(e.data.data(), static_cast<std::uint32_t>(e.data.size()), h) && h.run_id == result.run_id) {
      if (e.channel == ch::decision.name) recorded_decisions.emplace(h.serial, &e);
      run_result_t m;
      std::string why;
      if (e.channel == ch::result.name && decodeChecked(e.data.data(), e.data.size(), ctx, m, why))
        result.recorded_checksum = m.weights_checksum;
    }
    for (auto& p : procs) p->feed(e);
  }

  compareWithRecording(procs, recorded_decisions, ctx, result);
  return result;
}

}  // namespace afford

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

#include "experiment/run/outcome.hpp"
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
#include "afford/run_control_t.hpp"
#include "afford/run_result_t.hpp"
#include "afford/seal.hpp"
#include "motivation/component.hpp"
#include "motivation/goals.hpp"
#include "predictors/affordance.hpp"
#include "logger/logger.hpp"
#include "afford/process_main.hpp"

namespace afford {
namespace fs = std::filesystem;

bool ReplayResult::consistent() const {
  const bool weights = recorded_checksum.empty() || weights_checksum.empty() || weights_checksum == recorded_checksum;
  return weights && decisions_differing == 0 && goals_differing == 0 && dropped == 0;
}

bool ReplayResult::ok() const {
  return consistent() && gaps.empty() && incomplete.empty() && cut.empty() &&
         (!decider_skipped.empty() || decisions == decisions_recorded) &&
         (phase != Phase::Goals || !goals_skipped.empty() || goals == goals_recorded) &&
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

RecordedLogStream::RecordedLogStream(const fs::path& log_path, spdlog::logger& log, const BusKey* key)
    : path_(log_path),
      segments_(logSegments(log_path)),
      log_(log),
      key_(key),
      limits_(logLimits(loadProtocol(defaultConfigDir()))) {}

RecordedLogStream::~RecordedLogStream() = default;

void RecordedLogStream::endSegment() {
  const LogReader& r = *reader_;
  const std::string f = r.file().string();
  for (const LogProblem& p : r.problems()) log_.warn("{}: offset {}: {}: skipped", f, p.offset, p.what);
  if (r.problemCount() > static_cast<std::int64_t>(r.problems().size()))
    log_.warn("{}: {} more malformed parts skipped", f, r.problemCount() - static_cast<std::int64_t>(r.problems().size()));
  if (r.tornBytes() > 0)
    log_.warn("{}: the last event is incomplete ({} bytes): reading up to the one before", f, r.tornBytes());
  counts_.torn_bytes += r.tornBytes();
  counts_.malformed += r.problemCount();
  counts_.skipped_bytes += r.skippedBytes();
  segment_.torn_bytes = r.tornBytes();
  counts_.segments.push_back(std::move(segment_));
  reader_.reset();
}

std::vector<std::string> RecordedLogStream::cutShort(const RunSelector& run) const {
  return logCut(path_, counts_.segments, run.reach());
}

bool RecordedLogStream::next(LogEvent& e) {
  for (;;) {
    if (!reader_) {
      if (at_ == segments_.size()) return false;
      reader_ = std::make_unique<LogReader>(segments_[at_], limits_);
      segment_ = SegmentRead{segments_[at_++]};
    }
    if (!reader_->next(e)) {
      endSegment();
      continue;
    }
    ++segment_.events;  // (as the logger counts them: tags and all)
    segment_.payload_bytes += static_cast<std::int64_t>(e.data.size());
    if (!key_) return true;
    // Another program's channel on the bus (LCM's own LCM_SELF_TEST, which lcm-logger records): not afford's,
    // so nothing of its key; passed on as without a key, for the readers to leave aside as they do then.
    if (!channelNamed(e.channel)) return true;
    // A recording of a keyed bus: only what carries the key's tag, without it.
    if (key_->verify(e.channel, e.data.data(), e.data.size())) {
      e.data.resize(e.data.size() - BusKey::kTrailerBytes);
      return true;
    }
    // Recorded on a bus without the key, or with another: one line naming the fix; anything else: a few lines.
    ++counts_.untagged;
    const KeyMismatch m = keyMismatchOf(key_, e.data.data(), e.data.size());
    counts_.key.count(m);
    if (m != KeyMismatch::None && counts_.key.of(m) == 1)
      log_.warn("{}: offset {}: {} (events without a valid tag of the key given are skipped, and counted)",
                reader_->file().string(), e.offset, keyHint(m));
    else if (m == KeyMismatch::None && counts_.untagged - counts_.key.untagged - counts_.key.other_key <= 10)
      log_.warn("{}: offset {}: a {} event without a valid tag of the key: skipped", reader_->file().string(),
                e.offset, e.channel);
  }
}

RecordedLog readRecordedLog(const fs::path& log_path, spdlog::logger& log, const BusKey* key) {
  RecordedLogStream in(log_path, log, key);
  std::vector<LogEvent> events;
  LogEvent e;
  while (in.next(e)) events.push_back(std::move(e));
  RecordedLog out = in.counts();
  out.events = std::move(events);
  return out;
}

RunSelector::RunSelector(std::string run_id, std::string where, spdlog::logger& log)
    : run_id_(std::move(run_id)), where_(std::move(where)), log_(log), observer_(loadProtocol(defaultConfigDir())) {}

bool RunSelector::take(const LogEvent& e) {
  // Our logger's logs start with the RUN_CONFIG; a plain lcm-logger recording
  // may hold heartbeats before it, other runs around it, and forged datagrams.
  if (!found_) {
    if (e.channel != ch::runConfig.name) {
      tagged(e);  // (counted, and said once: why no RUN_CONFIG may come)
      return false;
    }
    run_config_t rc{};
    std::string why;
    if (!decodeChecked(e.data.data(), e.data.size(), BoundsContext{&observer_, nullptr}, rc, why)) {
      ++refused_configs_;
      if (!tagged(e)) log_.warn("{}: the RUN_CONFIG event at offset {} is refused ({}): skipped", where_, e.offset, why);
      return false;
    }
    if (!run_id_.empty() && rc.run_id != run_id_) return false;
    found_ = true;
    config_ = std::move(rc);
    reach_.add(e);
    return true;
  }
  // The run's own events from there on: those whose run id is the run's.
  std::string id;
  if (!peekRunId(e.data.data(), e.data.size(), observer_.limits.name_bytes, id)) return false;
  const bool taken = id == config_.run_id || (id.empty() && e.channel == ch::status.name);
  if (taken) reach_.add(e);
  return taken;
}

bool RunSelector::tagged(const LogEvent& e) {
  const KeyMismatch m = keyMismatchOf(nullptr, e.data.data(), e.data.size());
  if (m == KeyMismatch::None) return false;
  key_.count(m);
  if (key_.of(m) == 1) log_.warn("{}: offset {}: {} (a recording of a keyed bus)", where_, e.offset, keyHint(m));
  return true;
}

void RunSelector::check(const std::vector<std::string>& cut, const KeyMismatches& read) const {
  if (found_) return;
  // The key does not fit the recording: "tagged messages heard: ...; give --bus-key ...".
  const std::string key =
      KeyMismatches{key_.tagged + read.tagged, key_.untagged + read.untagged, key_.other_key + read.other_key}.said();
  throw std::runtime_error(
      where_ +
      (run_id_.empty() ? std::string(": no RUN_CONFIG that the edge accepts in the log, so nothing says how "
                                     "the run was configured")
                       : ": no RUN_CONFIG of run '" + run_id_ + "' that the edge accepts in the log") +
      (cut.empty() ? std::string() : "; the log is cut: " + joinedCut(cut)) + (key.empty() ? "" : "; " + key));
}

RunEvents readRunEvents(const fs::path& log_path, const std::string& run_id, spdlog::logger& log, const BusKey* key) {
  RecordedLogStream in(log_path, log, key);
  RunSelector select(run_id, log_path.string(), log);
  RunEvents run;
  std::int64_t events = 0;
  for (LogEvent e; in.next(e); ++events)
    if (select.take(e)) run.events.push_back(std::move(e));
  run.cut = in.cutShort(select);
  run.torn_bytes = in.counts().torn_bytes;
  const std::string torn =
      run.torn_bytes > 0 ? " (" + std::to_string(run.torn_bytes) + " bytes that are not one: a truncated or not an LCM log)"
                         : "";
  if (events == 0)
    throw std::runtime_error(log_path.string() + ": the log holds no complete event" + torn +
                             (run.cut.empty() ? std::string() : "; the log is cut: " + joinedCut(run.cut)));
  select.check(run.cut, in.counts().key);
  run.config = select.config();
  run.refused_configs = select.refusedConfigs();
  return run;
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

ReplayedProcess::ReplayedProcess(const std::string& process, const ProtocolConfig& protocol, Phase phase,
                                 const HostOptions& options)
    : name_(process), bus_(std::make_unique<lcm::LCM>("memq://")) {
  node_ = makeNode(process, *bus_, makeLogger("replay-" + process, "warn"), protocol, options);
  node_->holdNothingPublished();  // its bus is its own: nobody asks it again (what it holds would grow with the log)
  for (const auto& ch : channelsOf(process, phase)) {
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

bool isStop(const LogEvent& e, const BoundsContext& ctx) {
  run_control_t c{};
  std::string why;
  return e.channel == ch::runControl.name && decodeChecked(e.data.data(), e.data.size(), ctx, c, why) &&
         c.command == run_control_t::STOP;
}

namespace {

// A recorded START or STOP of the run's request, made out to the configuration replayed (its checkpoint taken
// out: another digest), which the replayed processes took.
void readdressControl(LogEvent& e, const BoundsContext& ctx, std::int64_t recorded, std::int64_t replayed) {
  run_control_t c{};
  std::string why;
  if (e.channel != ch::runControl.name || !decodeChecked(e.data.data(), e.data.size(), ctx, c, why) ||
      c.config_digest != recorded)
    return;
  c.config_digest = replayed;
  e.data = sealed(c);
}

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

bool SerialRuns::insert(std::int64_t s) {
  // Joined to the run it ends or begins, and those two joined.
  auto after = runs_.upper_bound(s);  // the first run beginning beyond s
  bool joined = false;
  if (after != runs_.begin()) {
    auto before = std::prev(after);
    if (before->second >= s) return false;
    if (before->second == s - 1) {
      before->second = s;
      if (after != runs_.end() && after->first == s + 1) {
        before->second = after->second;
        runs_.erase(after);
      }
      joined = true;
    }
  }
  if (!joined) {
    if (after != runs_.end() && after->first == s + 1) {
      const std::int64_t last = after->second;
      runs_.erase(after);
      runs_.emplace(s, last);
    } else {
      runs_.emplace(s, s);
    }
  }
  ++size_;
  return true;
}

GapFinder::GapFinder(std::string run_id, Phase phase, const BoundsContext& ctx, std::int64_t config_digest)
    : run_id_(std::move(run_id)), config_digest_(config_digest), phase_(phase), ctx_(ctx) {}

void GapFinder::add(const LogEvent& e) {
  if (isSerialChannel(e.channel)) {
    RunHeader h;
    // (a serial no publisher reaches is a forgery's: counting up to it would overflow)
    if (peekRunHeader(e.data.data(), static_cast<std::uint32_t>(e.data.size()), h) && h.run_id == run_id_ &&
        h.serial >= 0 && h.serial < kMostSerials)
      had_[e.channel].insert(h.serial);
  } else if (e.channel == ch::status.name) {
    process_status_t st{};
    std::string why;
    if (!decodeChecked(e.data.data(), e.data.size(), ctx_, st, why) || st.counts_run != run_id_ ||
        (config_digest_ != 0 && st.counts_config != config_digest_))
      return;  // another run's counts, or another request's
    for (int i = 0; i < st.n_channels; ++i)
      if (publisherOf(st.channels[i], phase_) == st.process)
        claimed_[st.channels[i]] = std::max(claimed_[st.channels[i]], std::min(st.counts[i], kMostSerials));
  }
}

std::vector<LogGap> GapFinder::gaps() const {
  std::vector<LogGap> gaps;
  std::set<std::string> channels;
  for (const auto& [c, s] : had_) channels.insert(c);
  for (const auto& [c, n] : claimed_) channels.insert(c);
  static const std::map<std::int64_t, std::int64_t> kNone;
  for (const auto& c : channels) {
    const auto h = had_.find(c);
    const auto& runs = h == had_.end() ? kNone : h->second.runs();
    const auto k = claimed_.find(c);
    const std::int64_t end = std::max(runs.empty() ? 0 : runs.rbegin()->second + 1, k == claimed_.end() ? 0 : k->second);
    std::int64_t next = 0;
    for (const auto& [first, last] : runs) {
      if (first > next) gaps.push_back({c, next, first - 1});
      next = last + 1;
    }
    if (end > next) gaps.push_back({c, next, end - 1});
  }
  return gaps;
}

std::vector<LogGap> recordingGaps(const std::vector<LogEvent>& events, const std::string& run_id, Phase phase,
                                  const BoundsContext& ctx) {
  GapFinder finder(run_id, phase, ctx);
  for (const LogEvent& e : events) finder.add(e);
  return finder.gaps();
}

std::string manifestIncomplete(const fs::path& log, std::vector<LogGap>& missing) {
  const fs::path manifest = (fs::is_directory(log) ? log : log.parent_path()) / "manifest.json";
  if (!fs::exists(manifest)) return "";
  const nlohmann::json m = readManifest(manifest);
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
    if (result.phase == Phase::Goals) {
      into.push_back("planner");
      const auto goal_kinds = goalChooserKinds();
      if (std::find(goal_kinds.begin(), goal_kinds.end(), config.goals.kind) == goal_kinds.end())
        result.goals_skipped = "goals.kind '" + config.goals.kind +
                               "' is not one of afford's own (a class in Python or a program of one's own chose "
                               "the goals): its recorded goals are fed to the planner";
      else
        into.push_back("motivation");
    } else if (result.extrinsic)
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
                             "its predictors cannot be replayed here (a class in Python replays in Python: "
                             "afford.replay(LOG, affordance=TheClass))" +
                             (result.extrinsic || own_motivation ? std::string() : "; replay --into motivation"));
  for (const auto& name : into)
    if (name != "predictors" && name != "motivation" && name != "planner")
      throw std::runtime_error("--into: unknown process \"" + name + "\" (predictors, motivation or planner)");
  return into;
}

// The decisions of the process that decided in the run's phase against the
// recorded ones, serial by serial, as each side comes: what waits is what the
// other side has not reached yet. Each serial once (a process publishes one
// again when a peer asks for it; a recording may hold repeats, the first
// counts).
class DecisionMatch {
 public:
  void recorded(std::int64_t serial, std::uint64_t digest) {
    if (recorded_.insert(serial)) meet(serial, digest, waiting_replayed_, waiting_recorded_);
  }
  void replayed(std::int64_t serial, std::uint64_t digest) {
    if (replayed_.insert(serial)) meet(serial, digest, waiting_recorded_, waiting_replayed_);
  }
  std::int64_t recordedCount() const { return recorded_.size(); }
  std::int64_t replayedCount() const { return replayed_.size(); }
  std::int64_t differing() const { return differing_; }

 private:
  void meet(std::int64_t serial, std::uint64_t digest, std::map<std::int64_t, std::uint64_t>& other,
            std::map<std::int64_t, std::uint64_t>& mine) {
    const auto it = other.find(serial);
    if (it == other.end()) {
      mine.emplace(serial, digest);
      return;
    }
    differing_ += it->second != digest;
    other.erase(it);
  }
  SerialRuns recorded_, replayed_;
  std::map<std::int64_t, std::uint64_t> waiting_recorded_, waiting_replayed_;
  std::int64_t differing_ = 0;
};

std::uint64_t digestOf(const LogEvent& e) { return fnv1a64(e.data.data(), e.data.size()); }

// What a replayed process published, against the recording: the predictors' checksum, the decisions of the
// process that decided in the run's phase, and the goals of the goal chooser (the goals phase).
void compareReplayed(ReplayedProcess& p, const BoundsContext& ctx, ReplayResult& result, DecisionMatch& decisions,
                     DecisionMatch& goals) {
  const bool decider = p.name() == publisherOf(ch::decision.name, result.phase);
  const bool chooser = p.name() == publisherOf(ch::goal.name, result.phase);
  for (const LogEvent& out : p.takePublished()) {
    RunHeader ph;
    if (out.channel == ch::result.name && p.name() == "predictors") {
      run_result_t m;
      std::string why;
      if (decodeChecked(out.data.data(), out.data.size(), ctx, m, why)) result.weights_checksum = m.weights_checksum;
    } else if ((decider && out.channel == ch::decision.name) || (chooser && out.channel == ch::goal.name)) {
      if (peekRunHeader(out.data.data(), static_cast<std::uint32_t>(out.data.size()), ph))
        (out.channel == ch::goal.name ? goals : decisions).replayed(ph.serial, digestOf(out));
    }
  }
}

}  // namespace

namespace {
// What the record says of the run's decisions, goals and weights.
void noteRecorded(const LogEvent& e, const BoundsContext& ctx, ReplayResult& result, DecisionMatch& decisions,
                  DecisionMatch& goals) {
  RunHeader h;
  if ((e.channel != ch::decision.name && e.channel != ch::goal.name && e.channel != ch::result.name) ||
      !peekRunHeader(e.data.data(), static_cast<std::uint32_t>(e.data.size()), h) || h.run_id != result.run_id)
    return;
  if (e.channel == ch::decision.name) decisions.recorded(h.serial, digestOf(e));
  if (e.channel == ch::goal.name) goals.recorded(h.serial, digestOf(e));
  run_result_t m;
  std::string why;
  if (e.channel == ch::result.name && decodeChecked(e.data.data(), e.data.size(), ctx, m, why))
    result.recorded_checksum = m.weights_checksum;
}

// An event into every replayed process, and what they publish meanwhile compared with the record.
void feedAll(std::vector<std::unique_ptr<ReplayedProcess>>& procs, const LogEvent& e, const BoundsContext& ctx,
             ReplayResult& result, DecisionMatch& decisions, DecisionMatch& goals) {
  for (auto& p : procs) {
    p->feed(e);
    compareReplayed(*p, ctx, result, decisions, goals);
  }
}
}  // namespace

ReplayResult replayRun(const ReplayOptions& o, spdlog::logger& log) {
  ReplayResult result;
  const std::shared_ptr<const BusKey> key = o.bus_key.empty() ? nullptr : busKeyFrom(o.bus_key);
  // Read as it is fed: nothing of the log is held but the event at hand.
  RecordedLogStream in(o.log_dir, log, key.get());
  std::vector<LogGap> manifest_missing;
  result.incomplete = manifestIncomplete(o.log_dir, manifest_missing);
  // The run: from its RUN_CONFIG (the first one, or the one of --run) on, its own events.
  RunSelector select(o.run_id, o.log_dir, log);
  std::unique_ptr<RunConfig> config;
  BoundsContext ctx{nullptr, nullptr};
  std::unique_ptr<GapFinder> gaps;
  std::int64_t recorded_digest = 0, replayed_digest = 0;  // the recorded RUN_CONFIG's, and the one replayed
  std::vector<LogEvent> stops;                            // the run's STOP, fed after everything else
  std::vector<std::unique_ptr<ReplayedProcess>> procs;
  DecisionMatch decisions, goals;
  bool decider_replayed = false, chooser_replayed = false;
  LogEvent e;
  while (in.next(e)) {
    if (!select.take(e)) continue;
    ++result.events;
    if (!config) {
      // The run's RUN_CONFIG: the processes are made for it.
      run_config_t config_msg = select.config();
      result.run_id = config_msg.run_id;
      config = std::make_unique<RunConfig>(parseRunConfigText(config_msg.config_yaml));
      result.phase = config->phase;
      result.extrinsic = config->phase == Phase::Extrinsic;
      ctx = BoundsContext{&config->protocol, config.get()};
      gaps = std::make_unique<GapFinder>(result.run_id, result.phase, ctx, config_msg.digest);
      recorded_digest = config_msg.digest;
      // The replayed processes write nothing: no checkpoint goes into the recorded run's folder.
      YAML::Node node = YAML::Load(config_msg.config_yaml);
      node["run"]["checkpoint"] = "";
      node["run"]["checkpoint_after_actions"] = 0;
      config_msg.config_yaml = emitYaml(node);
      e.data = sealed(config_msg);  // (the same request number: every recorded chain still follows)
      replayed_digest = config_msg.digest;
      const fs::path log_folder =
          fs::is_directory(o.log_dir) ? fs::path(o.log_dir) : fs::path(o.log_dir).parent_path();
      // (a file named without a folder is in the current one)
      fs::path run_folder = fs::absolute(log_folder.empty() ? fs::path(".") : log_folder).lexically_normal();
      if (!run_folder.has_filename()) run_folder = run_folder.parent_path();  // a trailing '/'
      for (const auto& name : processesToReplay(o, *config, result)) {
        // The predictors load an extrinsic run's agent only from the log root the log is in.
        HostOptions host;
        host.single_thread = true;
        host.log_root = run_folder.parent_path().string();
        procs.push_back(std::make_unique<ReplayedProcess>(name, config->protocol, result.phase, host));
        decider_replayed |= name == publisherOf(ch::decision.name, result.phase);
        chooser_replayed |= name == publisherOf(ch::goal.name, result.phase);
      }
    }
    gaps->add(e);
    readdressControl(e, ctx, recorded_digest, replayed_digest);
    if (const std::string why = checkRecorded(e, ctx); !why.empty()) {
      ++result.dropped;
      log.warn("{}: a recorded message is refused: {}", e.channel, why);
    }
    noteRecorded(e, ctx, result, decisions, goals);
    // The run's STOP goes in last: what the logger took after it (late answers to its RESENDs) is the run's too.
    if (isStop(e, ctx))
      stops.push_back(std::move(e));
    else
      feedAll(procs, e, ctx, result, decisions, goals);
  }
  for (const LogEvent& stop : stops) feedAll(procs, stop, ctx, result, decisions, goals);
  result.torn_bytes = in.counts().torn_bytes;
  result.malformed = in.counts().malformed;
  result.untagged = in.counts().untagged;
  result.refused_configs = select.refusedConfigs();
  result.cut = in.cutShort(select);
  select.check(result.cut, in.counts().key);
  result.gaps = gaps->gaps();
  for (const auto& g : manifest_missing) {  // what the logger knew it never got, beyond the last recorded
    const bool known = std::any_of(result.gaps.begin(), result.gaps.end(), [&](const ReplayResult::Gap& h) {
      return h.channel == g.channel && h.first <= g.first && h.last >= g.last;
    });
    if (!known) result.gaps.push_back(g);
  }
  if (decider_replayed) {
    result.decisions_recorded = decisions.recordedCount();
    result.decisions = decisions.replayedCount();
    result.decisions_differing = decisions.differing();
  }
  if (chooser_replayed) {
    result.goals_recorded = goals.recordedCount();
    result.goals = goals.replayedCount();
    result.goals_differing = goals.differing();
  }
  return result;
}

}  // namespace afford

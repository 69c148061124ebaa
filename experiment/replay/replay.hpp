// `afford replay LOGDIR`: feed a recorded run's messages into fresh instances
// of the learning processes, in log order and without a network (each on its
// own in-process memq bus, one event at a time, handled before the next), and
// compare what they compute with what the live run recorded. Replay writes
// nothing: the replayed predictors save no checkpoint, so the recorded run's
// folder is never touched. A recording with gaps (an lcm-logger capture that
// lost datagrams) is replayed as far as it goes, and the gaps are named; a
// log whose manifest says it is incomplete (a cut run) is said to be. The log
// is read as it is fed, and the replayed processes hold nothing of what they
// publish: replay holds as little of a log of a million steps as of one of a
// thousand.
#pragma once
#include <spdlog/spdlog.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "afford/auth.hpp"
#include "afford/bounds.hpp"
#include "experiment/run/host.hpp"
#include "afford/config.hpp"
#include "afford/logfile.hpp"
#include "afford/run_config_t.hpp"
#include "experiment/replay/log_cut.hpp"

namespace afford {

// ---- reading a run's log (also used by `afford explain`) ------------------------

// A run log's segments in order (log.00.lcm, log.01.lcm, ...), or the one file
// given; throws naming the path when there is no log there.
std::vector<std::filesystem::path> logSegments(const std::filesystem::path& log);

// Every well-formed event of a log's segments, in order, read by the project's
// log reader (afford/logfile.hpp) with the caps of the config folder's
// protocol: a malformed event is skipped and warned of with its file and
// offset; a segment whose last event is incomplete is warned of and read up
// to the one before.
struct RecordedLog {
  std::vector<LogEvent> events;
  std::int64_t torn_bytes = 0;      // of incomplete last events
  std::int64_t malformed = 0;       // malformed parts skipped
  std::int64_t skipped_bytes = 0;   // ... and their bytes
  std::int64_t untagged = 0;        // events without a valid tag of the key given, skipped
  std::vector<SegmentRead> segments;  // each segment read so far, as read
  KeyMismatches key;                // of those: untagged, or tagged with another key (by their structure)
};
// With a bus key (an lcm-logger recording of a keyed bus), every event must end
// with its tag, which is taken off; one without a valid tag is skipped and counted.
RecordedLog readRecordedLog(const std::filesystem::path& log_path, spdlog::logger& log,
                            const BusKey* key = nullptr);
// The same events one at a time, nothing held but the event read (replay reads
// a million-step log of gigabytes this way): counts() says what was skipped so
// far.
class RunSelector;
class RecordedLogStream {
 public:
  RecordedLogStream(const std::filesystem::path& log_path, spdlog::logger& log, const BusKey* key = nullptr);
  ~RecordedLogStream();
  RecordedLogStream(const RecordedLogStream&) = delete;
  RecordedLogStream& operator=(const RecordedLogStream&) = delete;
  bool next(LogEvent& e);  // false after the last segment's last event
  const RecordedLog& counts() const { return counts_; }  // (events stays empty)
  // Once next() has said false: what the log lacks of the run `run` took (log_cut.hpp); empty if it is whole.
  std::vector<std::string> cutShort(const RunSelector& run) const;

 private:
  void endSegment();
  std::filesystem::path path_;
  std::vector<std::filesystem::path> segments_;
  std::size_t at_ = 0;
  std::unique_ptr<LogReader> reader_;
  SegmentRead segment_;  // the one being read
  spdlog::logger& log_;
  const BusKey* key_;
  LogLimits limits_;
  RecordedLog counts_;
};

struct LogGap {
  std::string channel;
  std::int64_t first = 0, last = 0;  // serials missing from the recording, inclusive
};
// The serials each channel's publisher published in run `run_id` that `events`
// lack: holes below the highest recorded serial, and beyond it up to the
// publisher's own count (STATUS, in lcm-logger recordings).
std::vector<LogGap> recordingGaps(const std::vector<LogEvent>& events, const std::string& run_id, Phase phase,
                                  const BoundsContext& ctx);
// A set of serials as runs of consecutive ones: a few numbers for a channel
// recorded whole, whatever its length.
class SerialRuns {
 public:
  bool insert(std::int64_t serial);  // false: it was there
  const std::map<std::int64_t, std::int64_t>& runs() const { return runs_; }  // first -> last
  std::int64_t size() const { return size_; }

 private:
  std::map<std::int64_t, std::int64_t> runs_;
  std::int64_t size_ = 0;
};

// The same, event by event: what it holds is a few numbers per run of
// consecutive serials, not the serials.
class GapFinder {
 public:
  // `config_digest`: the request whose publishers' counts (a recording's STATUS) are taken; 0: any request's.
  GapFinder(std::string run_id, Phase phase, const BoundsContext& ctx, std::int64_t config_digest = 0);
  void add(const LogEvent& e);
  std::vector<LogGap> gaps() const;

 private:
  std::string run_id_;
  std::int64_t config_digest_ = 0;
  Phase phase_;
  BoundsContext ctx_;
  std::map<std::string, SerialRuns> had_;         // channel: the serials recorded
  std::map<std::string, std::int64_t> claimed_;  // channel: its publisher's count
};
// The manifest beside a log folder's segments: its reason if it says the log
// is incomplete ("" if it does not, or there is none), and into `missing` the
// serials it says the logger never got.
std::string manifestIncomplete(const std::filesystem::path& log, std::vector<LogGap>& missing);

// The events of one run in a log: its RUN_CONFIG (the first one the edge
// accepts, or the first of `run_id`), then every later event of that run id
// (other runs' events, and events without a run id, are left out: a recording
// of a bus may interleave runs, or hold a forged datagram).
struct RunEvents {
  run_config_t config;
  std::vector<LogEvent> events;      // events.front() is the RUN_CONFIG
  std::int64_t refused_configs = 0;  // RUN_CONFIG events the edge refuses, skipped (warned of)
  std::int64_t torn_bytes = 0;       // of incomplete last events
  std::vector<std::string> cut;      // what the log lacks of the run (RecordedLogStream::cutShort)
};
// The events of one run of a log (the first, or `run_id`'s), read whole. Throws
// std::runtime_error naming the log, and saying what it lacks, when it holds
// no event or no run (RunSelector::check). `key`: an lcm-logger recording of a keyed bus.
RunEvents readRunEvents(const std::filesystem::path& log_path, const std::string& run_id, spdlog::logger& log,
                        const BusKey* key = nullptr);
// The choice, event by event: take(e) says whether e is the run's (its
// RUN_CONFIG, then its events); once every event has been offered, check()
// throws std::runtime_error naming `where` if the run cannot be rebuilt: the
// log holds no (such) RUN_CONFIG that the edge accepts (saying, if given, what
// the log lacks: RecordedLogStream::cutShort, and naming the fix if the
// recording's key does not fit: tagged RUN_CONFIG events read without a key,
// or `read`, what the log's reader skipped).
class RunSelector {
 public:
  RunSelector(std::string run_id, std::string where, spdlog::logger& log);
  RunSelector(const RunSelector&) = delete;
  RunSelector& operator=(const RunSelector&) = delete;
  bool take(const LogEvent& e);
  bool found() const { return found_; }
  const run_config_t& config() const { return config_; }
  std::int64_t refusedConfigs() const { return refused_configs_; }
  const RunReach& reach() const { return reach_; }  // how far the events taken so far go
  void check(const std::vector<std::string>& cut = {}, const KeyMismatches& read = {}) const;

 private:
  std::string run_id_, where_;
  spdlog::logger& log_;
  ProtocolConfig observer_;
  RunReach reach_{observer_};
  bool found_ = false;
  run_config_t config_;
  std::int64_t refused_configs_ = 0;
  // Is `e`, before the run's RUN_CONFIG, tagged (by its structure: a keyed bus's recording read without its
  // key)? Counted, and said the first time.
  bool tagged(const LogEvent& e);
  KeyMismatches key_;  // the events found tagged
};

// One fresh process of a run, on an in-process bus of its own, fed a
// recording's events one at a time, each handled before the next (those on
// channels it publishes itself are not fed: it makes its own). What it
// publishes on the run's channels is kept, in order. Used by replay and
// explain; `options` says where its files are (HostOptions::log_root) and who
// observes the planner.
class ReplayedProcess {
 public:
  ReplayedProcess(const std::string& process, const ProtocolConfig& protocol, Phase phase,
                  const HostOptions& options);
  ~ReplayedProcess();
  ReplayedProcess(const ReplayedProcess&) = delete;
  ReplayedProcess& operator=(const ReplayedProcess&) = delete;
  void feed(const LogEvent& e);
  const std::string& name() const { return name_; }
  const std::vector<LogEvent>& published() const { return published_; }
  // What it published since the last call, handed over (a long replay keeps none of it).
  std::vector<LogEvent> takePublished() { return std::exchange(published_, {}); }

 private:
  std::string name_;
  std::unique_ptr<lcm::LCM> bus_;
  std::unique_ptr<NodeBase> node_;
  std::set<std::string> outputs_;
  std::vector<LogEvent> published_;
};

// A run's STOP (RUN_CONTROL): a replay feeds it after every other event of the run, since the logger records
// what comes after it too (the late answers to its requests).
bool isStop(const LogEvent& e, const BoundsContext& ctx);

struct ReplayOptions {
  std::string log_dir;                    // a run's folder: log.NN.lcm segments (or one .lcm file)
  // predictors, motivation, planner; empty: the predictors and the run's decider
  // (the motivation in the intrinsic phase, the planner in the extrinsic one, both in the goals phase)
  std::vector<std::string> into;
  std::string run_id;                     // the run to replay in a log of several (default: the first)
  std::string bus_key;                    // key file: the recording is of a keyed bus (tags checked and taken off)
};

struct ReplayResult {
  std::int64_t events = 0;            // of the replayed run in the log
  std::int64_t torn_bytes = 0;        // an incomplete last event (a writer killed mid-write)
  std::int64_t malformed = 0;         // malformed parts of the log file skipped (named with their offsets)
  std::int64_t refused_configs = 0;   // RUN_CONFIG events refused and skipped
  std::int64_t untagged = 0;          // with --bus-key: events without a valid tag, skipped
  std::string run_id;
  bool extrinsic = false;
  Phase phase = Phase::Intrinsic;
  std::string weights_checksum;       // the replayed predictors' final weights ("" without them)
  std::string recorded_checksum;      // the live run's RESULT ("" if the log has none)
  // Per replayed decider (motivation or planner): its decisions against the recorded ones.
  std::int64_t decisions = 0, decisions_recorded = 0, decisions_differing = 0;
  // The goals phase: the replayed goal chooser's GOALs against the recorded ones; or why it was not
  // replayed (a goals.kind not built in: its recorded goals are fed to the planner).
  std::int64_t goals = 0, goals_recorded = 0, goals_differing = 0;
  std::string goals_skipped;
  // Why the run's decider was not replayed ("" when it was): a motivation of
  // one's own (motivation.kind not built in) ran as its own process, which
  // replay cannot start; its decisions are taken from the record.
  std::string decider_skipped;
  using Gap = LogGap;
  std::vector<Gap> gaps;              // serials a channel's publisher published that the recording lacks
  std::string incomplete;             // the manifest's reason, when it says the log is incomplete
  std::vector<std::string> cut;       // what the log lacks of the run, when it is cut short (log_cut.hpp)
  std::int64_t dropped = 0;           // recorded messages the edge refused (a corrupted recording)
  // Everything the record holds was replayed and equals it, and the record is
  // the whole run (a record with gaps, or cut short, is never ok).
  bool ok() const;
  // What was replayed equals the record as far as it goes.
  bool consistent() const;
};

// Reads `options.log_dir`; throws std::runtime_error naming the file on a
// log it cannot read, or with no run in it (saying what the log lacks).
ReplayResult replayRun(const ReplayOptions& options, spdlog::logger& log);

}  // namespace afford

// `afford replay LOGDIR`: feed a recorded run's messages into fresh instances
// of the learning processes, in log order and without a network (each on its
// own in-process memq bus, one event at a time, handled before the next), and
// compare what they compute with what the live run recorded. Replay writes
// nothing: the replayed predictors save no checkpoint, so the recorded run's
// folder is never touched. A recording with gaps (an lcm-logger capture that
// lost datagrams) is replayed as far as it goes, and the gaps are named; a
// log whose manifest says it is incomplete (a cut run) is said to be.
#pragma once
#include <spdlog/spdlog.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "afford/bounds.hpp"
#include "afford/run_config_t.hpp"

namespace afford {

// ---- reading a run's log (also used by `afford explain`) ------------------------

struct LogEvent {
  std::string channel;
  std::vector<std::uint8_t> data;
};

// Every complete event of one log file, in order; `torn` gets the bytes of an
// incomplete last event. Throws std::runtime_error naming the file it cannot open.
std::vector<LogEvent> readLogFile(const std::filesystem::path& file, std::int64_t& torn);
// A run log's segments in order (log.00.lcm, log.01.lcm, ...), or the one file
// given; throws naming the path when there is no log there.
std::vector<std::filesystem::path> logSegments(const std::filesystem::path& log);

// Every complete event of a log's segments, in order; a segment whose last
// event is incomplete is warned of and read up to the one before.
struct RecordedLog {
  std::vector<LogEvent> events;
  std::int64_t torn_bytes = 0;  // of incomplete last events
};
RecordedLog readRecordedLog(const std::filesystem::path& log_path, spdlog::logger& log);

struct LogGap {
  std::string channel;
  std::int64_t first = 0, last = 0;  // serials missing from the recording, inclusive
};
// The serials each channel's publisher published in run `run_id` that `events`
// lack: holes below the highest recorded serial, and beyond it up to the
// publisher's own count (STATUS, in lcm-logger recordings).
std::vector<LogGap> recordingGaps(const std::vector<LogEvent>& events, const std::string& run_id, bool extrinsic,
                                  const BoundsContext& ctx);
// The manifest beside a log folder's segments: its reason if it says the log
// is incomplete ("" if it does not, or there is none), and into `missing` the
// serials it says the logger never got.
std::string manifestIncomplete(const std::filesystem::path& log, std::vector<LogGap>& missing);

// The events of one run in a log: from its RUN_CONFIG (the first one, or the one
// of `run_id`) up to the next run's.
struct RunEvents {
  run_config_t config;
  std::vector<LogEvent> events;  // events.front() is the RUN_CONFIG
};
// Throws std::runtime_error naming `where` when the log holds no (such)
// RUN_CONFIG or a RUN_CONFIG it refuses.
RunEvents runEventsOf(std::vector<LogEvent> events, const std::string& run_id, const std::string& where);

struct ReplayOptions {
  std::string log_dir;                    // a run's folder: log.NN.lcm segments (or one .lcm file)
  // predictors, motivation, planner; empty: the predictors and the run's decider
  // (the motivation in the intrinsic phase, the planner in the extrinsic one)
  std::vector<std::string> into;
  std::string run_id;                     // the run to replay in a log of several (default: the first)
};

struct ReplayResult {
  std::int64_t events = 0;            // of the replayed run in the log
  std::int64_t torn_bytes = 0;        // an incomplete last event (a writer killed mid-write)
  std::string run_id;
  bool extrinsic = false;
  std::string weights_checksum;       // the replayed predictors' final weights ("" without them)
  std::string recorded_checksum;      // the live run's RESULT ("" if the log has none)
  // Per replayed decider (motivation or planner): its decisions against the recorded ones.
  std::int64_t decisions = 0, decisions_recorded = 0, decisions_differing = 0;
  using Gap = LogGap;
  std::vector<Gap> gaps;              // serials a channel's publisher published that the recording lacks
  std::string incomplete;             // the manifest's reason, when it says the log is incomplete
  std::int64_t dropped = 0;           // recorded messages the edge refused (a corrupted recording)
  // Everything the record holds was replayed and equals it (a record with gaps
  // cannot be replayed whole, so it is never ok).
  bool ok() const;
  // What was replayed equals the record as far as it goes.
  bool consistent() const;
};

// Reads `options.log_dir`; throws std::runtime_error naming the file on a
// log it cannot read.
ReplayResult replayRun(const ReplayOptions& options, spdlog::logger& log);

}  // namespace afford

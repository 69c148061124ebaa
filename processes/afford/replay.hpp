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
#include <string>
#include <vector>

namespace afford {

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
  struct Gap {
    std::string channel;
    std::int64_t first = 0, last = 0;  // serials missing from the recording, inclusive
  };
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

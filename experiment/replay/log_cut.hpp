// Is a run's log the whole run? A log copied while it was written, cut at
// some size, or left by a writer killed mid-run holds less than its run, and
// no tool presents it as the run: replay and explain give no verdict on it,
// the viewers and export warn. Two witnesses say what is missing. The
// manifest beside a log folder, once its logger closed it, names the log's
// segments and counts the events and payload bytes of the last one. The log
// itself: its RUN_CONFIG says the run's steps (run.steps), its messages how
// far the run got, and a whole run's log holds the run's end: its RESULT (an
// extrinsic test's EXTRINSIC_RESULT), then the runner's STOP.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "afford/config.hpp"
#include "afford/logfile.hpp"

namespace afford {

// One segment of a log as it was read: its whole events and their payload
// bytes (as a logger counts them), and the bytes of an event cut short at its end.
struct SegmentRead {
  std::filesystem::path file;
  std::int64_t events = 0, payload_bytes = 0, torn_bytes = 0;
};

// How far one run's messages go, fed them in log order, its RUN_CONFIG first.
class RunReach {
 public:
  explicit RunReach(const ProtocolConfig& protocol) : protocol_(&protocol) {}
  void add(const LogEvent& e);
  bool configured() const { return configured_; }
  Phase phase() const { return phase_; }
  std::int64_t steps() const { return steps_; }         // the run's run.steps (-1: its configuration does not read)
  std::int64_t lastStep() const { return last_step_; }  // the highest step of its messages (-1: none)
  bool ended() const { return ended_; }                 // its RESULT (extrinsic: EXTRINSIC_RESULT) is in the log
  bool stopped() const { return stopped_; }             // the STOP of its request is in the log

 private:
  const ProtocolConfig* protocol_;
  bool configured_ = false, ended_ = false, stopped_ = false;
  Phase phase_ = Phase::Intrinsic;
  std::int64_t digest_ = 0, steps_ = -1, last_step_ = -1;
};

// What a log lacks of its run, one sentence each, each saying how much is
// missing; empty when the log is whole as far as its manifest and its own
// messages can tell. `log`: the log as given (a folder, or a file in one);
// `read`: its segments as read; `run`: the run's messages.
std::vector<std::string> logCut(const std::filesystem::path& log, const std::vector<SegmentRead>& read,
                                const RunReach& run);

// The sentences joined with "; ".
std::string joinedCut(const std::vector<std::string>& cut);

}  // namespace afford

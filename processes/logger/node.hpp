// Logger process node: records every channel of a run.
// Channels in:  RUN_CONFIG and RUN_CONTROL of the run (each distinct message
//               once, at most protocol.limits.control_messages of them; the
//               manifest counts those dropped beyond), every run channel (isSerialChannel) through the
//               edge like any receiver, STATUS (for the manifest and the
//               publishers' message counts; not recorded: it follows the wall
//               clock), RESEND (not recorded).
// Channels out: STATUS (state DONE with the log directory in `detail` after
//               STOP), RESEND (for messages missing from the log)
//
// Only runs whose configuration says run.record are recorded; the logger
// stays free during the others. The run channels are recorded in serial
// order, each message once: a repeat is skipped, and after a gap the missing
// messages are asked for again, so a lost datagram does not leave a hole in
// the log. A logger restarted during a run opens the next segment (log.01.lcm,
// ...), reads its earlier segments to know where each channel stopped, and
// asks for everything it missed. On STOP it closes the log once nothing is
// missing and every publisher of the run (those its earlier segments saw
// too) has left; or once protocol.stop_grace_ms passed with nothing taken
// (and the logger not held up, e.g. paused), naming what is missing. The
// manifest says `complete` only when the log holds the run's end (RESULT or
// EXTRINSIC_RESULT), nothing is missing and every write succeeded; otherwise
// it says why not. A write error (a full disk) fails the run with the reason;
// the logger stays alive for the next. A logger the STOP did not reach
// (paused through it) learns that the run was stopped from a publisher's
// final counts, and closes the log as on STOP. Given a run whose log an
// earlier logger process closed complete (killed before its DONE went out),
// it records nothing and says DONE.
#pragma once
#include <map>
#include <memory>
#include <set>
#include <string>

#include "afford/node.hpp"
#include "logger/logger.hpp"

namespace afford {

class LoggerNode : public NodeBase {
 public:
  LoggerNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol, std::string log_root);

 private:
  template <class Msg>
  void record(const Channel<Msg>& channel);
  bool wantsRun(const RunConfig& config) override { return config.record; }
  void onConfigured(const RunConfig& config) override;
  void onStop() override;
  bool readyToLeave() override;
  void onLeaveTimeout() override;
  void onControl(const Envelope& envelope) override;
  void onPeerStatus(const process_status_t& status) override;
  // Once its log holds the run's end, it says at once what its log holds whenever it goes idle: the runner
  // stops the run once the log holds everything published.
  bool announcesIdle() const override { return ended_; }
  // Its log is its snapshot: every event is flushed as it is written, and a restarted logger goes on from
  // where the log's segments end. So a restart would take each channel again from what it has recorded.
  void restartPositions(process_status_t& st) const override;
  void write(const Envelope& envelope);
  // Does `process` publish a channel of the run (its final counts matter)?
  bool publishes(const std::string& process) const;

  std::string log_root_;
  std::unique_ptr<RunLog> log_file_;
  std::map<std::string, std::set<std::string>> written_;  // RUN_CONFIG, RUN_CONTROL: contents recorded
  std::int64_t control_written_ = 0;  // ... how many (at most protocol.limits.control_messages)
  std::int64_t control_dropped_ = 0;  // ... and how many distinct ones were not recorded beyond it
  std::map<std::string, bool> left_;  // processes of the run -> their final counts are in
  bool ended_ = false;                // the run's end (RESULT, EXTRINSIC_RESULT) is in the log
  std::string write_error_;           // the first write that failed
  std::string closed_dir_;            // the run's log, closed complete by an earlier logger process ("": none)
  const std::int64_t session_ = BusKey::newRequest();  // this process, in the manifests it writes (wroteLog)
};

}  // namespace afford

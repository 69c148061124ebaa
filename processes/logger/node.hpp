// Logger process node: records every channel of the run.
// Channels in:  all (".*"). STATUS and RESEND are not recorded: they follow the
//               wall clock, not the run. STATUS is read for the manifest and
//               for the publishers' message counts.
// Channels out: STATUS (state DONE with the log directory in `detail` after
//               STOP), RESEND (for messages missing from the log)
//
// The run channels are recorded in serial order, each message once: a repeat
// is skipped, and after a gap the missing messages are asked for again, so a
// lost datagram does not leave a hole in the log. A logger restarted during a
// run opens the next segment (log.01.lcm, ...), reads its earlier segments to
// know where each channel stopped, and asks for everything it missed. On STOP
// it closes the log once nothing is missing (at most 5 s later).
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
  LoggerNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, std::string log_root);

 private:
  void onConfigured(const RunConfig& config) override;
  void onStop() override;
  bool readyToLeave() override;
  void onLeaveTimeout() override;
  void onAny(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void write(const lcm::ReceiveBuffer* rbuf, const std::string& channel);

  std::string log_root_;
  std::unique_ptr<RunLog> log_file_;
  std::map<std::string, std::set<std::string>> written_;  // untracked channels: contents already recorded
  std::map<std::string, bool> left_;  // processes of the run -> their final counts are in
};

}  // namespace afford

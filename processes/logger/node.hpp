// Logger process node: records every channel of the run.
// Channels in:  all (".*"); STATUS is read for the manifest but not recorded,
//               because heartbeats follow the wall clock, not the run.
// Channels out: STATUS (state DONE with the log directory in `detail` after STOP)
#pragma once
#include <memory>
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
  void onAny(const lcm::ReceiveBuffer* rbuf, const std::string& channel);

  std::string log_root_;
  std::unique_ptr<RunLog> log_file_;
};

}  // namespace afford

// The processes of the project hosted in one process, on one LCM bus
// (memq://): the same node code as the executables, each node ticked in turn.
// It serves `afford experiment --transport memq`, `afford replay` and the
// tests. A node is started by its registry name (afford/processes.hpp);
// starting it again destroys the old node first (it unsubscribes: whatever
// was queued for it is lost, as in a kill).
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "afford/config.hpp"
#include "afford/node.hpp"

namespace afford {

class PlannerObserver;  // planner/planner.hpp

struct HostOptions {
  // One thread runs every node: the eye does not speculate and the
  // predictors learn from effects in line (no idle time to fill).
  bool single_thread = true;
  std::string log_root = "logs";  // the logger's folder of run logs, and the predictors' of checkpoints
  // The planner core tells it what it checks and decides (afford explain); not owned.
  PlannerObserver* planner_observer = nullptr;
  // The folder of the nodes' snapshots (NodeBase::keepSnapshotsIn); "": none (replay, explain, the tables).
  std::string snapshot_root;
  // Snapshots written by a forked copy of the process (NodeBase::forkSnapshots): only where no node runs Python.
  bool fork_snapshots = false;
  // A run's failure is said by the runner that drives it (NodeBase::leaveFailuresToRunner).
  bool runner_says_failures = false;
};

using LoggerFactory = std::function<std::shared_ptr<spdlog::logger>(const std::string& process)>;

// A node of the named process on `lcm`; throws naming the process if it is not one of the registry's.
std::unique_ptr<NodeBase> makeNode(const std::string& process, lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log,
                                   const ProtocolConfig& protocol, const HostOptions& options = {});

// Every process's input rules (NodeBase::takes), as a markdown table: process,
// channel, rule. docs/processes-and-channels.md shows it (a test compares).
std::string inputRulesTable(const std::string& config_dir);

class InProcessHost {
 public:
  InProcessHost(lcm::LCM& lcm, const ProtocolConfig& protocol, LoggerFactory logger, HostOptions options = {});
  // Starts (or restarts) each named process.
  void start(const std::vector<std::string>& processes);
  void start(const std::string& process);
  NodeBase& node(const std::string& process) const;
  // tick() every node, in start order.
  void tick();
  // Some node is still in a run.
  bool inRun() const;
  // A node of this process has been started.
  bool hosts(const std::string& process) const { return nodes_.count(process) > 0; }

 private:
  lcm::LCM& lcm_;
  ProtocolConfig protocol_;
  LoggerFactory logger_;
  HostOptions options_;
  std::vector<std::string> order_;
  std::map<std::string, std::unique_ptr<NodeBase>> nodes_;
};

}  // namespace afford

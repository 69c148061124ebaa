#include "experiment/run/host.hpp"

#include <spdlog/sinks/null_sink.h>

#include <algorithm>
#include <stdexcept>

#include "afford/processes.hpp"
#include "environment/node.hpp"
#include "eye/node.hpp"
#include "logger/node.hpp"
#include "motivation/node.hpp"
#include "planner/node.hpp"
#include "predictors/node.hpp"

namespace afford {

namespace {
std::unique_ptr<NodeBase> newNode(const std::string& p, lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log,
                                  const ProtocolConfig& protocol, const HostOptions& options) {
  if (p == "environment") return std::make_unique<EnvironmentNode>(lcm, std::move(log), protocol);
  if (p == "eye") return std::make_unique<EyeNode>(lcm, std::move(log), protocol, /*speculate=*/!options.single_thread);
  if (p == "predictors")
    return std::make_unique<PredictorsNode>(lcm, std::move(log), protocol, /*async_effects=*/!options.single_thread,
                                            options.log_root);
  if (p == "motivation") return std::make_unique<MotivationNode>(lcm, std::move(log), protocol);
  if (p == "planner") return std::make_unique<PlannerNode>(lcm, std::move(log), protocol, options.planner_observer);
  if (p == "logger") return std::make_unique<LoggerNode>(lcm, std::move(log), protocol, options.log_root);
  std::string known;
  for (const ProcessInfo& info : processRegistry()) known += (known.empty() ? "" : ", ") + std::string(info.name);
  throw std::invalid_argument("unknown process \"" + p + "\" (" + known + ")");
}
}  // namespace

std::unique_ptr<NodeBase> makeNode(const std::string& p, lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log,
                                   const ProtocolConfig& protocol, const HostOptions& options) {
  std::unique_ptr<NodeBase> node = newNode(p, lcm, std::move(log), protocol, options);
  node->keepSnapshotsIn(options.snapshot_root);  // its peers then hold only what followed its latest one
  node->forkSnapshots(options.fork_snapshots);
  node->leaveFailuresToRunner(options.runner_says_failures);
  return node;
}

std::string inputRulesTable(const std::string& config_dir) {
  lcm::LCM bus("memq://");
  const ProtocolConfig protocol = loadProtocol(config_dir);
  auto quiet = std::make_shared<spdlog::logger>("rules", std::make_shared<spdlog::sinks::null_sink_mt>());
  std::string out = "| process | takes | when |\n|---|---|---|\n";
  for (const ProcessInfo& p : processRegistry()) {
    const std::unique_ptr<NodeBase> node = makeNode(p.name, bus, quiet, protocol, HostOptions{true, "", nullptr, ""});
    for (const NodeBase::InputRule& r : node->rules())
      out += std::string("| ") + p.name + " | `" + r.channel + "` | " + r.rule + " |\n";
  }
  return out;
}

InProcessHost::InProcessHost(lcm::LCM& lcm, const ProtocolConfig& protocol, LoggerFactory logger, HostOptions options)
    : lcm_(lcm), protocol_(protocol), logger_(std::move(logger)), options_(std::move(options)) {}

void InProcessHost::start(const std::vector<std::string>& processes) {
  for (const auto& p : processes) start(p);
}

void InProcessHost::start(const std::string& process) {
  auto& slot = nodes_[process];
  slot.reset();  // the old node unsubscribes before the new one subscribes
  slot = makeNode(process, lcm_, logger_(process), protocol_, options_);
  if (std::find(order_.begin(), order_.end(), process) == order_.end()) order_.push_back(process);
}

NodeBase& InProcessHost::node(const std::string& process) const {
  const auto it = nodes_.find(process);
  if (it == nodes_.end()) throw std::invalid_argument("process \"" + process + "\" is not hosted");
  return *it->second;
}

void InProcessHost::tick() {
  for (const auto& p : order_) nodes_.at(p)->tick();
}

bool InProcessHost::inRun() const {
  return std::any_of(nodes_.begin(), nodes_.end(), [](const auto& n) { return !n.second->runId().empty(); });
}

}  // namespace afford

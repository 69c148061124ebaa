// The life of a process around its node (docs/processes-and-channels.md):
// the shared command line (--lcm-url, --bus-key, --log-level, --config-dir
// and a process's own flags), the bus opened with its bounds, the loop that
// pumps it and ticks the node until SIGINT or SIGTERM, and an orderly
// shutdown; and what a program needs to find afford's files.
#pragma once
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <functional>
#include <memory>
#include <string>

#include "afford/config.hpp"
#include "afford/node.hpp"

namespace afford {

// The main() of every process: flags (--lcm-url, --log-level, --config-dir,
// --bus-key, plus extras), the node, the loop on handleTimeout until
// SIGINT/SIGTERM, orderly shutdown.
struct ProcessSpec {
  std::string name;         // "eye"
  std::string description;  // one line for --help
  // Snapshots written by a forked copy of the process (NodeBase::forkSnapshots); not in a process that runs
  // Python code.
  bool fork_snapshots = true;
};
class CLIHook;
int processMain(int argc, char** argv, const ProcessSpec& spec, const std::function<void(CLIHook&)>& add_options,
                const std::function<std::unique_ptr<NodeBase>(lcm::LCM&, std::shared_ptr<spdlog::logger>,
                                                              const ProtocolConfig&)>& make_node);

// Lets a process add its own flags to the shared command line.
class CLIHook {
 public:
  explicit CLIHook(void* app) : app_(app) {}
  void option(const std::string& name, std::string& target, const std::string& help);

 private:
  void* app_;
};

// The folder of afford's shared files beside the running executable, as
// `cmake --install` lays them out (<prefix>/bin/afford, <prefix>/share/afford:
// config/, docs/, java/, scripts/), or "" when the executable runs from a
// build tree.
std::string installedShareDir();
// The folder of defaults.yaml (--config-dir's default): an installed copy's
// share/afford/config, else the source tree's config/.
std::string defaultConfigDir();

// Where runs' folders go when a process is not told (the logger's --log-dir, the predictors'
// --checkpoint-dir): $AFFORD_LOGS if set (as scripts/procs.sh sets it), else "logs".
std::string defaultLogRoot();

// Large transient buffers (LCM's reassembly of fragmented messages) go back to
// the kernel when freed, so a flood of them does not stay resident.
void boundHeapGrowth();

// Set by SIGINT/SIGTERM.
bool stopRequested();
void installStopHandlers();
// Forget a stop request (a host that goes on after an interrupted run: the Python package).
void clearStopRequest();
// Stop as a SIGINT or SIGTERM would (stopRequested() becomes true), asked by the program itself.
void requestStop();
// ... saying why (the first reason given is kept: stopReason()). clearStopRequest() forgets it.
void requestStop(const std::string& why);
std::string stopReason();

}  // namespace afford

#include "afford/process_main.hpp"

#include <CLI/CLI.hpp>
#include <malloc.h>
#include <opencv2/core.hpp>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "afford/auth.hpp"
#include "afford/version.hpp"
#include "afford/bus.hpp"
#include "afford/logging.hpp"

namespace afford {

namespace {
volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }
std::mutex g_reason_mutex;
std::string g_reason;  // why the program asked to stop ("": it did not say)
}  // namespace

bool stopRequested() { return g_stop != 0; }
void clearStopRequest() {
  g_stop = 0;
  std::lock_guard<std::mutex> lock(g_reason_mutex);
  g_reason.clear();
}
void requestStop() { g_stop = 1; }
void requestStop(const std::string& why) {
  {
    std::lock_guard<std::mutex> lock(g_reason_mutex);
    if (g_reason.empty()) g_reason = why;
  }
  g_stop = 1;
}
std::string stopReason() {
  std::lock_guard<std::mutex> lock(g_reason_mutex);
  return g_reason;
}
void installStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void boundHeapGrowth() {
  // LCM assembles a fragmented message in one buffer of its size and frees it
  // once the edge has dropped or taken it. glibc raises its mmap threshold after
  // each such free, so later large buffers come from the heap and stay
  // resident; a fixed threshold sends every block of 128 KB or more back to the
  // kernel as soon as it is freed (docs/processes-and-channels.md).
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  mallopt(M_TRIM_THRESHOLD, 256 * 1024);
}

void CLIHook::option(const std::string& name, std::string& target, const std::string& help) {
  static_cast<CLI::App*>(app_)->add_option(name, target, help)->capture_default_str();
}

int processMain(int argc, char** argv, const ProcessSpec& spec, const std::function<void(CLIHook&)>& add_options,
                const std::function<std::unique_ptr<NodeBase>(lcm::LCM&, std::shared_ptr<spdlog::logger>,
                                                              const ProtocolConfig&)>& make_node) {
  CLI::App app{spec.description, "afford-" + spec.name};
  app.set_version_flag("--version", "afford-" + spec.name + " " + affordVersion());
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::string level = "info";
  std::string config_dir = defaultConfigDir();
  std::string key_file;
  std::string state_dir = defaultLogRoot();
  app.add_option("--lcm-url", url, "LCM provider URL of the run (one UDP port per run)")->capture_default_str();
  app.add_option("--bus-key", key_file,
                 "key file of a keyed bus (default: the file $AFFORD_BUS_KEY names; none: messages untagged)");
  app.add_option("--log-level", level, "trace, debug, info, warn, error or off")->capture_default_str();
  app.add_option("--config-dir", config_dir, "folder whose defaults.yaml gives the protocol used between runs")
      ->capture_default_str();
  app.add_option("--state-dir", state_dir,
                 "folder of the process's snapshots in a run (<folder>/<run-id>/<process>.snapshot), which a "
                 "restart goes on from; default $AFFORD_LOGS, else logs")
      ->capture_default_str();
  CLIHook hook(&app);
  add_options(hook);
  CLI11_PARSE(app, argc, argv);

  std::shared_ptr<spdlog::logger> log;
  try {
    log = makeLogger(spec.name, level);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "afford-%s: --log-level: %s\n", spec.name.c_str(), e.what());
    return 2;
  }
  ProtocolConfig protocol;
  try {
    protocol = loadProtocol(config_dir);
  } catch (const std::exception& e) {
    log->error("--config-dir: {}", e.what());
    return 2;
  }
  std::shared_ptr<const BusKey> key;
  try {
    key = busKeyFrom(key_file);
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 2;
  }
  installStopHandlers();
  boundHeapGrowth();
  // Log lines are written once per pass of the loop, not one write each: a
  // flood of bad messages is a flood of lines.
  static char log_buffer[1 << 16];
  std::setvbuf(stderr, log_buffer, _IOFBF, sizeof log_buffer);
  cv::setNumThreads(0);  // images are 150 x 150: a thread pool only adds wake-ups
  std::unique_ptr<lcm::LCM> bus;
  try {
    bus = openBus(url, protocol.bus);
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
  lcm::LCM& lcm = *bus;
  std::unique_ptr<NodeBase> node;
  try {
    node = make_node(lcm, log, protocol);
  } catch (const std::exception& e) {
    log->error("cannot start: {}", e.what());
    return 1;
  }
  node->useBusKey(key);
  node->keepSnapshotsIn(state_dir);
  node->forkSnapshots(spec.fork_snapshots);
  log->info("listening on {}{}", url, key ? " (keyed: messages without this key's tag are dropped)" : "");
  while (!stopRequested()) {
    // Everything pending (or what comes before the node's next business), then that business.
    pumpBus(lcm, node->msUntilDue());
    try {
      node->tick();
    } catch (const std::exception& e) {
      log->error("{}", e.what());
    }
    std::fflush(stderr);  // the log lines of the burst, in one write
  }
  if (!node->refusal().empty()) {
    // Another copy serves the bus: this one leaves as it came, writing nothing (no snapshot of a run it may have
    // joined: the copy that serves it keeps its own).
    log->info("stopped without serving (another copy of {} serves this bus)", spec.name);
    std::fflush(stderr);
    return 1;
  }
  node->leaveRun();
  const EdgeDrops drops = node->drops();
  node.reset();
  log->info("stopped; {} messages dropped at the edge{}", drops.refused + drops.untagged + drops.replayed,
            key ? " (" + std::to_string(drops.untagged) + " without a valid tag, " + std::to_string(drops.replayed) +
                      " said again)"
                : std::string());
  return 0;
}

}  // namespace afford

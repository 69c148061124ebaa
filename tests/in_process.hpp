// The whole choreography hosted in one process over memq:// (the same node
// code as the real processes), driven by the runner's RunDriver: what the
// choreography and node-alone tests record and compare.
#pragma once
#include <spdlog/sinks/ostream_sink.h>

#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "afford/protocol.hpp"
#include "experiment/run/driver.hpp"
#include "afford/focus_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/seal.hpp"
#include "experiment/run/host.hpp"
#include "afford/processes.hpp"
#include "tests/support.hpp"

namespace afford::test {

// The folder the hosted predictors read checkpoints from (as --checkpoint-dir
// gives it to the process): the tests' checkpoints are in tempDir folders.
inline std::string checkpointRoot() { return std::filesystem::temp_directory_path().string(); }

// A node of the named process on `lcm`, as the executables run it (threads of its own).
inline std::unique_ptr<NodeBase> makeNode(const std::string& p, lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log,
                                          const ProtocolConfig& protocol) {
  return afford::makeNode(p, lcm, std::move(log), protocol, HostOptions{/*single_thread=*/false, checkpointRoot(), nullptr, ""});
}

// Publishes something malformed into a running run: (lcm, run id, current
// step, the bytes of that step's real FOCUS).
using Bytes = std::vector<std::uint8_t>;
using Injector = std::function<void(lcm::LCM&, const std::string&, std::int64_t, const Bytes&)>;

// A process "killed" (its node destroyed, with whatever was in flight to it)
// and started anew, once it has handled step `at`.
struct Restart {
  std::string process;  // empty: none
  std::int64_t at = 0;
  std::string snapshots;  // the nodes' snapshot folder (HostOptions::snapshot_root); "": none
  bool graceful = false;  // it leaves the run first, as on SIGINT or SIGTERM (else: killed, as by SIGKILL)
  bool fork = false;      // snapshots written by a forked copy of this process (HostOptions::fork_snapshots)
};

struct InProcessRun {
  std::ostringstream log;
  std::vector<Event> events;
  RunOutcome outcome;
  bool restarted = false;
  std::int64_t restarted_at = -1;  // the last step the killed node had handled
  std::int64_t restored_step = -1; // the step of the snapshot the restarted node went on from (-1: none)

  InProcessRun(const std::string& yaml, System system, std::int64_t seed, std::int64_t steps, const Injector& inject = {},
               std::int64_t inject_at = 50, bool leave_stale_run = false, const Restart& restart = {},
               double stall_seconds = 20) {
    lcm::LCM lcm("memq://");
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
    auto logger = [&](const std::string& name) {
      auto l = std::make_shared<spdlog::logger>(name, sink);
      l->set_pattern("[%n] %v");
      l->set_level(spdlog::level::info);
      return l;
    };
    const ProtocolConfig protocol = shippedProtocol();
    // Both deciders: the run's configuration says which one decides.
    InProcessHost host(lcm, protocol, logger,
                       HostOptions{/*single_thread=*/false, checkpointRoot(), nullptr, restart.snapshots, restart.fork});
    host.start(runProcesses(Phase::Intrinsic, /*recorded=*/false));
    host.start("planner");
    RunDriver driver(lcm, logger("runner"), protocol);
    struct Tap {
      InProcessRun* run;
      lcm::LCM* lcm;
      Injector inject;
      std::int64_t at;
      bool done = false;
      void on(const lcm::ReceiveBuffer* b, const std::string& ch) {
        if (ch == ch::status.name) return;
        const auto* d = static_cast<const std::uint8_t*>(b->data);
        run->events.push_back({ch, std::vector<std::uint8_t>(d, d + b->data_size)});
        if (inject && !done && ch == ch::focus.name) {
          focus_t f;
          f.decode(b->data, 0, static_cast<int>(b->data_size));
          if (f.step == at) {
            done = true;
            inject(*lcm, f.run_id, f.step, run->events.back().data);
          }
        }
      }
    } tap{this, &lcm, inject, inject_at};
    lcm.subscribe(".*", &Tap::on, &tap)->setQueueCapacity(100000);
    RunSpec spec;
    spec.run_id = "test-run";
    spec.experiment = YAML::Load(yaml)["experiment"].as<std::string>();
    spec.system = toString(system);
    spec.seed = seed;
    spec.steps = steps;
    spec.config_yaml = yaml;
    spec.phase = Phase::Intrinsic;  // read as it is written: a test may give a configuration the runner refuses
    for (const auto& [name, phase] : kPhaseNames)
      if (YAML::Load(yaml)["phase"].as<std::string>() == name) spec.phase = phase;
    spec.extrinsic = spec.phase == Phase::Extrinsic;
    spec.processes = runProcesses(spec.phase, /*recorded=*/false);
    spec.stall_seconds = stall_seconds;
    auto maybeRestart = [&] {
      if (restart.process.empty() || restarted) return;
      const NodeBase& v = host.node(restart.process);
      if (v.runId() != spec.run_id || v.lastStep() < restart.at) return;
      restarted_at = v.lastStep();
      if (restart.graceful) host.node(restart.process).leaveRun();
      host.start(restart.process);  // the old node unsubscribes: what was queued for it is lost, as in a kill
      restarted = true;
    };
    auto pump = [&] {
      while (lcm.handleTimeout(0) > 0) maybeRestart();  // one message at a time
      lcm.handleTimeout(2);
      host.tick();
    };
    if (leave_stale_run) {
      // The processes take an earlier run whose STOP never comes (a lost datagram).
      run_config_t stale;
      stale.run_id = "stale-run";
      stale.step = 0;
      stale.request = 1;
      stale.seed = seed;
      stale.experiment = spec.experiment;
      stale.system = spec.system;
      stale.config_yaml = yaml;
      const auto bytes = sealed(stale);
      lcm.publish(ch::runConfig.name, bytes.data(), static_cast<unsigned>(bytes.size()));
      for (int i = 0; i < 50; ++i) pump();
    }
    outcome = driver.run(spec, pump, [] { return std::string(); });
    if (restarted) restored_step = host.node(restart.process).restoredStep();
    // The STOP the runner sent, and what the processes publish on it, into `events`.
    for (int i = 0; i < 500 && host.inRun(); ++i) pump();
  }

  int count(const std::string& channel) const {
    int n = 0;
    for (const auto& e : events) n += e.channel == channel;
    return n;
  }
};

inline std::string baseYaml(System s, std::int64_t steps, std::int64_t seed = 3) {
  return shippedConfigYaml("base", s, seed, steps);
}

}  // namespace afford::test

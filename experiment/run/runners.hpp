// The runner on its bus, beside the processes (docs/processes-and-channels.md,
// "Copies of a process, and runners"): while it drives a run it beats, as
// process "runner" on STATUS (its pid, host, start, run, request and what it
// waits for), so that `afford status` shows it and another runner hears it.
// Of two runners that hear each other (each names the other in its beat), the
// later started refuses at once; a runner tells no process to leave another
// run before it has listened long enough to have heard any runner driving it.
// Of a process's copies, one that an earlier copy names refuses to serve: the
// runner gives it nothing; two copies in its run that do not hear each other
// fail the run, naming both.
// Channels in:  STATUS (through the driver's edge)
// Channels out: STATUS (the runner's beat)
#pragma once
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "afford/config.hpp"
#include "afford/edge.hpp"
#include "afford/edge_peers.hpp"

namespace afford {

// The name a runner's beat goes by (not a process of a run: afford/processes.hpp).
inline constexpr const char* kRunnerName = "runner";

class RunnerBeat {
 public:
  using Clock = std::chrono::steady_clock;
  RunnerBeat(Edge& edge, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol);

  // A STATUS heard: a runner's (true: nothing else is to be taken from it), or a process's (its instance noted).
  bool heard(const process_status_t& m);
  // Is it a copy of a process that refuses to serve (an earlier copy of its name names it)? Said once each.
  bool refusingCopy(const process_status_t& m);
  // Is it a process free while another instance of its name served the run (`run_id`, `request`) within the
  // last heartbeat? Then it is more likely a copy than that one restarted: the run is not given to it until
  // the other has been silent for a heartbeat (a live copy names it before, and it refuses).
  bool anotherServes(const process_status_t& m, const std::string& run_id, std::int64_t request) const;
  // Why this runner must not drive the bus: another runner, started earlier, drives it ("" while none does).
  const std::string& refusal() const { return refusal_; }
  // Two copies of one of `processes` in the run (`run_id`, `request`) that do not hear each other, or "".
  std::string mixed(const std::string& run_id, std::int64_t request, const std::vector<std::string>& processes) const;
  // May it tell a process to leave another run (another runner's, perhaps)? Only once it has listened for two
  // heartbeats since its first beat, and since it first heard an earlier runner that has not answered it.
  bool settled() const;

  // What the beat says.
  struct Doing {
    std::string run_id;
    std::int64_t request = 0;  // the digest of its RUN_CONFIG
    std::int64_t step = -1;    // the last step a process of the run reported
    std::string detail;        // what it waits for
  };
  // Is a beat due: the heartbeat, a runner heard anew, or `stage` (the driver's) changed?
  bool due(int stage) const;
  void beat(int stage, const Doing& doing);

 private:
  Clock::duration live() const { return 3 * std::chrono::milliseconds(protocol_->heartbeat_ms); }

  Edge& edge_;
  std::shared_ptr<spdlog::logger> log_;
  const ProtocolConfig* protocol_;
  Copies runners_;      // the other runners heard; who this one is
  Instances processes_; // the processes' instances heard (their copies)
  std::int64_t forgotten_ = 0;
  std::int64_t beats_ = 0;
  Clock::time_point next_{};       // the next heartbeat (none yet: due at once)
  Clock::time_point quiet_from_{}; // settled two heartbeats after this
  bool beaten_ = false;
  bool answer_ = false;            // a runner heard anew: beat at once (it learns it is heard)
  int stage_ = -1;                 // the stage of the last beat
  std::string run_;                // the run of the last beat, its request and the furthest step said of it
  std::int64_t request_ = 0;
  std::int64_t step_ = -1;
  std::string refusal_;
  std::set<std::string> said_;     // copies already said
};

}  // namespace afford

// The registry of the project's processes: each one's name and the phases it
// takes part in; the run channels it publishes come from the protocol
// (afford/protocol.hpp). Every list of processes or channels (who runs in a
// phase, who publishes a channel, what a replayed process answers on,
// `afford processes` for the scripts) derives from the two.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "afford/phase.hpp"

namespace afford {

struct ProcessInfo {
  const char* name;
  std::array<bool, kPhases> phases;  // takes part in each phase (intrinsic, extrinsic, goals)
  bool recorder;    // takes part only in recorded runs (the logger)
  std::vector<const char*> publishes;  // run channels it publishes in its phases (STATUS aside: every process says it)
  const char* summary;

  bool in(Phase phase) const { return phases[static_cast<std::size_t>(phase)]; }
};

// Every process, in the order they are listed and started.
const std::vector<ProcessInfo>& processRegistry();

// The processes of a run of that phase, the logger last if the run is recorded.
std::vector<std::string> runProcesses(Phase phase, bool recorded);

// The publisher of each run channel (one per channel and phase); "" for others.
std::string publisherOf(const std::string& channel, Phase phase);

// One of the project's processes?
bool isProcessName(const std::string& name);

// What a process publishes in that phase, STATUS included (empty for an unknown name).
std::vector<std::string> channelsOf(const std::string& process, Phase phase);

}  // namespace afford

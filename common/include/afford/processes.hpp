// The registry of the project's processes: each one's name and the phases it
// takes part in; the run channels it publishes come from the protocol
// (afford/protocol.hpp). Every list of processes or channels (who runs in a
// phase, who publishes a channel, what a replayed process answers on,
// `afford processes` for the scripts) derives from the two.
#pragma once
#include <string>
#include <vector>

namespace afford {

struct ProcessInfo {
  const char* name;
  bool intrinsic;   // takes part in the intrinsic phase
  bool extrinsic;   // ... in the extrinsic phase
  bool recorder;    // takes part only in recorded runs (the logger)
  std::vector<const char*> publishes;  // run channels it publishes in its phases (STATUS aside: every process says it)
  const char* summary;
};

// Every process, in the order they are listed and started.
const std::vector<ProcessInfo>& processRegistry();

// The processes of a run of that phase, the logger last if the run is recorded.
std::vector<std::string> runProcesses(bool extrinsic, bool recorded);

// The publisher of each run channel (one per channel and phase); "" for others.
std::string publisherOf(const std::string& channel, bool extrinsic);

// One of the project's processes?
bool isProcessName(const std::string& name);

// What a process publishes in that phase, STATUS included (empty for an unknown name).
std::vector<std::string> channelsOf(const std::string& process, bool extrinsic);

}  // namespace afford

#include "afford/processes.hpp"

#include "afford/channels.hpp"

namespace afford {

const std::vector<ProcessInfo>& processRegistry() {
  using namespace channel;
  static const std::vector<ProcessInfo> registry = {
      {"environment", true, true, false, {kScene, kProbe}, "the world: scene, objects, actions"},
      {"eye", true, true, false, {kFocus, kEffect}, "attention and perception: focus, effects"},
      {"predictors", true, true, false, {kPrediction, kAffordanceTable, kResult, kForwardPrediction},
       "affordance and forward models"},
      {"motivation", true, false, false, {kDecision}, "intrinsic motivations: chooses the action (intrinsic phase)"},
      {"planner", false, true, false, {kLook, kForwardQuery, kDecision, kExtrinsicResult},
       "attention to the goal and planning (extrinsic phase)"},
      {"logger", true, true, true, {}, "records a run into an LCM log"},
  };
  return registry;
}

std::vector<std::string> runProcesses(bool extrinsic, bool recorded) {
  std::vector<std::string> out;
  for (const ProcessInfo& p : processRegistry())
    if ((extrinsic ? p.extrinsic : p.intrinsic) && (!p.recorder || recorded)) out.emplace_back(p.name);
  return out;
}

std::string publisherOf(const std::string& channel, bool extrinsic) {
  for (const ProcessInfo& p : processRegistry()) {
    if (!(extrinsic ? p.extrinsic : p.intrinsic)) continue;
    for (const char* c : p.publishes)
      if (channel == c) return p.name;
  }
  return "";
}

bool isProcessName(const std::string& name) {
  for (const ProcessInfo& p : processRegistry())
    if (name == p.name) return true;
  return false;
}

std::vector<std::string> channelsOf(const std::string& process, bool extrinsic) {
  std::vector<std::string> out;
  for (const ProcessInfo& p : processRegistry())
    if (process == p.name && (extrinsic ? p.extrinsic : p.intrinsic)) {
      out.assign(p.publishes.begin(), p.publishes.end());
      out.emplace_back(channel::kStatus);
    }
  return out;
}

}  // namespace afford

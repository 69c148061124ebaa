#include "afford/processes.hpp"

#include "afford/protocol.hpp"

namespace afford {

const std::vector<ProcessInfo>& processRegistry() {
  static const std::vector<ProcessInfo> registry = [] {
    std::vector<ProcessInfo> r = {
        {"environment", {true, true, true}, false, {}, "the world: scene, objects, actions"},
        {"eye", {true, true, true}, false, {}, "attention and perception: focus, effects"},
        {"predictors", {true, true, true}, false, {}, "affordance and forward models"},
        {"motivation", {true, false, true}, false, {},
         "intrinsic motivations: chooses the action (intrinsic phase) or the goal (goals phase)"},
        {"planner", {false, true, true}, false, {},
         "attention to the goal and planning (extrinsic phase; goals phase: the agent's own goals)"},
        {"logger", {true, true, true}, true, {}, "records a run into an LCM log"},
    };
    // What each publishes: the run channels (afford/protocol.hpp) whose publisher it is in a phase it is in.
    for (ProcessInfo& p : r)
      forEachChannel([&](const ChannelInfo& c) {
        bool mine = false;
        for (std::size_t i = 0; i < kPhases; ++i) mine = mine || (p.phases[i] && std::string(c.publishers[i]) == p.name);
        if (c.serial && mine) p.publishes.push_back(c.name);
      });
    return r;
  }();
  return registry;
}

std::vector<std::string> runProcesses(Phase phase, bool recorded) {
  std::vector<std::string> out;
  for (const ProcessInfo& p : processRegistry())
    if (p.in(phase) && (!p.recorder || recorded)) out.emplace_back(p.name);
  return out;
}

std::string publisherOf(const std::string& channel, Phase phase) {
  const ChannelInfo* c = channelNamed(channel);
  if (!c || !c->serial) return "";
  const std::string p = c->publisher(phase);
  return isProcessName(p) ? p : "";
}

bool isProcessName(const std::string& name) {
  for (const ProcessInfo& p : processRegistry())
    if (name == p.name) return true;
  return false;
}

std::vector<std::string> channelsOf(const std::string& process, Phase phase) {
  std::vector<std::string> out;
  for (const ProcessInfo& p : processRegistry())
    if (process == p.name && p.in(phase)) {
      forEachChannel([&](const ChannelInfo& c) {
        if (c.serial && process == c.publisher(phase)) out.emplace_back(c.name);
      });
      out.emplace_back(ch::status.name);
    }
  return out;
}

}  // namespace afford

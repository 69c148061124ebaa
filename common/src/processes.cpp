#include "afford/processes.hpp"

#include "afford/protocol.hpp"

namespace afford {

const std::vector<ProcessInfo>& processRegistry() {
  static const std::vector<ProcessInfo> registry = [] {
    std::vector<ProcessInfo> r = {
        {"environment", true, true, false, {}, "the world: scene, objects, actions"},
        {"eye", true, true, false, {}, "attention and perception: focus, effects"},
        {"predictors", true, true, false, {}, "affordance and forward models"},
        {"motivation", true, false, false, {}, "intrinsic motivations: chooses the action (intrinsic phase)"},
        {"planner", false, true, false, {}, "attention to the goal and planning (extrinsic phase)"},
        {"logger", true, true, true, {}, "records a run into an LCM log"},
    };
    // What each publishes: the run channels (afford/protocol.hpp) whose publisher it is in a phase it is in.
    for (ProcessInfo& p : r)
      forEachChannel([&](const ChannelInfo& c) {
        const bool mine = (p.intrinsic && std::string(c.intrinsic_publisher) == p.name) ||
                          (p.extrinsic && std::string(c.extrinsic_publisher) == p.name);
        if (c.serial && mine) p.publishes.push_back(c.name);
      });
    return r;
  }();
  return registry;
}

std::vector<std::string> runProcesses(bool extrinsic, bool recorded) {
  std::vector<std::string> out;
  for (const ProcessInfo& p : processRegistry())
    if ((extrinsic ? p.extrinsic : p.intrinsic) && (!p.recorder || recorded)) out.emplace_back(p.name);
  return out;
}

std::string publisherOf(const std::string& channel, bool extrinsic) {
  const ChannelInfo* c = channelNamed(channel);
  if (!c || !c->serial) return "";
  const std::string p = c->publisher(extrinsic);
  return isProcessName(p) ? p : "";
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
      out.emplace_back(ch::status.name);
    }
  return out;
}

}  // namespace afford

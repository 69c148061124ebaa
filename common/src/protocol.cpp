#include "afford/protocol.hpp"

#include <algorithm>

#include "afford/config.hpp"

namespace afford {

const ChannelInfo* channelNamed(const std::string& name) {
  const ChannelInfo* out = nullptr;
  forEachChannel([&](const ChannelInfo& c) {
    if (!out && name == c.name) out = &c;
  });
  return out;
}

std::vector<std::string> channelNames(bool serial_only) {
  std::vector<std::string> out;
  forEachChannel([&](const ChannelInfo& c) {
    if (!serial_only || c.serial) out.emplace_back(c.name);
  });
  return out;
}

bool isSerialChannel(const std::string& name) {
  const ChannelInfo* c = channelNamed(name);
  return c && c->serial;
}

namespace {
std::string code(const char* s) { return std::string("`") + s + "`"; }
// A publisher or reader in words: a process by its name, the others as they are.
std::string who(const char* s) {
  const std::string w = s;
  return w == kRunner ? "the runner (`afford`)" : w;
}
}  // namespace

std::string protocolTable() {
  std::string out = "| channel | type | published by | read by | recorded | when |\n|---|---|---|---|---|---|\n";
  forEachChannel([&](const ChannelInfo& c) {
    // One publisher in every phase: its name; otherwise each publisher with the phases it publishes in.
    std::string by;
    bool same = true;
    for (const char* p : c.publishers) same = same && std::string(p) == c.publishers[0];
    if (same) {
      by = who(c.publishers[0]);
    } else {
      std::vector<std::string> seen;
      for (std::size_t i = 0; i < kPhases; ++i) {
        const std::string p = c.publishers[i];
        if (p.empty() || std::find(seen.begin(), seen.end(), p) != seen.end()) continue;
        seen.push_back(p);
        std::string phases;
        for (std::size_t j = i; j < kPhases; ++j)
          if (p == c.publishers[j]) phases += (phases.empty() ? "" : ", ") + std::string(kPhaseNames[j].name);
        by += (by.empty() ? "" : "; ") + who(p.c_str()) + " (" + phases + ")";
      }
    }
    std::string readers;
    for (const char* r : c.readers)
      if (r) readers += (readers.empty() ? "" : ", ") + who(r);
    out += "| " + code(c.name) + " | " + code(c.type) + " | " + by + " | " + readers + " | " +
           (c.recorded ? "yes" : "no") + " | " + c.when + " |\n";
  });
  return out;
}

}  // namespace afford

#include "afford/protocol.hpp"

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
    std::string by = who(c.intrinsic_publisher);
    if (std::string(c.intrinsic_publisher) != c.extrinsic_publisher) {
      by = (*c.intrinsic_publisher ? who(c.intrinsic_publisher) + " (intrinsic)" : std::string());
      if (*c.extrinsic_publisher) by += (by.empty() ? "" : ", ") + who(c.extrinsic_publisher) + " (extrinsic)";
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

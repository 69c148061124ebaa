#include "experiment/execute/bus_note.hpp"

#include <fstream>

#include "experiment/run/outcome.hpp"
#include "experiment/schema/codec.hpp"

namespace afford {

std::vector<std::string> slotUrls(const HostRequest& o) {
  std::vector<std::string> urls;
  for (int k = 0; k < o.jobs; ++k)
    // A 2 MB receive buffer per socket (the kernel's default is 208 KB): every process hears every
    // datagram of its slot, and one descheduled for a while must not lose any (the kernel caps the
    // request at net.core.rmem_max).
    urls.push_back(!o.attach.empty() ? o.attach
                                     : "udpm://239.255.76.67:" + std::to_string(o.base_port + k) +
                                           "?ttl=0&recv_buf_size=2097152");
  return urls;
}

std::filesystem::path busNotePath(const std::filesystem::path& out_dir) { return out_dir / "bus.json"; }

void writeBusNote(const std::filesystem::path& out_dir, const BusNote& note) {
  writeWhole(busNotePath(out_dir), toJsonOf(note).dump(2) + "\n");
}

BusNote readBusNote(const std::filesystem::path& out_dir) {
  const auto file = busNotePath(out_dir);
  std::error_code ec;
  if (!std::filesystem::exists(file, ec))
    throw std::runtime_error("no " + file.string() + ": no experiment has run its processes there yet");
  try {  // (a FIFO or a huge file in its place is refused, not waited on or held)
    return fromJsonOf<BusNote>(readJsonFile(file, 1u << 20), file.string());
  } catch (const std::exception& e) {
    throw std::runtime_error(file.string() + " does not read: " + e.what());
  }
}

}  // namespace afford

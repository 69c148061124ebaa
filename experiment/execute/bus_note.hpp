// Where a running experiment's runs are heard: the bus of each job slot, and
// DIR/bus.json, which says so to `afford watch --out DIR` (the runner's pid,
// whose network namespace the buses are in, the slots' URLs, the key file).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "experiment/execute/request.hpp"

namespace afford {

// The bus of each job slot: port base_port + k (or the --attach URL).
std::vector<std::string> slotUrls(const HostRequest& o);

struct BusNote {
  long long pid = 0;               // the runner: its network namespace is the buses'
  std::vector<std::string> urls;   // a bus per job slot
  std::string bus_key;             // the key file, absolute ("": an unkeyed bus)
  std::string experiment;
  template <class V>
  void visit(V& v) {
    v("pid", pid);
    v("urls", urls);
    v("bus_key", bus_key);
    v("experiment", experiment);
  }
};

// DIR/bus.json
std::filesystem::path busNotePath(const std::filesystem::path& out_dir);
// Written as the runs' network is entered, by the runner holding DIR's lock.
void writeBusNote(const std::filesystem::path& out_dir, const BusNote& note);
// Throws std::runtime_error naming the file if it is not there or does not read.
BusNote readBusNote(const std::filesystem::path& out_dir);

}  // namespace afford

// What runs now, as the files of a log root and an experiment folder say it: the kernel locks their holders
// keep for as long as they live, and a scripts/procs.sh group's pid files (afford clean, afford watch).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace afford {

// Someone holds a kernel lock on `path` (flock): tested by taking it, without waiting, and letting it go at
// once. `exclusive`: the test conflicts with a shared hold too. A lock that cannot be tested counts as held.
bool lockHeld(const std::filesystem::path& path, bool exclusive);

// The experiment folder's lock is held: its runner is running (experiment/state.hpp's OutDirLock).
bool experimentRunning(const std::filesystem::path& out_dir);

// A process of a scripts/procs.sh group that is alive: a pid file whose process has the start time recorded
// beside it (procs.sh's own test: pids are reused). By name.
struct GroupProcess {
  std::string name;
  long pid = 0;
};
std::vector<GroupProcess> groupAlive(const std::filesystem::path& dir);


// Runs that a watcher can follow: their buses, the key file, and a process whose network namespace the buses
// are in (afford watch enters it).
struct Watchable {
  std::string what;               // "experiment base in out/x", "group 'demo'"
  std::vector<std::string> urls;  // a bus per job slot
  std::string bus_key;            // the key file ("": unkeyed)
  long pid = 0;
};

// The experiment running in out_dir (its lock held; its bus.json). Throws std::runtime_error saying why not.
Watchable runningExperiment(const std::filesystem::path& out_dir);
// The scripts/procs.sh group NAME of the log root, with a process alive. Throws std::runtime_error saying why not.
Watchable runningGroup(const std::filesystem::path& log_root, const std::string& name);
// Every running experiment with a run folder in the log root, and every group there with a process alive; one
// entry per bus (a group's experiment run on its bus is the group).
std::vector<Watchable> runningIn(const std::filesystem::path& log_root);

}  // namespace afford

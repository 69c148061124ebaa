#include "apps/afford/commands/running.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "experiment/execute/bus_note.hpp"
#include "experiment/run/outcome.hpp"

namespace afford {
namespace fs = std::filesystem;

bool lockHeld(const fs::path& path, bool exclusive) {
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool held = flock(fd, (exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0;
  close(fd);
  return held;
}

bool experimentRunning(const fs::path& out_dir) { return lockHeld(out_dir / ".lock", /*exclusive=*/false); }

std::vector<GroupProcess> groupAlive(const fs::path& dir) {
  std::vector<GroupProcess> alive;
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(dir, ec)) {
    if (f.path().extension() != ".pid") continue;
    const auto pid_text = readSmallFile(f.path(), 64), started_text = readSmallFile(fs::path(f.path()).replace_extension(".started"), 64);
    if (!pid_text || !started_text) continue;
    std::istringstream pid_in(*pid_text), started_in(*started_text);
    long pid = 0;
    std::string started;
    if (!(pid_in >> pid) || pid <= 0 || !(started_in >> started)) continue;
    std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const auto close_paren = line.rfind(')');
    if (close_paren == std::string::npos) continue;
    std::istringstream fields(line.substr(close_paren + 2));
    std::vector<std::string> v{std::istream_iterator<std::string>(fields), {}};
    if (v.size() > 19 && v[0] != "Z" && v[19] == started) alive.push_back({f.path().stem().string(), pid});
  }
  std::sort(alive.begin(), alive.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return alive;
}


Watchable runningExperiment(const fs::path& out_dir) {
  std::error_code ec;
  if (!fs::is_directory(out_dir, ec)) throw std::runtime_error("--out " + out_dir.string() + ": no such folder");
  if (!experimentRunning(out_dir))
    throw std::runtime_error("no experiment runs in " + out_dir.string() +
                             " now (it finished, stopped or has not begun): `afford watch --log LOG` plays a run's log");
  const BusNote note = readBusNote(out_dir);
  return {"experiment " + note.experiment + " in " + out_dir.string(), note.urls, note.bus_key, note.pid};
}

Watchable runningGroup(const fs::path& log_root, const std::string& name) {
  const fs::path dir = log_root / name;
  const auto url_text = readSmallFile(dir / "lcm-url", 4096);
  std::istringstream url_in(url_text.value_or(""));
  std::string url;
  if (!std::getline(url_in, url) || url.empty())
    throw std::runtime_error("--group " + name + ": no scripts/procs.sh group '" + name + "' in " + log_root.string() +
                             " (no " + (dir / "lcm-url").string() + "; --log-root, or $AFFORD_LOGS, names another?)");
  const std::vector<GroupProcess> alive = groupAlive(dir);
  if (alive.empty())
    throw std::runtime_error("--group " + name + ": no process of the group runs (scripts/procs.sh start " + name + ")");
  std::error_code ec;
  const std::string key = fs::exists(dir / "bus.key", ec) ? fs::absolute(dir / "bus.key").string() : "";
  return {"group '" + name + "' (scripts/procs.sh)", {url}, key, alive.front().pid};
}

namespace {

// The network namespace of a process, as its device and inode ("" if it cannot be read).
std::string netnsOf(long pid) {
  struct stat st {};
  if (stat(("/proc/" + std::to_string(pid) + "/ns/net").c_str(), &st) != 0) return "";
  return std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
}

// The experiment folder a run folder's run.json names ("" if none).
std::string outDirOf(const fs::path& run_dir) {
  try {
    const nlohmann::json j = readJsonFile(run_dir / "run.json", 1u << 20);
    return j.is_object() && j.contains("out_dir") && j["out_dir"].is_string() ? j["out_dir"].get<std::string>() : "";
  } catch (const std::exception&) {
    return "";
  }
}

}  // namespace

std::vector<Watchable> runningIn(const fs::path& log_root) {
  std::vector<Watchable> found;
  std::set<std::string> buses, outs;  // (namespace, url) heard already; experiment folders looked at
  auto add = [&](Watchable w) {
    const std::string ns = netnsOf(w.pid);
    bool fresh = false;
    for (const std::string& u : w.urls) fresh = buses.insert(ns + " " + u).second || fresh;
    if (fresh) found.push_back(std::move(w));
  };
  std::error_code ec;
  std::vector<fs::path> dirs;
  for (const auto& d : fs::directory_iterator(log_root, ec))
    if (d.is_directory(ec) && d.path().filename().string().front() != '.') dirs.push_back(d.path());
  std::sort(dirs.begin(), dirs.end());
  for (const fs::path& d : dirs)  // groups first: an experiment run on a group's bus is the group's
    if (fs::exists(d / "lcm-url", ec) && !groupAlive(d).empty()) add(runningGroup(log_root, d.filename().string()));
  for (const fs::path& d : dirs) {
    const std::string out = outDirOf(d);
    if (out.empty() || !outs.insert(out).second || !experimentRunning(out) || !fs::exists(busNotePath(out), ec)) continue;
    try {
      add(runningExperiment(out));
    } catch (const std::exception&) {  // (it ended meanwhile, or wrote no note yet)
    }
  }
  return found;
}

}  // namespace afford

// afford clean: the folders of a log root (run logs and checkpoints, stored
// agents) chosen by age, size or experiment; a dry run unless --delete. Only
// what it can attribute is offered: a finished run's folder (its run.json or
// manifest.json says whose it is) whose experiment is not running, and a stored
// agent. A scripts/procs.sh group's folder, a run under way and anything it
// cannot attribute are left alone, and said.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "apps/afford/commands.hpp"
#include "afford/config.hpp"

namespace afford {
namespace fs = std::filesystem;

namespace {

enum class Kind { Run, Agent, Group, Unknown };

struct Entry {
  fs::path path;
  std::string label;       // run id, or agents/<key>
  std::string experiment;  // "?" if nothing in the folder says
  Kind kind = Kind::Unknown;
  std::string kept_because;  // why it is never removed ("" if it may be)
  std::uintmax_t bytes = 0;
  std::time_t modified = 0;  // the newest file in it
};

// A small JSON file of the folder (run.json, manifest.json, outcome.json), if it reads.
std::optional<nlohmann::json> smallJson(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec) || fs::file_size(file, ec) > (16u << 20)) return std::nullopt;
  std::ifstream in(file);
  try {
    return nlohmann::json::parse(in);
  } catch (const std::exception&) {
    return std::nullopt;  // an unreadable file says nothing about the folder; another one may
  }
}

// The experiment folder's lock is held: its runner is running (experiment/state.hpp's OutDirLock).
bool experimentRunning(const fs::path& out_dir) {
  const fs::path lock = out_dir / ".lock";
  const int fd = open(lock.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool held = flock(fd, LOCK_SH | LOCK_NB) != 0;
  close(fd);
  return held;
}

// The processes of a scripts/procs.sh group that are alive: a pid file whose process has the start
// time recorded beside it (procs.sh's own test: pids are reused).
std::vector<std::string> groupAlive(const fs::path& dir) {
  std::vector<std::string> alive;
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(dir, ec)) {
    if (f.path().extension() != ".pid") continue;
    std::ifstream pid_in(f.path()), started_in(fs::path(f.path()).replace_extension(".started"));
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
    if (v.size() > 19 && v[0] != "Z" && v[19] == started) alive.push_back(f.path().stem().string());
  }
  std::sort(alive.begin(), alive.end());
  return alive;
}

// What the folder is, and whether it may go.
void classify(Entry& e) {
  std::error_code ec;
  if (fs::exists(e.path / "lcm-url", ec) || fs::exists(e.path / "bus.key", ec)) {
    e.kind = Kind::Group;
    const std::vector<std::string> alive = groupAlive(e.path);
    std::string names;
    for (const auto& n : alive) names += (names.empty() ? "" : ", ") + n;
    e.kept_because = "a scripts/procs.sh group (" + (alive.empty() ? std::string("stopped") : "running: " + names) +
                     "); stop it and remove its folder yourself";
    return;
  }
  for (const char* name : {"run.json", "manifest.json", "outcome.json"}) {
    const auto j = smallJson(e.path / name);
    if (!j || !j->is_object() || !j->contains("experiment") || !(*j)["experiment"].is_string()) continue;
    e.experiment = (*j)["experiment"].get<std::string>();
    e.kind = e.label.rfind("agents/", 0) == 0 ? Kind::Agent : Kind::Run;
    if (j->contains("out_dir") && (*j)["out_dir"].is_string() && experimentRunning((*j)["out_dir"].get<std::string>()))
      e.kept_because = "its experiment is running (in " + (*j)["out_dir"].get<std::string>() + ")";
    return;
  }
  e.kept_because = "nothing in it says whose it is (a run under way, a cut run, or not afford's)";
}

Entry measure(const fs::path& dir, const std::string& label) {
  Entry e;
  e.path = dir;
  e.label = label;
  e.experiment = "?";
  classify(e);
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    struct stat st {};
    if (stat(it->path().c_str(), &st) != 0) continue;
    // A file linked from several folders (a run's checkpoint and its stored agent) counts a share in each.
    if (S_ISREG(st.st_mode)) e.bytes += static_cast<std::uintmax_t>(st.st_size) / std::max<nlink_t>(st.st_nlink, 1);
    e.modified = std::max(e.modified, st.st_mtime);
  }
  return e;
}

struct Args {
  std::string log_root = "logs";
  std::vector<std::string> experiments;
  double older_than_days = -1, larger_than_mb = -1, keep_under_mb = -1;
  bool all = false, remove = false;
};

// The folders of the log root: runs, stored agents, and whatever else is there (hidden ones aside).
std::vector<Entry> entriesOf(const std::string& log_root) {
  std::vector<Entry> entries;
  for (const auto& d : fs::directory_iterator(log_root)) {
    const std::string name = d.path().filename().string();
    if (!d.is_directory() || name.front() == '.') continue;  // .prefixes: the run prefixes taken
    if (name == "agents") {
      for (const auto& k : fs::directory_iterator(d.path()))
        if (k.is_directory()) entries.push_back(measure(k.path(), "agents/" + k.path().filename().string()));
    } else {
      entries.push_back(measure(d.path(), name));
    }
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
    return x.modified != y.modified ? x.modified < y.modified : x.label < y.label;
  });
  return entries;
}

int clean(const Args& a) {
  if (!a.all && a.older_than_days < 0 && a.larger_than_mb < 0 && a.experiments.empty() && a.keep_under_mb < 0)
    throw ConfigError("afford clean: choose folders with --older-than, --larger-than, --experiment, --keep-under or "
                      "--all");
  if (!fs::is_directory(a.log_root)) throw ConfigError("afford clean: no log root " + a.log_root);
  const std::vector<Entry> entries = entriesOf(a.log_root);
  const std::time_t now = std::time(nullptr);
  std::uintmax_t total = 0;
  for (const auto& e : entries) total += e.bytes;
  std::vector<const Entry*> chosen, left_alone;
  std::uintmax_t left = total;
  for (const auto& e : entries) {
    bool pick = a.all;
    if (a.older_than_days >= 0) pick = pick || difftime(now, e.modified) > a.older_than_days * 86400.0;
    if (a.larger_than_mb >= 0) pick = pick || e.bytes > a.larger_than_mb * 1e6;
    if (!a.experiments.empty())
      pick = pick || std::find(a.experiments.begin(), a.experiments.end(), e.experiment) != a.experiments.end();
    if (a.keep_under_mb >= 0) pick = pick || left > a.keep_under_mb * 1e6;  // oldest first
    if (!pick) continue;
    if (!e.kept_because.empty()) {
      left_alone.push_back(&e);
      continue;
    }
    chosen.push_back(&e);
    left -= e.bytes;
  }
  std::uintmax_t freed = 0;
  for (const Entry* e : chosen) {
    char when[32];
    std::strftime(when, sizeof when, "%Y-%m-%d %H:%M", std::localtime(&e->modified));
    std::printf("%s %10.1f MB  %s  %-16s %s\n", a.remove ? "removed" : "would remove", e->bytes / 1e6, when,
                e->experiment.c_str(), e->path.string().c_str());
    if (a.remove) fs::remove_all(e->path);
    freed += e->bytes;
  }
  for (const Entry* e : left_alone)
    std::printf("left alone   %10.1f MB  %s: %s\n", e->bytes / 1e6, e->path.string().c_str(), e->kept_because.c_str());
  if (a.remove && fs::is_directory(fs::path(a.log_root) / "agents") && fs::is_empty(fs::path(a.log_root) / "agents"))
    fs::remove(fs::path(a.log_root) / "agents");
  std::printf("%s %zu of %zu folder(s), %.1f MB of %.1f MB in %s%s\n", a.remove ? "removed" : "would remove",
              chosen.size(), entries.size(), freed / 1e6, total / 1e6, a.log_root.c_str(),
              a.remove || chosen.empty() ? "" : " (a dry run: --delete removes them)");
  return 0;
}

}  // namespace

Command cleanCommand(CLI::App& app, const FrontDoor&) {
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("clean", "list, then with --delete remove, the run folders and stored agents of a log "
                                          "root chosen by age, size or experiment (a dry run by default); a "
                                          "scripts/procs.sh group, a running experiment's runs and folders it "
                                          "cannot attribute are left alone");
  cmd->add_option("--log-root", a->log_root, "the log root (an experiment's --log-root)")->capture_default_str();
  cmd->add_option("--older-than", a->older_than_days, "folders last changed more than this many days ago")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--larger-than", a->larger_than_mb, "folders of more than this many MB")->check(CLI::NonNegativeNumber);
  cmd->add_option("--experiment", a->experiments, "folders of these experiments (repeatable)");
  cmd->add_option("--keep-under", a->keep_under_mb,
                  "the oldest folders, until what is left takes at most this many MB")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--all", a->all, "every folder");
  cmd->add_flag("--delete", a->remove, "remove them (without it, only list what would go)");
  return {cmd, [a] { return clean(*a); }};
}

}  // namespace afford

// afford clean: the folders of a log root (run logs and checkpoints, stored
// agents) chosen by age, size or experiment; a dry run unless --delete. Only
// what it can attribute and is not in use is offered: a run's folder (its
// run.json, written as the run starts, or its manifest.json says whose it is)
// whose experiment finished, and a stored agent. What is in use says so with a
// lock the kernel holds for as long as its holder lives, or in its
// experiment's state: a run going on (its experiment's lock), a log being
// written (the logger's lock on the folder), a run whose experiment stopped
// before it finished (--resume continues it), a study's trial, a
// scripts/procs.sh group. Those, and what it cannot attribute, are left alone,
// each with its reason.
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
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "experiment/run/outcome.hpp"
#include "apps/afford/commands.hpp"
#include "afford/config.hpp"
#include "experiment/state.hpp"
#include "apps/afford/commands/running.hpp"

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
  try {
    return readJsonFile(file, 16u << 20);
  } catch (const std::exception&) {
    return std::nullopt;  // an unreadable file says nothing about the folder; another one may
  }
}

// A logger is writing a log in the folder: it holds the folder (a shared flock) from the log's first byte to its
// final manifest (logger/logger.hpp's RunLog), whoever started it and whether or not its runner lives.
bool beingRecorded(const fs::path& dir) { return lockHeld(dir, /*exclusive=*/true); }

// The study (afford tune) of which the experiment folder is a trial: STUDY/trials/NNNN beside STUDY/study.json.
std::optional<fs::path> studyOf(const fs::path& out_dir) {
  const fs::path out = fs::path(out_dir).lexically_normal();
  const fs::path trials = (out.has_filename() ? out : out.parent_path()).parent_path();
  std::error_code ec;
  if (trials.filename() != "trials" || !fs::is_regular_file(trials.parent_path() / "study.json", ec))
    return std::nullopt;
  return trials.parent_path();
}

// Why the runs of the experiment in `out_dir` are in use, or "" if they are not: it is running, it is a study's
// trial, or it stopped before it finished (its --resume takes its runs' checkpoints and moves a cut run aside).
// An experiment folder that is gone leaves its runs to clean.
std::string experimentInUse(const std::string& out_dir) {
  const fs::path out = out_dir;
  if (experimentRunning(out)) return "its experiment is running (in " + out_dir + ")";
  if (const auto study = studyOf(out))
    return "a trial of the study in " + study->string() + " (" + out_dir +
           "): afford tune keeps its trials (an interrupted one runs again when the study goes on)";
  std::error_code ec;
  if (!fs::exists(statePath(out), ec)) return "";
  ExperimentState state;
  try {
    state = readState(out);
  } catch (const std::exception& e) {
    return "its experiment's state does not read (" + std::string(e.what()) + ")";
  }
  if (state.state == "finished") return "";
  const std::string how = state.state == "interrupted" && !state.interruptions.empty()
                              ? "interrupted by " + state.interruptions.back().signal
                              : "its runner ended before it finished";
  return "its experiment (in " + out_dir + ") stopped before it finished (" + how + "): `" + state.resume + "`" +
         (state.cwd.empty() ? "" : " (in " + state.cwd + ")") + " continues it";
}

// Why the experiments' runs are in use ("" if not), by experiment folder: asked once per clean.
using InUse = std::map<std::string, std::string>;

// Whose the folder is (e.kind, e.experiment); the experiment folder its run.json names, if any.
std::string attribute(Entry& e) {
  for (const char* name : {"run.json", "manifest.json", "outcome.json"}) {
    const auto j = smallJson(e.path / name);
    if (!j || !j->is_object() || !j->contains("experiment") || !(*j)["experiment"].is_string()) continue;
    e.experiment = (*j)["experiment"].get<std::string>();
    e.kind = e.label.rfind("agents/", 0) == 0 ? Kind::Agent : Kind::Run;
    return j->contains("out_dir") && (*j)["out_dir"].is_string() ? (*j)["out_dir"].get<std::string>() : "";
  }
  return "";
}

// What the folder is, and whether it may go.
void classify(Entry& e, InUse& in_use) {
  std::error_code ec;
  if (fs::exists(e.path / "lcm-url", ec) || fs::exists(e.path / "bus.key", ec)) {
    e.kind = Kind::Group;
    const std::vector<GroupProcess> alive = groupAlive(e.path);
    std::string names;
    for (const auto& n : alive) names += (names.empty() ? "" : ", ") + n.name;
    e.kept_because = "a scripts/procs.sh group (" + (alive.empty() ? std::string("stopped") : "running: " + names) +
                     "); stop it and remove its folder yourself";
    return;
  }
  const std::string out_dir = attribute(e);
  if (e.label.rfind("agents/", 0) == 0 && e.label.find(".part.") != std::string::npos) {
    e.kept_because = "an agent being stored (its runner renames it once whole; if none runs, remove it yourself)";
    return;
  }
  if (!out_dir.empty()) {
    const auto known = in_use.find(out_dir);
    e.kept_because = known != in_use.end() ? known->second : (in_use[out_dir] = experimentInUse(out_dir));
  }
  if (e.kept_because.empty() && beingRecorded(e.path))
    e.kept_because = "a log is being written in it (a logger holds it: a run going on, or its log being closed)";
  if (!out_dir.empty() || !e.kept_because.empty()) return;
  if (fs::exists(statePath(e.path), ec)) {  // an experiment's folder, not a run's
    const auto study = studyOf(e.path);
    e.kept_because = study ? "a trial of the study in " + study->string() + ": afford tune keeps its trials"
                           : "an experiment's folder (its results), not a run's: remove it yourself";
    return;
  }
  if (e.kind == Kind::Run) {  // attributed by its log's manifest alone: no runner said where its experiment is
    const auto manifest = smallJson(e.path / "manifest.json");
    if (manifest && manifest->is_object() && !manifest->value("complete", false))
      e.kept_because = "its log is incomplete and no run.json names its experiment (a run cut, or recorded by a "
                       "logger started by hand): remove it yourself";
    return;
  }
  if (e.kind == Kind::Unknown) e.kept_because = "nothing in it says whose it is (not afford's, or not a run's)";
}

Entry measure(const fs::path& dir, const std::string& label, InUse& in_use) {
  Entry e;
  e.path = dir;
  e.label = label;
  e.experiment = "?";
  classify(e, in_use);
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
  InUse in_use;
  for (const auto& d : fs::directory_iterator(log_root)) {
    const std::string name = d.path().filename().string();
    if (!d.is_directory() || name.front() == '.') continue;  // .prefixes: the run prefixes taken
    if (name == "agents") {
      for (const auto& k : fs::directory_iterator(d.path()))
        if (k.is_directory()) entries.push_back(measure(k.path(), "agents/" + k.path().filename().string(), in_use));
    } else {
      entries.push_back(measure(d.path(), name, in_use));
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
                                          "root chosen by age, size or experiment (a dry run by default); what is "
                                          "in use (a run going on, a log being written, the runs of an experiment "
                                          "that --resume continues, a study's trials, a scripts/procs.sh group) "
                                          "and folders it cannot attribute are left alone, each with its reason");
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

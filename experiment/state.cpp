#include "experiment/state.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include "afford/auth.hpp"
#include "afford/checksum.hpp"
#include "afford/config.hpp"
#include "afford/process_main.hpp"
#include "experiment/run/outcome.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

std::string shellQuoted(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_./:=@%+,-") ==
                        std::string::npos)
    return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

namespace {

// What scripts/procs.sh run says reaches its group (`<procs.sh> run GROUP`, with the settings that find it).
std::string procsCommand() {
  const char* with = std::getenv("AFFORD_RESUME_WITH");
  return with ? with : "";
}

// The network namespace this process runs in, if `ip netns` named it (/run/netns/NAME, as `ip netns identify`
// finds it); "" if none did.
std::string namedNetns() {
  struct stat self {};
  if (stat("/proc/self/ns/net", &self) != 0) return "";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/run/netns", ec)) {
    struct stat ns {};
    if (stat(e.path().c_str(), &ns) == 0 && ns.st_dev == self.st_dev && ns.st_ino == self.st_ino)
      return e.path().filename().string();
  }
  return "";
}

}  // namespace

std::string reachCommand(const ExperimentRequest& o) {
  if (const std::string procs = procsCommand(); !procs.empty()) return procs;
  std::string c = shellQuoted(o.write.program) + " experiment";
  if (o.host.attach.empty()) return c;  // its own processes: the runner starts them again
  c += " --attach " + shellQuoted(o.host.attach);
  if (const std::string key = busKeySource(o.host.bus_key); !key.empty())
    c += " --bus-key " + shellQuoted(fs::absolute(key).string());
  if (const std::string ns = namedNetns(); !ns.empty()) c = "ip netns exec " + shellQuoted(ns) + " " + c;
  return c;
}

std::string resumeCommand(const ExperimentRequest& o) {
  return (o.resume_with.empty() ? shellQuoted(o.write.program) + " experiment" : o.resume_with) + " --resume --out " +
         shellQuoted(o.write.out_dir);
}

OutDirLock::OutDirLock(const fs::path& out) {
  const fs::path lock = out / ".lock";
  fd_ = open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  // `afford clean` tests the lock by taking it shared for an instant: a few tries get past that.
  for (int tries = 0; fd_ >= 0 && tries < 100; ++tries) {
    if (flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
    usleep(1000);
  }
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  throw ConfigError("another afford experiment is writing to " + out.string() + " (it holds " + lock.string() + ")");
}

OutDirLock::~OutDirLock() {
  if (fd_ >= 0) close(fd_);
}

OutDirLock& OutDirLock::operator=(OutDirLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

namespace {

// An entry of an experiment folder that afford writes: the experiment (its state, summary, CSV files,
// kept outcomes, sweep conditions, lock) and `afford plot` (fig_*).
bool writtenByAfford(const fs::path& entry) {
  const std::string name = entry.filename().string();
  if (name == "experiment.json" || name == "summary.json" || name == ".lock" || name == "runs" || name == "bus.json" ||
      name == "conditions" || name == "processes")  // processes/slot<j>/<process>.log: their output (udpm)
    return true;
  const std::string ext = entry.extension().string();
  if (ext == ".csv") return true;
  return name.rfind("fig_", 0) == 0 && (ext == ".png" || ext == ".gp");
}

bool sameFolder(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  return fs::weakly_canonical(fs::absolute(a), ec) == fs::weakly_canonical(fs::absolute(b), ec);
}

// An entry of `out` that is the request's own though afford's experiment did not write it: its log root;
// for a merge, the shards' folders it merges and scripts/slurm-submit.sh's `slurm` folder beside them.
bool requestsOwn(const ExperimentRequest& o, const fs::path& entry) {
  if (sameFolder(entry, o.plan.log_root)) return true;
  if (o.merged_from.empty()) return false;
  if (entry.filename() == "slurm") return true;
  return std::any_of(o.merged_from.begin(), o.merged_from.end(), [&](const std::string& shard) { return sameFolder(entry, shard); });
}

// The entries of `out` that are not afford's.
std::vector<std::string> foreignEntries(const ExperimentRequest& o) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(o.write.out_dir, ec))
    if (!writtenByAfford(e.path()) && !requestsOwn(o, e.path())) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string someNames(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t k = 0; k < names.size() && k < 5; ++k) s += (k ? ", " : "") + names[k];
  return names.size() > 5 ? s + ", ... (" + std::to_string(names.size()) + " in all)" : s;
}

}  // namespace

void refuseUsedOutDir(const ExperimentRequest& o) {
  const fs::path out = o.write.out_dir;
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  if (!fs::is_directory(out, ec)) throw ConfigError("--out " + out.string() + " is not a folder");
  if (!fs::exists(statePath(out))) {
    const std::vector<std::string> foreign = foreignEntries(o);
    bool afford_files = false;
    for (const auto& e : fs::directory_iterator(out, ec))
      afford_files |= writtenByAfford(e.path()) && e.path().filename() != ".lock";  // (the lock: a runner's, or ours)
    if (foreign.empty() && !afford_files) return;  // empty (but for its log root)
    throw ConfigError("--out " + out.string() + " is not empty and holds no afford experiment (it holds " +
                      someNames(foreign.empty() ? std::vector<std::string>{"summary or CSV files without "
                                                                           "experiment.json"}
                                                : foreign) +
                      "): an experiment writes into a folder of its own; choose a new or empty --out");
  }
  const ExperimentState state = readState(out);
  const std::string& what = state.experiment;
  if (state.state != "finished")
    throw ConfigError("--out " + out.string() + " holds an experiment that did not finish (" + what + ", " +
                      state.state + "): continue it with `" + (state.resume.empty() ? resumeCommand(o) : state.resume) +
                      "`, or choose another --out");
  if (!o.write.replace)
    throw ConfigError("--out " + out.string() + " holds a finished experiment (" + what + "; its results: " +
                      (out / "summary.json").string() +
                      "): choose another --out to keep both, or give --replace to remove it and write this one "
                      "in its place");
  if (const std::vector<std::string> foreign = foreignEntries(o); !foreign.empty())
    throw ConfigError("--replace: " + out.string() + " holds files afford did not write (" + someNames(foreign) +
                      "); move them away or choose another --out: --replace removes only an experiment's own files");
}

void clearReplaced(const ExperimentRequest& o) {
  if (!o.write.replace || !fs::exists(statePath(o.write.out_dir))) return;
  std::error_code ec;
  std::vector<fs::path> gone;
  for (const auto& e : fs::directory_iterator(o.write.out_dir, ec))
    if (writtenByAfford(e.path()) && e.path().filename() != ".lock") gone.push_back(e.path());
  for (const fs::path& p : gone) fs::remove_all(p);
}

namespace {
// One word as shellQuoted wrote it; nullopt if it is not one.
std::optional<std::string> shellWord(const std::string& s) {
  std::string w;
  bool quoted = false;
  for (char c : s) {
    if (c == '\'') quoted = !quoted;
    else if (!quoted && (c == ' ' || c == '\\' || c == '"')) return std::nullopt;  // ('\'': '\'' ends and starts)
    else w += c;
  }
  if (quoted || w.empty()) return std::nullopt;
  return w;
}

// --out as the experiment was given it where it was started: stored from 0.2.0; 0.1.0 named it only in the
// command that resumes it (`... --resume --out DIR`, DIR as shellQuoted writes it). "" if neither says.
std::string storedOut(const ExperimentState& state) {
  if (state.out) return *state.out;
  const std::string flag = " --resume --out ";
  const auto at = state.resume.rfind(flag);
  if (at == std::string::npos) return "";
  return shellWord(state.resume.substr(at + flag.size())).value_or("");
}
}  // namespace

FollowedFolder followMovedFolder(ExperimentState& state, const ExperimentRequest& given) {
  FollowedFolder followed;
  std::vector<std::string>& notes = followed.notes;
  const fs::path here = fs::current_path();
  const fs::path started = state.cwd;
  const std::string stored_out = storedOut(state);
  // Where the folder was (from where it was started) and where it is.
  const fs::path was = stored_out.empty() ? fs::path() : (started / stored_out).lexically_normal();
  std::vector<PathMove> moves;
  ExperimentRequest& o = state.options;
  for (auto [option, path] : {std::pair{"--log-root", &o.plan.log_root}, {"--config-dir", &o.plan.config_dir}}) {
    if (path->empty()) continue;  // (an empty --config-dir: the default)
    const fs::path where = (started / *path).lexically_normal();
    std::string now = *path;
    if (const fs::path inside = was.empty() ? fs::path() : where.lexically_relative(was);
        !inside.empty() && *inside.begin() != "..") {
      // Inside the folder (moved to another machine, kept in a repository): inside it where it is now.
      now = (inside == "." ? fs::path(given.write.out_dir) : fs::path(given.write.out_dir) / inside)
                .lexically_normal()
                .string();
      if (option == std::string("--log-root")) followed.log_root_inside = true;
    } else if (!fs::path(*path).is_absolute() && here != started) {
      // Outside it, relative to where it was started: there still.
      if (!fs::is_directory(started))
        throw ConfigError("--resume: the experiment in " + given.write.out_dir + " was started in " + state.cwd +
                          ", which is gone, and its " + option + " '" + *path +
                          "' is relative to that folder and outside the experiment's own: make " + state.cwd +
                          " hold it again, or move it inside the experiment's folder");
      now = where.string();
    }
    if (option == std::string("--config-dir") && !fs::is_directory(now)) {
      // A config folder that is gone (the source tree or installation that started it moved or was upgraded):
      // the one named now, or this build's own. A configuration that differs is refused below (its runs'
      // fingerprints), never run.
      const std::string instead = given.given.count("--config-dir") ? given.plan.config_dir : defaultConfigDir();
      notes.push_back("--resume: the experiment's --config-dir " + *path + " is gone; its runs are planned with " +
                      (given.given.count("--config-dir") ? "the --config-dir given, " : "this build's, ") +
                      instead + " (its runs must come out the same: any that differ are refused)");
      now = instead;
    }
    if (now != *path) moves.push_back({*path, now});
    *path = now;
  }
  if (!moves.empty()) {
    if (!state.moved) state.moved.emplace();
    state.moved->insert(state.moved->end(), moves.begin(), moves.end());
  }
  if (const fs::path is = fs::absolute(given.write.out_dir).lexically_normal(); !was.empty() && was != is)
    followed.was = was.string();
  state.cwd = here.string();
  state.out = given.write.out_dir;
  return followed;
}

// The stored experiment's options, with the run options given now.
ExperimentRequest resumedRequest(const ExperimentRequest& given, const ExperimentState& state) {
  ExperimentRequest o = state.options;
  o.write.out_dir = given.write.out_dir;
  o.resume = true;
  o.given = given.given;
  o.write.program = given.write.program;
  o.host.bus_key = given.host.bus_key;  // (never stored: the key file given now, or $AFFORD_BUS_KEY's)
  o.host.on_curve = given.host.on_curve;
  o.host.on_bus = given.host.on_bus;
  const auto has = [&](const char* option) { return given.given.count(option) > 0; };
  if (has("--jobs")) o.host.jobs = given.host.jobs;
  if (has("--transport")) o.host.transport = given.host.transport;
  if (has("--netns")) o.host.netns = given.host.netns;
  if (has("--base-port")) o.host.base_port = given.host.base_port;
  if (has("--process-log-level")) o.host.process_log_level = given.host.process_log_level;
  if (has("--stall-seconds")) o.host.stall_seconds = given.host.stall_seconds;
  if (has("--quiet")) o.write.quiet = given.write.quiet;
  if (has("--progress")) o.host.progress = given.host.progress;
  if (has("--progress-every")) o.host.progress_every = given.host.progress_every;
  if (has("--attach")) o.host.attach = given.host.attach;
  if (has("--reuse-agents")) o.host.reuse_agents = given.host.reuse_agents;
  // How its processes are reached: as this command says, unless it says nothing of it and they are someone
  // else's (attached): then as the experiment stored it (a plain --resume then names the command that works).
  if (o.resume_with.empty() || o.host.attach.empty() || !procsCommand().empty() || has("--attach") || has("--bus-key"))
    o.resume_with = reachCommand(o);
  return o;
}

// The stored experiment of DIR, if it did not finish.
ExperimentState unfinishedState(const ExperimentRequest& given) {
  if (!fs::exists(statePath(given.write.out_dir)))
    throw ConfigError("--resume: " + given.write.out_dir + " holds no experiment to resume (no " +
                      statePath(given.write.out_dir).string() + "): is --out right?");
  ExperimentState state = readState(given.write.out_dir);
  if (state.state == "finished")
    throw NothingToResume("--resume: nothing to resume: the experiment in " + given.write.out_dir + " (" +
                          state.experiment + ") finished; its results are in " +
                          (fs::path(given.write.out_dir) / "summary.json").string());
  return state;
}

// With --resume, a plan option given again must say what the stored experiment
// says (`stored`: its options; `plan`: what they resolved to).
void refuseChangedPlan(const ExperimentRequest& given, const ExperimentRequest& stored, const Plan& plan) {
  const auto check = [&](const std::string& option, const std::string& now, const std::string& then) {
    if (!given.given.count(option) || now == then) return;
    const std::string name = option == "name" ? "the experiment name" : option;
    throw ConfigError("--resume: " + name + " '" + now + "' differs from the stored experiment's '" + then +
                      "': a resumed experiment keeps its plan (leave " + name +
                      " out, or start a new experiment with another --out)");
  };
  // (An option not given is empty: no path, and nothing to compare; fs::absolute("") throws.)
  const auto path = [](const std::string& p) { return p.empty() ? p : fs::absolute(p).lexically_normal().string(); };
  check("name", given.plan.experiment, stored.plan.experiment);
  check("--system", joined(given.plan.systems), joined(plan.systems));
  // 0 (or none) stands for the experiment's own count: nothing to compare
  if (given.plan.reps) check("--reps", std::to_string(*given.plan.reps), std::to_string(plan.reps));
  if (given.plan.steps) check("--steps", std::to_string(*given.plan.steps), std::to_string(plan.runs.front().spec.steps));
  if (given.plan.extrinsic_reps)
    check("--extrinsic-reps", std::to_string(*given.plan.extrinsic_reps), std::to_string(plan.tests));
  check("--seed", std::to_string(given.plan.seed), std::to_string(stored.plan.seed));
  check("--keep-logs", given.plan.keep_logs, stored.plan.keep_logs);
  check("--keep-checkpoints", given.plan.keep_checkpoints, stored.plan.keep_checkpoints);
  check("--log-root", path(given.plan.log_root), path(stored.plan.log_root));
  check("--run-prefix", given.plan.run_prefix, stored.plan.run_prefix);
  check("--set", joined(given.plan.settings), joined(stored.plan.settings));
  const auto swapped = [](const ExperimentRequest& x) {
    std::vector<std::string> v;
    for (const auto& [name, command] : x.host.processes) v.push_back(name + "=" + command);
    return joined(v);
  };
  check("--process", swapped(given), swapped(stored));
  check("--sweep", given.plan.sweep_file.empty() ? "" : path(given.plan.sweep_file), stored.plan.sweep_file.empty() ? "" : path(stored.plan.sweep_file));
  const auto shard = [](const ExperimentRequest& x) {
    return x.host.shard_count ? std::to_string(x.host.shard_index) + "/" + std::to_string(x.host.shard_count) : std::string("none");
  };
  check("--shard", shard(given), shard(stored));
  check("--config-dir", path(given.plan.config_dir), path(stored.plan.config_dir));
  check("--scenarios", joined(given.plan.scenarios), joined(plan.scenarios));
  if (given.plan.tables) check("--tables", std::to_string(*given.plan.tables), std::to_string(plan.tables ? plan.tables->count : 0));
  if (given.plan.table_seed)
    check("--table-seed", std::to_string(*given.plan.table_seed), std::to_string(plan.tables ? plan.tables->seed : 0));
}

}  // namespace afford

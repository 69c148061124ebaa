#include "afford/store.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <fstream>

#include "afford/checksum.hpp"
#include "afford/config.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {
const char* netnsName(NetnsMode m) { return m == NetnsMode::On ? "on" : m == NetnsMode::Off ? "off" : "auto"; }
fs::path outcomePath(const fs::path& out, const std::string& run_id) { return out / "runs" / (run_id + ".json"); }
}  // namespace

// `text` into `path`, whole or not at all: written beside it, then renamed
// over it (an interruption leaves the previous version or the new one).
void writeWhole(const fs::path& path, const std::string& text) {
  const fs::path part = path.string() + ".part";
  {
    std::ofstream f(part, std::ios::binary | std::ios::trunc);
    f << text;
    f.close();
    if (!f) throw std::runtime_error("cannot write " + part.string());
  }
  fs::rename(part, path);
}

fs::path statePath(const fs::path& out) { return out / "experiment.json"; }

json optionsToJson(const ExperimentOptions& o) {
  return {{"experiment", o.experiment},
          {"systems", o.systems},
          {"reps", o.reps ? json(*o.reps) : json(nullptr)},
          {"steps", o.steps ? json(*o.steps) : json(nullptr)},
          {"seed", o.seed},
          {"keep_logs", o.keep_logs},
          {"keep_checkpoints", o.keep_checkpoints},
          {"reuse_agents", o.reuse_agents},
          {"log_root", o.log_root},
          {"run_prefix", o.run_prefix},
          {"config_dir", o.config_dir},
          {"settings", o.settings},
          {"sweep_file", o.sweep_file},
          {"shard", o.shard_count ? json{{"index", o.shard_index}, {"count", o.shard_count}} : json(nullptr)},
          {"merged_from", o.merged_from},  // a merge resumes as one: it gathers its shards again
          {"merged_network", o.merged_network},
          {"extrinsic_reps", o.extrinsic_reps},
          {"scenarios", o.scenarios},
          {"tables", o.tables ? json(*o.tables) : json(nullptr)},
          {"processes", o.processes},
          {"table_seed", o.table_seed ? json(*o.table_seed) : json(nullptr)},
          // run options: --resume uses them unless given again
          {"jobs", o.jobs},
          {"transport", o.transport},
          {"netns", netnsName(o.netns)},
          {"base_port", o.base_port},
          {"process_log_level", o.process_log_level},
          {"stall_seconds", o.stall_seconds},
          {"quiet", o.quiet},
          {"progress", o.progress},
          {"progress_every", o.progress_every},
          {"attach", o.attach}};
}

ExperimentOptions optionsFromJson(const json& j) {
  ExperimentOptions o;
  o.experiment = j.at("experiment").get<std::string>();
  o.systems = j.at("systems").get<std::vector<std::string>>();
  if (!j.at("reps").is_null()) o.reps = j["reps"].get<int>();
  if (!j.at("steps").is_null()) o.steps = j["steps"].get<std::int64_t>();
  o.seed = j.at("seed").get<std::int64_t>();
  o.keep_logs = j.at("keep_logs").get<std::string>();
  o.keep_checkpoints = j.value("keep_checkpoints", std::string("all"));  // stored before issue 13: all were kept
  o.reuse_agents = j.value("reuse_agents", false);
  o.log_root = j.at("log_root").get<std::string>();
  o.run_prefix = j.at("run_prefix").get<std::string>();
  o.config_dir = j.at("config_dir").get<std::string>();
  o.settings = j.at("settings").get<std::vector<std::string>>();
  o.sweep_file = j.value("sweep_file", std::string());  // stored before issue 13: no sweeps, no shards
  if (j.contains("shard") && !j["shard"].is_null()) {
    o.shard_index = j["shard"].at("index").get<int>();
    o.shard_count = j["shard"].at("count").get<int>();
  }
  o.merged_from = j.value("merged_from", std::vector<std::string>());
  o.merged_network = j.value("merged_network", std::string());
  o.extrinsic_reps = j.at("extrinsic_reps").get<int>();
  o.scenarios = j.at("scenarios").get<std::vector<std::string>>();
  if (j.contains("tables") && !j["tables"].is_null()) o.tables = j["tables"].get<int>();
  o.processes = j.value("processes", std::map<std::string, std::string>());  // stored before issue 24: none
  if (j.contains("table_seed") && !j["table_seed"].is_null()) o.table_seed = j["table_seed"].get<std::int64_t>();
  o.jobs = j.at("jobs").get<int>();
  o.transport = j.at("transport").get<std::string>();
  const std::string netns = j.at("netns").get<std::string>();
  o.netns = netns == "on" ? NetnsMode::On : netns == "off" ? NetnsMode::Off : NetnsMode::Auto;
  o.base_port = j.at("base_port").get<int>();
  o.process_log_level = j.at("process_log_level").get<std::string>();
  o.stall_seconds = j.at("stall_seconds").get<double>();
  o.quiet = j.at("quiet").get<bool>();
  o.progress = j.value("progress", std::string("auto"));  // stored before issue 13: the default
  o.progress_every = j.value("progress_every", -1.0);
  o.attach = j.at("attach").get<std::string>();
  return o;
}

json outcomeToJson(const RunOutcome& r) {
  json curve = json::array();
  for (const auto& s : r.curve) curve.push_back({{"step", s.step}, {"affordance", s.affordance}});
  json goals = json::array();
  for (const auto& g : r.extrinsic.sub_goals)
    goals.push_back({{"x", g.x}, {"y", g.y}, {"iterations", g.iterations}, {"actions_checked", g.actions_checked},
                     {"actions_taken", g.actions_taken}, {"reached", g.reached}});
  return {{"ok", r.ok},
          {"error", r.error},
          {"weights_checksum", r.weights_checksum},
          {"checkpoint", r.checkpoint},
          {"reused_from", r.reused_from},
          {"curve", curve},
          {"executed", r.executed},
          {"successes", r.successes},
          {"looks", r.looks},
          {"replayed", r.replayed},
          {"replayed_effects", r.replayed_effects},
          {"revisits", r.revisits},
          {"log_dir", r.log_dir},
          {"wall_seconds", r.wall_seconds},
          {"run_seconds", r.run_seconds},
          {"peak_rss_kb", r.peak_rss_kb},
          {"log_bytes", r.log_bytes},
          {"extrinsic",
           {{"scenario", r.extrinsic.scenario},
            {"success", r.extrinsic.success},
            {"completion", r.extrinsic.completion},
            {"attempts", r.extrinsic.attempts},
            {"utility", r.extrinsic.utility},
            {"sub_goals", goals}}}};
}

RunOutcome outcomeFromJson(const json& j) {
  RunOutcome r;
  r.ok = j.at("ok").get<bool>();
  r.error = j.at("error").get<std::string>();
  r.weights_checksum = j.at("weights_checksum").get<std::string>();
  r.checkpoint = j.at("checkpoint").get<std::string>();
  r.reused_from = j.value("reused_from", std::string());  // outcomes kept before issue 13 have none
  for (const auto& s : j.at("curve"))
    r.curve.push_back({s.at("step").get<std::int64_t>(), s.at("affordance").get<std::vector<std::vector<double>>>()});
  r.executed = j.at("executed").get<std::vector<std::int64_t>>();
  r.successes = j.at("successes").get<std::vector<std::int64_t>>();
  r.looks = j.value("looks", 0);  // outcomes kept before issue 11 have none of these
  r.replayed = j.value("replayed", std::int64_t{0});
  r.replayed_effects = j.value("replayed_effects", std::int64_t{0});
  r.revisits = j.value("revisits", std::int64_t{0});
  r.log_dir = j.at("log_dir").get<std::string>();
  r.wall_seconds = j.at("wall_seconds").get<double>();
  r.run_seconds = j.at("run_seconds").get<double>();
  r.peak_rss_kb = j.at("peak_rss_kb").get<std::map<std::string, long>>();
  r.log_bytes = j.at("log_bytes").get<std::uintmax_t>();
  const json& e = j.at("extrinsic");
  r.extrinsic.scenario = e.at("scenario").get<std::string>();
  r.extrinsic.success = e.at("success").get<bool>();
  r.extrinsic.completion = e.at("completion").get<int>();
  r.extrinsic.attempts = e.at("attempts").get<int>();
  r.extrinsic.utility = e.at("utility").get<double>();
  for (const auto& g : e.at("sub_goals"))
    r.extrinsic.sub_goals.push_back({g.at("x").get<double>(), g.at("y").get<double>(), g.at("iterations").get<int>(),
                                     g.at("actions_checked").get<int>(), g.at("actions_taken").get<int>(),
                                     g.at("reached").get<bool>()});
  return r;
}

// A finished run's outcome, kept as it finishes: --resume does not run it again.
void keepOutcome(const fs::path& out, const std::string& run_id, const RunOutcome& r) {
  fs::create_directories(out / "runs");
  writeWhole(outcomePath(out, run_id), json{{"run_id", run_id}, {"outcome", outcomeToJson(r)}}.dump() + "\n");
}

std::optional<RunOutcome> keptOutcome(const fs::path& out, const std::string& run_id) {
  const fs::path path = outcomePath(out, run_id);
  if (!fs::exists(path)) return std::nullopt;
  try {
    std::ifstream in(path);
    const json j = json::parse(in);
    if (j.at("run_id") != run_id) throw std::runtime_error("it is the outcome of run '" + j["run_id"].dump() + "'");
    return outcomeFromJson(j.at("outcome"));
  } catch (const std::exception& e) {
    throw ConfigError("cannot read " + path.string() + ": " + e.what());
  }
}

json readState(const fs::path& out) {
  std::ifstream in(statePath(out));
  try {
    return json::parse(in);
  } catch (const std::exception& e) {
    throw ConfigError("cannot read " + statePath(out).string() + ": " + e.what());
  }
}

// Each run's id and the FNV-1a of its configuration: a resumed experiment
// must plan the very same runs.
json fingerprint(const std::vector<PlannedRun>& runs) {
  json f = json::array();
  for (const auto& p : runs) {
    Fnv1a h;
    h.add(p.spec.config_yaml.data(), p.spec.config_yaml.size());
    f.push_back({{"run_id", p.spec.run_id}, {"config", h.hex()}});
  }
  return f;
}

void refuseOtherPlan(const json& stored, const json& now, const std::string& what) {
  for (std::size_t i = 0; i < std::max(stored.size(), now.size()); ++i) {
    if (i < stored.size() && i < now.size() && stored[i] == now[i]) continue;
    const std::string id = (i < stored.size() ? stored[i] : now[i])["run_id"].get<std::string>();
    throw ConfigError("--resume: the " + what + " differ from those stored: run '" + id +
                      (i < stored.size() && i < now.size() && stored[i]["run_id"] == now[i]["run_id"]
                           ? "' now has another configuration (did the config folder change since?)"
                           : "' is not in both") +
                      "; start a new experiment with another --out instead");
  }
}

std::string shellQuoted(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_./:=@%+,-") ==
                        std::string::npos)
    return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string resumeCommand(const ExperimentOptions& o) {
  return shellQuoted(o.program) + " experiment --resume --out " + shellQuoted(o.out_dir);
}

// One runner per output folder, until it exits (closed on exec: the children do not hold it).
void lockOutDir(const fs::path& out) {
  const fs::path lock = out / ".lock";
  const int fd = open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0 || flock(fd, LOCK_EX | LOCK_NB) != 0)
    throw ConfigError("another afford experiment is writing to " + out.string() + " (it holds " + lock.string() + ")");
}

// A fresh experiment never replaces one that did not finish.
void refuseUnfinished(const ExperimentOptions& o) {
  if (!fs::exists(statePath(o.out_dir))) return;
  const json state = readState(o.out_dir);
  if (state.value("state", "") == "finished") return;
  throw ConfigError("--out " + o.out_dir + " holds an experiment that did not finish (" +
                    state.value("experiment", "?") + ", " + state.value("state", "?") + "): continue it with `" +
                    resumeCommand(o) + "`, or choose another --out");
}

// The stored experiment's options, with the run options given now (--jobs, --transport, ...).
ExperimentOptions resumedOptions(const ExperimentOptions& given, const json& state) {
  ExperimentOptions o = optionsFromJson(state.at("options"));
  o.out_dir = given.out_dir;
  o.resume = true;
  o.given = given.given;
  o.program = given.program;
  const auto has = [&](const char* option) { return given.given.count(option) > 0; };
  if (has("--jobs")) o.jobs = given.jobs;
  if (has("--transport")) o.transport = given.transport;
  if (has("--netns")) o.netns = given.netns;
  if (has("--base-port")) o.base_port = given.base_port;
  if (has("--process-log-level")) o.process_log_level = given.process_log_level;
  if (has("--stall-seconds")) o.stall_seconds = given.stall_seconds;
  if (has("--quiet")) o.quiet = given.quiet;
  if (has("--progress")) o.progress = given.progress;
  if (has("--progress-every")) o.progress_every = given.progress_every;
  if (has("--attach")) o.attach = given.attach;
  if (has("--reuse-agents")) o.reuse_agents = given.reuse_agents;
  const std::string cwd = state.at("cwd").get<std::string>();
  if (fs::current_path() != fs::path(cwd))
    for (const auto& [option, path] : {std::pair{"--log-root", o.log_root}, {"--config-dir", o.config_dir}})
      if (fs::path(path).is_relative())
        throw ConfigError("--resume: the experiment in " + given.out_dir + " was started in " + cwd + ", and its " +
                          option + " '" + path + "' is relative to that folder: resume it from there");
  return o;
}

// The stored experiment of DIR, if it did not finish.
json unfinishedState(const ExperimentOptions& given) {
  if (!fs::exists(statePath(given.out_dir)))
    throw ConfigError("--resume: " + given.out_dir + " holds no experiment to resume (no " +
                      statePath(given.out_dir).string() + "): is --out right?");
  json state = readState(given.out_dir);
  if (state.value("state", "") == "finished")
    throw ConfigError("--resume: the experiment in " + given.out_dir + " (" + state.value("experiment", "?") +
                      ") finished: its results are in " + (fs::path(given.out_dir) / "summary.json").string());
  return state;
}

}  // namespace afford

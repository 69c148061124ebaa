#include "afford/experiment.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <thread>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "afford/actions.hpp"
#include "afford/checksum.hpp"
#include "afford/config.hpp"
#include "afford/design.hpp"
#include "afford/driver.hpp"
#include "afford/generate.hpp"
#include "afford/group.hpp"
#include "afford/logging.hpp"
#include "afford/node.hpp"
#include "afford/tables.hpp"
#include "environment/node.hpp"
#include "eye/node.hpp"
#include "logger/node.hpp"
#include "motivation/node.hpp"
#include "planner/node.hpp"
#include "predictors/node.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct PlannedRun {
  RunSpec spec;
  std::string system;
  std::vector<std::vector<double>> target;  // the world's affordance table (objects x actions)
  int table = -1;                            // random tables: which one
  std::string intrinsic_condition;           // random tables: the condition's name ("" without conditions)
  bool keep_log = false;
  std::size_t index = 0;
  // extrinsic tests: which intrinsic run trained the agent, which scenario, which repetition
  std::size_t intrinsic = 0;
  std::string scenario;
  int condition = 0;  // index into Plan::conditions
  int rep = 0;
};

std::string defaultPrefix() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::localtime(&t));
  return buf;
}

// ---- interruption ------------------------------------------------------------

volatile std::sig_atomic_t g_signal = 0;  // the first SIGINT or SIGTERM received (0: none)
void (*g_stop_handler)(int) = nullptr;     // common's handler: it sets stopRequested()
std::string g_quit_message;                // said on a second signal (set before the handlers, then never changed)

void onInterrupt(int sig) {
  if (g_signal != 0) {  // a second one: quit now; every file written so far is whole (written aside, then renamed)
    (void)!write(STDERR_FILENO, g_quit_message.data(), g_quit_message.size());
    _exit(128 + sig);
  }
  g_signal = sig;
  static const char msg[] =
      "\nafford: stopping the runs under way, then writing what finished (a second signal quits at once)\n";
  (void)!write(STDERR_FILENO, msg, sizeof msg - 1);
  if (g_stop_handler) g_stop_handler(sig);
}

// SIGINT and SIGTERM set stopRequested() (the drivers stop their runs) and are
// remembered for the exit status. `resume`: the command that goes on.
void installInterruptHandlers(const std::string& resume) {
  g_quit_message = "\nafford: a second signal: quitting at once; what finished is kept. To resume: " + resume + "\n";
  installStopHandlers();
  struct sigaction common {};
  sigaction(SIGINT, nullptr, &common);
  g_stop_handler = common.sa_handler;
  struct sigaction sa {};
  sa.sa_handler = onInterrupt;
  sigemptyset(&sa.sa_mask);
  sigaddset(&sa.sa_mask, SIGINT);
  sigaddset(&sa.sa_mask, SIGTERM);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

std::string signalName(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : std::to_string(sig); }

// ---- what --resume needs: DIR/experiment.json and DIR/runs/<run-id>.json --------

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
fs::path outcomePath(const fs::path& out, const std::string& run_id) { return out / "runs" / (run_id + ".json"); }

const char* netnsName(NetnsMode m) { return m == NetnsMode::On ? "on" : m == NetnsMode::Off ? "off" : "auto"; }

json optionsToJson(const ExperimentOptions& o) {
  return {{"experiment", o.experiment},
          {"systems", o.systems},
          {"reps", o.reps ? json(*o.reps) : json(nullptr)},
          {"steps", o.steps ? json(*o.steps) : json(nullptr)},
          {"seed", o.seed},
          {"keep_logs", o.keep_logs},
          {"log_root", o.log_root},
          {"run_prefix", o.run_prefix},
          {"config_dir", o.config_dir},
          {"settings", o.settings},
          {"extrinsic_reps", o.extrinsic_reps},
          {"scenarios", o.scenarios},
          {"tables", o.tables ? json(*o.tables) : json(nullptr)},
          {"table_seed", o.table_seed ? json(*o.table_seed) : json(nullptr)},
          // run options: --resume uses them unless given again
          {"jobs", o.jobs},
          {"transport", o.transport},
          {"netns", netnsName(o.netns)},
          {"base_port", o.base_port},
          {"process_log_level", o.process_log_level},
          {"stall_seconds", o.stall_seconds},
          {"quiet", o.quiet},
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
  o.log_root = j.at("log_root").get<std::string>();
  o.run_prefix = j.at("run_prefix").get<std::string>();
  o.config_dir = j.at("config_dir").get<std::string>();
  o.settings = j.at("settings").get<std::vector<std::string>>();
  o.extrinsic_reps = j.at("extrinsic_reps").get<int>();
  o.scenarios = j.at("scenarios").get<std::vector<std::string>>();
  if (j.contains("tables") && !j["tables"].is_null()) o.tables = j["tables"].get<int>();
  if (j.contains("table_seed") && !j["table_seed"].is_null()) o.table_seed = j["table_seed"].get<std::int64_t>();
  o.jobs = j.at("jobs").get<int>();
  o.transport = j.at("transport").get<std::string>();
  const std::string netns = j.at("netns").get<std::string>();
  o.netns = netns == "on" ? NetnsMode::On : netns == "off" ? NetnsMode::Off : NetnsMode::Auto;
  o.base_port = j.at("base_port").get<int>();
  o.process_log_level = j.at("process_log_level").get<std::string>();
  o.stall_seconds = j.at("stall_seconds").get<double>();
  o.quiet = j.at("quiet").get<bool>();
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
  if (has("--attach")) o.attach = given.attach;
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

// Handle what is pending (up to a batch), or wait briefly for something.
void pumpLcm(lcm::LCM& lcm) {
  int handled = 0;
  while (handled < 512 && lcm.handleTimeout(0) > 0) ++handled;
  if (handled == 0) lcm.handleTimeout(5);
}

RunOutcome runInProcess(const PlannedRun& run, const ExperimentOptions& o, const ProtocolConfig& protocol, int slot) {
  lcm::LCM lcm("memq://");
  const std::string tag = o.jobs > 1 ? "#" + std::to_string(slot) : "";
  const std::string level = o.process_log_level == "info" ? "warn" : o.process_log_level;
  EnvironmentNode env(lcm, makeLogger("environment" + tag, level), protocol);
  EyeNode eye(lcm, makeLogger("eye" + tag, level), protocol, /*speculate=*/false);  // one thread: no idle time to fill
  PredictorsNode predictors(lcm, makeLogger("predictors" + tag, level), protocol, /*async_effects=*/false);
  // The motivation decides in the intrinsic phase, the planner in the extrinsic one.
  std::unique_ptr<NodeBase> decider;
  if (run.spec.extrinsic)
    decider = std::make_unique<PlannerNode>(lcm, makeLogger("planner" + tag, level), protocol);
  else
    decider = std::make_unique<MotivationNode>(lcm, makeLogger("motivation" + tag, level), protocol);
  std::unique_ptr<LoggerNode> logger;
  if (run.keep_log) logger = std::make_unique<LoggerNode>(lcm, makeLogger("logger" + tag, level), protocol, o.log_root);
  RunDriver driver(lcm, makeLogger("runner" + tag, level), protocol);
  auto pump = [&] {
    pumpLcm(lcm);
    env.tick();
    eye.tick();
    predictors.tick();
    decider->tick();
    if (logger) logger->tick();
  };
  RunOutcome r = driver.run(run.spec, pump, [] { return std::string(); });
  r.peak_rss_kb["all (one process)"] = peakRssKb(getpid());
  return r;
}

struct Slot {
  int index = 0;
  std::string url;
  std::unique_ptr<ProcessGroup> group;   // environment, eye, predictors, and motivation or planner
  bool extrinsic = false;                // which of the two the group has
  std::unique_ptr<ProcessGroup> logger;  // started with the slot's first recorded run, kept for the others
  // One bus connection and driver for all the slot's runs: the driver keeps
  // what each process last said, so a run starts as soon as they are free.
  std::unique_ptr<lcm::LCM> lcm;
  std::unique_ptr<RunDriver> driver;
};

RunOutcome runOverUdpm(const PlannedRun& run, const ExperimentOptions& o, const ProtocolConfig& protocol, Slot& slot,
                       const std::string& bin) {
  const std::string out = (fs::path(o.out_dir) / "processes" / ("slot" + std::to_string(slot.index))).string();
  const bool attached = !o.attach.empty();  // the user started the processes; none are ours to start
  // The runner listens before it starts any process: it hears each one's first STATUS.
  if (!slot.lcm) {
    // This thread only watches the runs (see kWatcherNice); LCM's receive
    // thread, created on the first handle(), inherits the priority.
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), kWatcherNice);
    slot.lcm = std::make_unique<lcm::LCM>(slot.url);
    if (!slot.lcm->good()) {
      slot.lcm.reset();
      RunOutcome r;
      r.error = "cannot open LCM at " + slot.url;
      return r;
    }
    slot.driver = std::make_unique<RunDriver>(*slot.lcm, makeLogger("runner", "warn"), protocol);
  }
  if (!attached && (!slot.group || !slot.group->health().empty() || slot.extrinsic != run.spec.extrinsic)) {
    slot.group.reset();
    slot.extrinsic = run.spec.extrinsic;
    slot.group = std::make_unique<ProcessGroup>(
        bin, std::vector<std::string>{"environment", "eye", "predictors", run.spec.extrinsic ? "planner" : "motivation"},
        slot.url, out, std::vector<std::string>{});
  }
  // The logger serves the slot's runs one after another; those not to be kept
  // say so in their configuration (run.record), and it stays free during them.
  if (run.keep_log && !attached && (!slot.logger || !slot.logger->health().empty()))
    slot.logger = std::make_unique<ProcessGroup>(bin, std::vector<std::string>{"logger"}, slot.url, out,
                                                 std::vector<std::string>{"--log-dir", o.log_root});
  lcm::LCM& lcm = *slot.lcm;
  RunDriver& driver = *slot.driver;
  auto health = [&]() {
    std::string h = slot.group ? slot.group->health() : std::string();
    if (h.empty() && slot.logger && run.keep_log) h = slot.logger->health();
    return h;
  };
  RunOutcome r = driver.run(run.spec, [&] { pumpLcm(lcm); }, health);
  if (slot.group) r.peak_rss_kb = slot.group->peakRssKb();
  if (slot.logger && run.keep_log)
    for (const auto& [name, kb] : slot.logger->peakRssKb()) r.peak_rss_kb[name] = kb;
  if (!r.ok) {  // a broken group is not reused
    slot.group.reset();
    slot.logger.reset();
  }
  return r;
}

using Table = std::vector<std::vector<double>>;

double meanAbsError(const Table& a, const Table& b) {
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < a[i].size(); ++j, ++n) sum += std::abs(a[i][j] - b[i][j]);
  return n ? sum / n : 0.0;
}

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// The validated list of runs of a request, with each system's config.
struct Plan {
  std::string config_dir;
  ExperimentFile exp;
  int reps = 0;
  std::vector<PlannedRun> runs;
  std::map<std::string, RunConfig> configs;  // per system (of its first repetition)
  std::vector<std::string> systems;          // the systems run
  std::vector<std::string> scenarios;        // extrinsic tests, if any
  std::map<std::string, int> sub_goals;      // objects (sub-goals) per scenario
  std::map<std::string, Scenario> generated;  // scenarios drawn for the design (extrinsic.generate), by name
  std::map<std::string, ScenarioSpec> specs;  // ... and what each was drawn as
  int tests = 0;                             // extrinsic tests per agent, condition and scenario
  std::vector<Condition> conditions{Condition{}};  // planner settings compared (default: one, no settings)
  ExtrinsicDesign design;                    // the experiment file's extrinsic section, if any
  ProtocolConfig protocol;                   // the runner's between runs (each run's config has its own)
  std::optional<TablesDesign> tables;        // random tables (count and seed as run), if any
  std::vector<AffordanceTable> table_list;   // ... the tables drawn
  std::vector<std::pair<std::string, std::vector<std::string>>> conditions_run{{"", {}}};  // intrinsic conditions
};

// Everything that can be wrong with the request is found here, before any process starts.
// `fresh`: no run may have a log folder yet (a resumed experiment has some).
Plan planExperiment(const ExperimentOptions& o, bool fresh) {
  Plan plan;
  plan.config_dir = o.config_dir.empty() ? std::string(AFFORD_SOURCE_DIR) + "/config" : o.config_dir;
  plan.exp = loadExperiment(plan.config_dir, o.experiment);
  plan.protocol = loadProtocol(plan.config_dir);
  const int reps = plan.reps = o.reps.value_or(plan.exp.repetitions);
  if (reps < 1) throw ConfigError("--reps must be at least 1");
  if (o.jobs < 1) throw ConfigError("--jobs must be at least 1");
  if (!o.attach.empty() && (o.jobs != 1 || o.transport != "udpm"))
    throw ConfigError("--attach runs one run at a time over the given bus: it needs --jobs 1 and --transport udpm");
  if (o.transport != "udpm" && o.transport != "memq")
    throw ConfigError("--transport must be udpm or memq, not \"" + o.transport + "\"");
  if (o.keep_logs != "all" && o.keep_logs != "first" && o.keep_logs != "none")
    throw ConfigError("--keep-logs must be all, first or none, not \"" + o.keep_logs + "\"");
  if (o.extrinsic_reps < 0) throw ConfigError("--extrinsic-reps must be 0 or more");
  plan.systems = !o.systems.empty() ? o.systems
                 : !plan.exp.default_systems.empty() ? plan.exp.default_systems
                                                     : std::vector<std::string>{"FIX", "IGN", "IMP"};
  if (plan.exp.extrinsic) plan.design = *plan.exp.extrinsic;
  plan.tests = o.extrinsic_reps > 0 ? o.extrinsic_reps : plan.design.tests;
  if ((o.tables || o.table_seed) && !plan.exp.tables)
    throw ConfigError("--tables and --table-seed are for experiments on random tables (a 'tables:' section, e.g. "
                      "random-tables); " + o.experiment + " has none");
  if (plan.exp.tables) {
    plan.tables = TablesDesign{o.tables.value_or(plan.exp.tables->count), o.table_seed.value_or(plan.exp.tables->seed)};
    if (plan.tables->count < 1) throw ConfigError("--tables must be at least 1");
    if (plan.tests > 0)
      throw ConfigError("random tables have no extrinsic tests: the scenarios assume the paper's Table 1 "
                        "(leave --extrinsic-reps out)");
    if (!plan.exp.conditions.empty()) plan.conditions_run = plan.exp.conditions;
  }
  if (plan.tests > 0) {
    const RunConfig any = parseRunConfig(effectiveConfig(plan.config_dir, RunRequest{o.experiment, System::IMP, o.seed, o.steps, o.settings}));
    plan.scenarios = !o.scenarios.empty() ? o.scenarios
                     : !plan.design.scenarios.empty() || plan.design.generate ? plan.design.scenarios
                                                                              : listScenarios(plan.config_dir);
    for (const auto& name : plan.scenarios)
      plan.sub_goals[name] = static_cast<int>(loadScenario(plan.config_dir, name, any.world).objects.size());
    if (o.scenarios.empty() && plan.design.generate) {  // drawn here, kept in the plan: nothing is written to config/
      const GenerateDesign& gen = *plan.design.generate;
      for (const ScenarioSpec& spec : designPoints(gen))
        for (int i = 0; i < gen.per_point; ++i) {
          GeneratedScenario g;
          try {
            g = generateScenario(any, spec, gen.seed, i);
          } catch (const std::exception& e) {
            throw ConfigError("extrinsic.generate: " + std::string(e.what()));
          }
          const std::string name = g.scenario.name;
          plan.scenarios.push_back(name);
          plan.sub_goals[name] = spec.sub_goals;
          plan.specs[name] = spec;
          plan.generated[name] = std::move(g.scenario);
        }
    }
    plan.conditions = conditionsOf(plan.design);
    for (const Condition& c : plan.conditions) {  // every combination must make a valid extrinsic config
      std::vector<std::string> settings = o.settings;
      for (const auto& [k, v] : c.settings) settings.push_back(k + "=" + v);
      const RunRequest req{o.experiment, System::IMP, o.seed, o.steps, settings};
      if (plan.generated.count(plan.scenarios.front()))
        extrinsicConfig(plan.config_dir, req, "unchecked", plan.generated.at(plan.scenarios.front()));
      else
        extrinsicConfig(plan.config_dir, req, "unchecked", plan.scenarios.front());
    }
  }
  const std::string prefix = o.run_prefix.empty() ? defaultPrefix() : o.run_prefix;
  auto& runs = plan.runs;
  auto& configs = plan.configs;
  // Random tables: table k of the series replaces the affordances of the world's objects.
  std::vector<ObjectSpec> drawn_for;  // the objects the tables are drawn for
  if (plan.tables) {
    drawn_for = parseRunConfig(effectiveConfig(plan.config_dir, RunRequest{o.experiment, System::IMP, o.seed, o.steps, o.settings}))
                    .world.objects;
    for (int k = 0; k < plan.tables->count; ++k) plan.table_list.push_back(randomTable(plan.tables->seed, k, drawn_for));
  }
  const int n_tables = plan.tables ? plan.tables->count : 1;
  for (int table = 0; table < n_tables; ++table)
  for (const auto& [condition, condition_settings] : plan.conditions_run)
  for (const auto& sys_name : plan.systems) {
    const System sys = parseSystem(sys_name);
    for (int r = 0; r < reps; ++r) {
      std::vector<std::string> settings = o.settings;
      settings.insert(settings.end(), condition_settings.begin(), condition_settings.end());
      RunRequest req{o.experiment, sys, o.seed + r, o.steps, settings};
      YAML::Node node;
      try {
        node = effectiveConfig(plan.config_dir, req);
      } catch (const ConfigError& e) {
        if (condition.empty()) throw;
        throw ConfigError("condition '" + condition + "' of " + o.experiment + ": " + e.what());
      }
      std::string run_id = prefix + "-" + o.experiment + "-";
      if (plan.tables) {
        const auto objects = parseRunConfig(node).world.objects;
        const auto same = [](const ObjectSpec& a, const ObjectSpec& b) { return a.shape == b.shape && a.colour == b.colour; };
        if (objects.size() != drawn_for.size() || !std::equal(objects.begin(), objects.end(), drawn_for.begin(), same))
          throw ConfigError("condition '" + condition + "' of " + o.experiment +
                            " changes world.objects, for which the random tables are drawn (their colours decide which "
                            "entries are 0): a condition may not change the objects' number, shapes or colours");
        char t[16];
        std::snprintf(t, sizeof t, "t%02d-", table);
        run_id += t + condition + (condition.empty() ? "" : "-");
        for (std::size_t i = 0; i < plan.table_list[table].size(); ++i) {
          YAML::Node aff = node["world"]["objects"][i]["affordance"];
          for (int a = 0; a < kNumActions; ++a) aff[a] = plan.table_list[table][i][a];
        }
      }
      run_id += sys_name + "-s" + std::to_string(o.seed + r);
      node["run"]["checkpoint"] = (fs::path(o.log_root) / run_id / "predictors.ckpt").string();
      const bool first = r == 0 && table == 0 && condition == plan.conditions_run.front().first;
      node["run"]["record"] = o.keep_logs == "all" || (o.keep_logs == "first" && first);
      if (plan.design.after_actions > 0) node["run"]["checkpoint_after_actions"] = plan.design.after_actions;
      const RunConfig cfg = parseRunConfig(node);
      if (!configs.count(sys_name)) configs[sys_name] = cfg;
      PlannedRun p;
      p.system = sys_name;
      p.table = plan.tables ? table : -1;
      p.intrinsic_condition = condition;
      for (const auto& ob : cfg.world.objects) p.target.emplace_back(ob.affordance.begin(), ob.affordance.end());
      p.keep_log = o.keep_logs == "all" || (o.keep_logs == "first" && first);
      p.spec.run_id = run_id;
      p.spec.experiment = o.experiment;
      p.spec.system = sys_name;
      p.spec.seed = o.seed + r;
      p.spec.steps = cfg.steps;
      p.spec.config_yaml = emitYaml(node);
      p.spec.processes = {"environment", "eye", "predictors", "motivation"};
      if (p.keep_log) p.spec.processes.push_back("logger");
      p.spec.stall_seconds = o.stall_seconds;
      p.index = runs.size();
      runs.push_back(std::move(p));
    }
  }

  // The run's folder holds its log and its checkpoint: a run never writes into another's.
  for (const auto& p : runs)
    if (fresh && fs::exists(fs::path(o.log_root) / p.spec.run_id))
      throw ConfigError("the log folder " + (fs::path(o.log_root) / p.spec.run_id).string() +
                        " exists already: choose another --run-prefix or --log-root");

  return plan;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& e : v) s += (s.empty() ? "" : " ") + e;
  return s;
}

// With --resume, a plan option given again must say what the stored experiment
// says (`stored`: its options; `plan`: what they resolved to).
void refuseChangedPlan(const ExperimentOptions& given, const ExperimentOptions& stored, const Plan& plan) {
  const auto check = [&](const std::string& option, const std::string& now, const std::string& then) {
    if (!given.given.count(option) || now == then) return;
    const std::string name = option == "name" ? "the experiment name" : option;
    throw ConfigError("--resume: " + name + " '" + now + "' differs from the stored experiment's '" + then +
                      "': a resumed experiment keeps its plan (leave " + name +
                      " out, or start a new experiment with another --out)");
  };
  const auto path = [](const std::string& p) { return fs::absolute(p).lexically_normal().string(); };
  check("name", given.experiment, stored.experiment);
  check("--system", joined(given.systems), joined(plan.systems));
  // 0 (or none) stands for the experiment's own count: nothing to compare
  if (given.reps) check("--reps", std::to_string(*given.reps), std::to_string(plan.reps));
  if (given.steps) check("--steps", std::to_string(*given.steps), std::to_string(plan.runs.front().spec.steps));
  if (given.extrinsic_reps > 0)
    check("--extrinsic-reps", std::to_string(given.extrinsic_reps), std::to_string(plan.tests));
  check("--seed", std::to_string(given.seed), std::to_string(stored.seed));
  check("--keep-logs", given.keep_logs, stored.keep_logs);
  check("--log-root", path(given.log_root), path(stored.log_root));
  check("--run-prefix", given.run_prefix, stored.run_prefix);
  check("--set", joined(given.settings), joined(stored.settings));
  check("--config-dir", path(given.config_dir), path(stored.config_dir));
  check("--scenarios", joined(given.scenarios), joined(plan.scenarios));
  if (given.tables) check("--tables", std::to_string(*given.tables), std::to_string(plan.tables ? plan.tables->count : 0));
  if (given.table_seed)
    check("--table-seed", std::to_string(*given.table_seed), std::to_string(plan.tables ? plan.tables->seed : 0));
}

// The runs of one phase (intrinsic runs, or extrinsic tests), in plan order.
struct PhaseRuns {
  std::vector<RunOutcome> outcomes;
  std::vector<char> finished;              // its outcome is final (it succeeded or failed) and kept in DIR/runs/
  std::map<std::size_t, std::string> cut;  // run index -> where a signal stopped it
  std::size_t finishedCount() const { return static_cast<std::size_t>(std::count(finished.begin(), finished.end(), 1)); }
};

// The outcomes kept by an earlier invocation (--resume); none on a fresh start.
PhaseRuns keptRuns(const std::vector<PlannedRun>& runs, const fs::path& out) {
  PhaseRuns phase;
  phase.outcomes.resize(runs.size());
  phase.finished.assign(runs.size(), 0);
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (auto r = keptOutcome(out, runs[i].spec.run_id)) {
      phase.outcomes[i] = std::move(*r);
      phase.finished[i] = 1;
    }
  return phase;
}

// A run that did not finish may have left its folder (an incomplete log): it
// is never reused nor deleted, but moved aside as <run-id>.cut-<k>, and the
// run starts afresh.
void moveUnfinishedAside(const std::vector<PlannedRun>& runs, const PhaseRuns& phase, const ExperimentOptions& o,
                         json& state, spdlog::logger& log) {
  bool moved = false;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const fs::path dir = fs::path(o.log_root) / runs[i].spec.run_id;
    if (phase.finished[i] || !fs::exists(dir)) continue;
    fs::path aside;
    for (int k = 1; fs::exists(aside = dir.string() + ".cut-" + std::to_string(k)); ++k) {
    }
    fs::rename(dir, aside);
    state["moved_aside"].push_back({{"run_id", runs[i].spec.run_id}, {"to", aside.string()}});
    log.info("run '{}' did not finish: its folder is now {}; the run starts again", runs[i].spec.run_id, aside.string());
    moved = true;
  }
  if (moved) writeWhole(statePath(o.out_dir), state.dump(2) + "\n");
}

// Run every planned run not finished yet, J at a time, and keep each outcome
// in DIR/runs/ as it comes. After a SIGINT or SIGTERM no run starts; a run it
// stopped is cut, not finished.
void executeRuns(const std::vector<PlannedRun>& runs, PhaseRuns& phase, const ExperimentOptions& o,
                 const ProtocolConfig& protocol, const std::string& bin, spdlog::logger& log) {
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (!phase.finished[i]) todo.push_back(i);
  std::atomic<std::size_t> next{0};
  std::size_t done = phase.finishedCount();
  std::mutex mutex;
  auto worker = [&](int slot_index) {
    Slot slot;
    slot.index = slot_index;
    // A 2 MB receive buffer per socket (the kernel's default is 208 KB): every process hears every
    // datagram of its slot, and one descheduled for a while must not lose any (the kernel caps the
    // request at net.core.rmem_max).
    slot.url = "udpm://239.255.76.67:" + std::to_string(o.base_port + slot_index) + "?ttl=0&recv_buf_size=2097152";
    if (!o.attach.empty()) slot.url = o.attach;
    for (std::size_t k; !stopRequested() && (k = next.fetch_add(1)) < todo.size();) {
      const std::size_t i = todo[k];
      const std::string& id = runs[i].spec.run_id;
      RunOutcome r;
      try {
        r = o.transport == "memq" ? runInProcess(runs[i], o, protocol, slot_index)
                                  : runOverUdpm(runs[i], o, protocol, slot, bin);
      } catch (const std::exception& e) {
        r.ok = false;
        r.error = "run '" + id + "': " + e.what();
      }
      // A run that fails while the processes are being stopped failed because of it: cut too.
      const bool cut = r.interrupted || (!r.ok && stopRequested());
      if (r.ok && !r.log_dir.empty()) {
        std::error_code ec;
        for (const auto& f : fs::directory_iterator(r.log_dir, ec))
          if (f.path().extension() == ".lcm") r.log_bytes += fs::file_size(f.path(), ec);
      }
      if (!cut) try {
          keepOutcome(o.out_dir, id, r);
        } catch (const std::exception& e) {
          log.error("cannot keep the outcome of run '{}' ({}): --resume would run it again", id, e.what());
        }
      std::lock_guard<std::mutex> lock(mutex);
      if (cut) {
        const std::string prefix = "run '" + id + "': ";
        std::string where = r.error.rfind(prefix, 0) == 0 ? r.error.substr(prefix.size()) : r.error;
        // (The step is the last one the processes reported, in their heartbeats.)
        if (const std::string none = "at step -1"; where.size() > none.size() && where.substr(where.size() - none.size()) == none)
          where = where.substr(0, where.size() - none.size()) + "before any step was reported";
        phase.cut[i] = where;
        log.warn("{}: {}", id, phase.cut[i]);
        continue;
      }
      phase.outcomes[i] = std::move(r);
      phase.finished[i] = 1;
      const RunOutcome& out = phase.outcomes[i];
      ++done;
      if (out.ok && runs[i].spec.extrinsic)
        log.info("[{}/{}] {}: {}, {} action(s), utility {}", done, runs.size(), id,
                 out.extrinsic.success ? "solved in " + std::to_string(out.extrinsic.completion) + " steps" : "not solved",
                 out.extrinsic.attempts, out.extrinsic.utility);
      else if (out.ok)
        log.info("[{}/{}] {} done in {:.1f} s, weights {}", done, runs.size(), id, out.wall_seconds,
                 out.weights_checksum);
      else
        log.error("[{}/{}] {}", done, runs.size(), out.error);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::min<int>(o.jobs, static_cast<int>(todo.size())); ++j) threads.emplace_back(worker, j);
  for (auto& t : threads) t.join();
}

// The tests of every condition and scenario from each intrinsic run that left
// a checkpoint. An agent without the checkpoint the design asks for (not
// written, or too few actions for extrinsic.after_actions) is not tested;
// `errors` says why.
std::vector<PlannedRun> planExtrinsic(const Plan& plan, const std::vector<RunOutcome>& trained,
                                      const ExperimentOptions& o, std::vector<std::string>& errors) {
  std::vector<PlannedRun> tests;
  for (const auto& p : plan.runs) {
    const RunOutcome& r = trained[p.index];
    if (!r.ok) continue;  // a failed run is reported as such
    if (r.checkpoint.empty()) {
      errors.push_back("run '" + p.spec.run_id + "' left no checkpoint of its predictors (they could not write it: " +
                       "see their log), so its agent is not tested");
      continue;
    }
    std::string checkpoint = r.checkpoint;
    if (plan.design.after_actions > 0) {
      checkpoint = actionsCheckpoint(r.checkpoint, plan.design.after_actions);
      if (!fs::exists(checkpoint)) {
        errors.push_back("run '" + p.spec.run_id + "' executed fewer than " + std::to_string(plan.design.after_actions) +
                         " actions, so it has no " + checkpoint + " (extrinsic.after_actions): give it more run.steps");
        continue;
      }
    }
    for (std::size_t c = 0; c < plan.conditions.size(); ++c)
      for (std::size_t k = 0; k < plan.scenarios.size(); ++k)
        for (int e = 0; e < plan.tests; ++e) {
          PlannedRun t;
          t.system = p.system;
          t.intrinsic = p.index;
          t.scenario = plan.scenarios[k];
          t.condition = static_cast<int>(c);
          t.rep = e;
          t.keep_log = o.keep_logs == "all" || (o.keep_logs == "first" && p.keep_log && e == 0);
          // Each test its own seed, derived from the intrinsic run's (documented in docs/experiments.md);
          // the conditions share seeds, so they meet the same draws.
          const std::int64_t seed = p.spec.seed * 1'000'000 + static_cast<std::int64_t>(k + 1) * 1000 + e;
          std::vector<std::string> settings = o.settings;
          for (const auto& [key, value] : plan.conditions[c].settings) settings.push_back(key + "=" + value);
          const RunRequest req{o.experiment, parseSystem(p.system), seed, std::nullopt, settings};
          const auto gen = plan.generated.find(t.scenario);
          YAML::Node node = gen != plan.generated.end() ? extrinsicConfig(plan.config_dir, req, checkpoint, gen->second)
                                                        : extrinsicConfig(plan.config_dir, req, checkpoint, t.scenario);
          node["run"]["record"] = t.keep_log;
          t.spec.run_id = p.spec.run_id + (plan.conditions.size() > 1 ? "-c" + std::to_string(c) : "") + "-" +
                          t.scenario + "-e" + std::to_string(e);
          t.spec.experiment = o.experiment;
          t.spec.system = p.system;
          t.spec.seed = seed;
          t.spec.steps = node["run"]["steps"].as<std::int64_t>();
          t.spec.config_yaml = emitYaml(node);
          t.spec.extrinsic = true;
          t.spec.processes = {"environment", "eye", "predictors", "planner"};
          if (t.keep_log) t.spec.processes.push_back("logger");
          t.spec.stall_seconds = o.stall_seconds;
          t.index = tests.size();
          tests.push_back(std::move(t));
        }
  }
  return tests;
}

// Per system: the paper's Table 2 metric, raw success, completion steps and
// their fit a x^2 + b x (Figure 6), actions checked per sub-goal; and a CSV.
// Only the finished tests count (all of them, unless a signal stopped the phase).
void summariseExtrinsic(json& summary, const Plan& plan, const std::vector<PlannedRun>& tests, const PhaseRuns& phase,
                        const ExperimentOptions& o) {
  const auto& outcomes = phase.outcomes;
  for (const auto& sys : plan.systems) {
    std::ostringstream csv;
    csv << "system,intrinsic_run_id,seed,scenario,condition,rep,success,completion,attempts,utility,sub_goals,"
           "active_sub_goals,actions_checked,wall_seconds\n";
    for (const auto& t : tests) {
      if (t.system != sys || !phase.finished[t.index]) continue;
      const RunOutcome& r = outcomes[t.index];
      int checks = 0, active = 0;
      for (const auto& g : r.extrinsic.sub_goals) checks += g.actions_checked, active += g.iterations > 0;
      csv << sys << "," << plan.runs[t.intrinsic].spec.run_id << "," << t.spec.seed << "," << t.scenario << ",\""
          << plan.conditions[t.condition].label << "\"," << t.rep << "," << (r.ok && r.extrinsic.success) << ","
          << r.extrinsic.completion << "," << r.extrinsic.attempts << "," << r.extrinsic.utility << ","
          << r.extrinsic.sub_goals.size() << "," << active << "," << checks << "," << r.wall_seconds << "\n";
    }
    writeWhole(fs::path(o.out_dir) / ("extrinsic_" + sys + ".csv"), csv.str());
    json ex = {{"scenarios", plan.scenarios}, {"tests_per_scenario", plan.tests}};
    if (plan.conditions.size() > 1) {  // the design's summary compares the conditions
      summary["systems"][sys]["extrinsic"] = ex;
      continue;
    }
    std::vector<std::pair<double, double>> solved;  // (sub-goals, completion) of every solved test
    for (const auto& scenario : plan.scenarios) {
      std::map<std::size_t, std::pair<int, int>> per_run;  // intrinsic run -> (successes, tests)
      std::vector<double> steps;
      double checked = 0;
      int sub_goal_count = 0, successes = 0, total = 0;
      for (const auto& t : tests) {
        if (t.system != sys || t.scenario != scenario || !phase.finished[t.index]) continue;
        const RunOutcome& r = outcomes[t.index];
        const bool ok = r.ok && r.extrinsic.success;
        auto& [s, n] = per_run[t.intrinsic];
        s += ok;
        ++n;
        successes += ok;
        ++total;
        int checks = 0;
        for (const auto& g : r.extrinsic.sub_goals) checks += g.actions_checked;
        checked += checks;
        sub_goal_count += static_cast<int>(r.extrinsic.sub_goals.size());
        if (ok) {
          steps.push_back(r.extrinsic.completion);
          solved.emplace_back(plan.sub_goals.at(scenario), r.extrinsic.completion);
        }
      }
      int good_runs = 0;
      for (const auto& [run, sn] : per_run) good_runs += sn.first > 0.9 * sn.second;
      std::sort(steps.begin(), steps.end());
      double mean = 0;
      for (double v : steps) mean += v / steps.size();
      ex["table_metric"][scenario] = per_run.empty() ? 0.0 : static_cast<double>(good_runs) / per_run.size();
      ex["success_rate"][scenario] = total ? static_cast<double>(successes) / total : 0.0;
      ex["completion_steps"][scenario] = {{"n", steps.size()},
                                          {"sub_goals", plan.sub_goals.at(scenario)},
                                          {"median", quantile(steps, 0.5)},
                                          {"q1", quantile(steps, 0.25)},
                                          {"q3", quantile(steps, 0.75)},
                                          {"min", steps.empty() ? 0.0 : steps.front()},
                                          {"max", steps.empty() ? 0.0 : steps.back()},
                                          {"mean", mean}};
      ex["actions_checked_per_sub_goal"][scenario] = sub_goal_count ? checked / sub_goal_count : 0.0;
    }
    if (const auto fit = fitCompletion(solved)) ex["completion_steps"]["fit"] = {{"a", fit->a}, {"b", fit->b}};
    summary["systems"][sys]["extrinsic"] = ex;
  }
}

// Random tables (issue 11): per condition and system, each table's mean
// absolute error (mean over its runs), their mean, quartiles and the worst
// table; and random_tables.csv, random_tables_entries.csv.
json summariseTables(const Plan& plan, const PhaseRuns& phase, const ExperimentOptions& o) {
  const auto label = [](const std::string& c) { return c.empty() ? std::string("default") : c; };
  std::vector<std::string> names;
  for (const auto& ob : plan.configs.begin()->second.world.objects) names.push_back(ob.name);
  const auto names_of = [&](std::size_t i) { return names[i]; };
  json rt = {{"seed", plan.tables->seed}, {"count", plan.tables->count}, {"tables", plan.table_list},
             {"conditions", json::object()}, {"mae", json::object()}};
  rt["one_way_looks"] = json::array();  // per table: the objects whose look cannot come back once left
  for (const auto& table : plan.table_list) {
    json names = json::array();
    for (std::size_t i : oneWayLooks(table, plan.configs.begin()->second.world.objects)) names.push_back(names_of(i));
    rt["one_way_looks"].push_back(names);
  }
  rt["condition_order"] = json::array();
  rt["system_order"] = plan.systems;
  for (const auto& [c, settings] : plan.conditions_run) {
    rt["conditions"][label(c)] = settings;
    rt["condition_order"].push_back(label(c));
  }
  std::ostringstream csv, entries;
  csv << "table,condition,system,seed,run_id,mae\n";
  entries << "table,object,action,afforded\n";
  for (std::size_t k = 0; k < plan.table_list.size(); ++k)
    for (std::size_t i = 0; i < plan.table_list[k].size(); ++i)
      for (int a = 0; a < kNumActions; ++a)
        entries << k << ",\"" << names[i] << "\"," << kActionNames[a] << "," << plan.table_list[k][i][a] << "\n";
  for (const auto& [c, settings] : plan.conditions_run)
    for (const auto& sys : plan.systems) {
      std::vector<double> sum(plan.table_list.size(), 0.0);
      std::vector<int> n(plan.table_list.size(), 0);
      for (const auto& p : plan.runs) {
        if (p.intrinsic_condition != c || p.system != sys || !phase.finished[p.index]) continue;
        const RunOutcome& r = phase.outcomes[p.index];
        if (!r.ok || r.curve.empty()) continue;
        const double mae = meanAbsError(r.curve.back().affordance, p.target);
        sum[static_cast<std::size_t>(p.table)] += mae;
        ++n[static_cast<std::size_t>(p.table)];
        csv << p.table << "," << label(c) << "," << sys << "," << p.spec.seed << "," << p.spec.run_id << "," << mae << "\n";
      }
      json per_table = json::array();
      std::vector<double> values;
      int worst = -1;
      for (std::size_t k = 0; k < sum.size(); ++k) {
        if (!n[k]) {
          per_table.push_back(nullptr);
          continue;
        }
        per_table.push_back(sum[k] / n[k]);
        values.push_back(sum[k] / n[k]);
        if (worst < 0 || sum[k] / n[k] > per_table[static_cast<std::size_t>(worst)].get<double>()) worst = static_cast<int>(k);
      }
      std::vector<double> sorted = values;
      std::sort(sorted.begin(), sorted.end());
      double mean = 0;
      for (double v : values) mean += v / values.size();
      rt["mae"][label(c)][sys] = {{"per_table", per_table},
                                  {"tables", values.size()},
                                  {"mean", values.empty() ? json(nullptr) : json(mean)},
                                  {"median", quantile(sorted, 0.5)},
                                  {"q1", quantile(sorted, 0.25)},
                                  {"q3", quantile(sorted, 0.75)},
                                  {"min", sorted.empty() ? json(nullptr) : json(sorted.front())},
                                  {"worst", sorted.empty() ? json(nullptr) : json(sorted.back())},
                                  {"worst_table", worst}};
    }
  writeWhole(fs::path(o.out_dir) / "random_tables.csv", csv.str());
  writeWhole(fs::path(o.out_dir) / "random_tables_entries.csv", entries.str());
  return rt;
}

// summary.json content (docs/results-schema.md) of the finished runs; also writes the CSV files.
json summarise(const Plan& plan, const ExperimentOptions& o, const PhaseRuns& phase, const std::string& network) {
  const auto& outcomes = phase.outcomes;
  const auto& runs = plan.runs;
  const auto& configs = plan.configs;
  const int reps = plan.reps;
  const auto& exp = plan.exp;
  const std::string& config_dir = plan.config_dir;
  const auto& any_cfg = configs.begin()->second;
  std::vector<std::string> object_names;
  for (const auto& ob : any_cfg.world.objects) object_names.push_back(ob.name);
  json summary = {{"experiment", o.experiment},
                  {"description", exp.description},
                  {"steps", runs.front().spec.steps},
                  {"repetitions", reps},
                  {"seed", o.seed},
                  {"transport", o.transport},
                  {"network", network},
                  {"afford_version", AFFORD_VERSION},
                  {"objects", object_names},
                  {"actions", {"move", "turn green", "turn red", "turn blue"}},
                  {"systems", json::object()}};
  YAML::Node reference;
  try {
    reference = YAML::LoadFile(config_dir + "/reference.yaml")[o.experiment];
  } catch (const YAML::Exception&) {
  }
  for (const auto& sys : plan.systems) {
    const RunConfig& cfg = configs.at(sys);
    Table target;
    for (const auto& ob : cfg.world.objects) target.emplace_back(ob.affordance.begin(), ob.affordance.end());
    json js = {{"target", target}, {"runs", json::array()}};
    std::vector<Table> finals;
    std::vector<double> maes;
    std::ostringstream curves_csv;
    curves_csv << "system,run_id,seed,step,object,action,prediction\n";
    std::map<std::int64_t, std::pair<Table, int>> curve_sum;
    for (const auto& p : runs) {
      if (p.system != sys || !phase.finished[p.index]) continue;
      const RunOutcome& r = outcomes[p.index];
      if (!r.ok || r.curve.empty()) {
        js["failed_runs"].push_back({{"run_id", p.spec.run_id}, {"seed", p.spec.seed}, {"error", r.error}});
        continue;
      }
      // Every run reports its table at the same steps (run.curve_interval): a snapshot lost on the
      // way would bias the mean curve at that step, so say so.
      if (r.curve.size() != static_cast<std::size_t>(cfg.steps / cfg.curve_interval + 1) + (cfg.steps % cfg.curve_interval != 0))
        js["curve_gaps"].push_back({{"run_id", p.spec.run_id}, {"snapshots", r.curve.size()}});
      const Table& fin = r.curve.back().affordance;
      finals.push_back(fin);
      maes.push_back(meanAbsError(fin, p.target));
      json entry = {{"run_id", p.spec.run_id},
                    {"seed", p.spec.seed},
                    {"affordance", fin},
                    {"affordance_mae", maes.back()},
                    {"weights_checksum", r.weights_checksum},
                    {"actions_executed", r.executed},
                    {"successes", r.successes},
                    {"looks", r.looks},
                    {"replayed", r.replayed},
                    {"replayed_effects", r.replayed_effects},
                    {"revisits", r.revisits},
                    {"wall_seconds", r.wall_seconds},
                    {"steps_per_second", r.run_seconds > 0 ? p.spec.steps / r.run_seconds : 0.0}};
      if (plan.tables) {  // random tables: each run against its own table; no mean table or curve across them
        entry["table"] = p.table;
        entry["condition"] = p.intrinsic_condition.empty() ? std::string("default") : p.intrinsic_condition;
        entry["target"] = p.target;
        js["runs"].push_back(entry);
        continue;
      }
      entry["log_dir"] = r.log_dir.empty() ? json(nullptr) : json(r.log_dir);
      entry["checkpoint"] = r.checkpoint;
      entry["peak_rss_kb"] = r.peak_rss_kb;
      entry["log_bytes"] = r.log_bytes;
      entry["log_bytes_per_step"] = static_cast<double>(r.log_bytes) / p.spec.steps;
      js["runs"].push_back(entry);
      for (const auto& snap : r.curve) {
        auto& [sum, n] = curve_sum[snap.step];
        if (sum.empty()) sum = Table(snap.affordance.size(), std::vector<double>(kNumActions, 0.0));
        for (std::size_t i = 0; i < snap.affordance.size(); ++i)
          for (int a = 0; a < kNumActions; ++a) {
            sum[i][a] += snap.affordance[i][a];
            curves_csv << sys << "," << p.spec.run_id << "," << p.spec.seed << "," << snap.step << ",\""
                       << object_names[i] << "\"," << kActionNames[a] << "," << snap.affordance[i][a] << "\n";
          }
        ++n;
      }
    }
    if (!finals.empty() && !plan.tables) {
      Table mean = target, mn = target, mx = target;
      for (std::size_t i = 0; i < target.size(); ++i)
        for (int a = 0; a < kNumActions; ++a) {
          double s = 0, lo = 1e9, hi = -1e9;
          for (const auto& f : finals) {
            s += f[i][a];
            lo = std::min(lo, f[i][a]);
            hi = std::max(hi, f[i][a]);
          }
          mean[i][a] = s / finals.size();
          mn[i][a] = lo;
          mx[i][a] = hi;
        }
      double mae_sum = 0;
      for (double m : maes) mae_sum += m;
      js["affordance"] = mean;
      js["affordance_min"] = mn;
      js["affordance_max"] = mx;
      js["affordance_mae"] = mae_sum / maes.size();
      js["affordance_mae_of_mean"] = meanAbsError(mean, target);
      json steps = json::array(), means = json::array();
      for (auto& [step, sn] : curve_sum) {
        auto& [sum, n] = sn;
        for (auto& row : sum)
          for (auto& v : row) v /= n;
        steps.push_back(step);
        means.push_back(sum);
      }
      js["curves"] = {{"steps", steps}, {"mean", means}};
      std::ostringstream csv;
      csv << "system,object,action,target,mean,min,max\n";
      for (std::size_t i = 0; i < target.size(); ++i)
        for (int a = 0; a < kNumActions; ++a)
          csv << sys << ",\"" << object_names[i] << "\"," << kActionNames[a] << "," << target[i][a] << ","
              << mean[i][a] << "," << mn[i][a] << "," << mx[i][a] << "\n";
      writeWhole(fs::path(o.out_dir) / ("affordance_" + sys + ".csv"), csv.str());
    }
    if (!plan.tables) writeWhole(fs::path(o.out_dir) / ("curves_" + sys + ".csv"), curves_csv.str());
    if (plan.tables) js.erase("target");
    if (reference && reference["affordance_mae"] && reference["affordance_mae"][sys])
      js["reference_affordance_mae"] = reference["affordance_mae"][sys].as<double>();
    summary["systems"][sys] = js;
  }
  if (reference && reference["source"]) summary["reference_source"] = reference["source"].as<std::string>();
  if (plan.tables) {
    summary["random_tables"] = summariseTables(plan, phase, o);
    if (reference && reference["floors"])  // what issue 11 asks of the memory options, shown beside
      summary["random_tables"]["floors"] = {{"mean", reference["floors"]["mean"].as<double>()},
                                            {"worst", reference["floors"]["worst"].as<double>()},
                                            {"source", reference["floors"]["source"].as<std::string>()}};
  }
  try {  // the paper's extrinsic tables, for the same experiment
    const YAML::Node ext = YAML::LoadFile(config_dir + "/reference.yaml")[o.experiment + "_extrinsic"];
    if (ext && ext["table_metric"])
      for (const auto& sys : plan.systems)
        if (ext["table_metric"][sys]) {  // the paper's scenarios 1-5
          const auto row = ext["table_metric"][sys].as<std::vector<double>>();
          for (std::size_t k = 0; k < row.size(); ++k)
            summary["systems"][sys]["reference_table_metric"]["scenario" + std::to_string(k + 1)] = row[k];
        }
    if (ext && ext["completion_fit"])
      summary["reference_completion_fit"] = {{"a", ext["completion_fit"]["a"].as<double>()},
                                             {"b", ext["completion_fit"]["b"].as<double>()}};
    if (ext && ext["source"]) summary["reference_extrinsic_source"] = ext["source"].as<std::string>();
  } catch (const YAML::Exception&) {
  }
  return summary;
}

// The mean learned table of each system beside the experiment's table.
void printTables(const json& summary, const Plan& plan, const ExperimentOptions& o) {
  const auto& runs_steps = summary["steps"];
  const auto object_names = summary["objects"].get<std::vector<std::string>>();
  const int reps = summary["repetitions"].get<int>();
  std::ostringstream t;
  if (summary.contains("random_tables")) {  // no one table to show: the error on each run's own
    const json& rt = summary["random_tables"];
    t << "\nRandom affordance tables: " << rt["count"].get<int>() << " tables drawn from seed " << rt["seed"].get<std::int64_t>()
      << ", " << runs_steps.get<std::int64_t>() << " steps, " << reps
      << " run(s) per table, system and condition.\nMean absolute error of each run's learned table against its own table";
    if (rt.contains("floors"))
      t << "; " << rt["floors"]["source"].get<std::string>();
    t << "\n\n  condition    system   mean     median   worst (table)\n";
    std::vector<std::pair<std::string, std::string>> columns;
    for (const auto& cj : rt["condition_order"])
      for (const auto& sj : rt["system_order"]) {
        const std::string c = cj.get<std::string>(), sys = sj.get<std::string>();
        const json& m = rt["mae"][c][sys];
        columns.emplace_back(c, sys);
        const auto num = [](const json& v) { return v.is_null() ? std::string("-") : fixed(v.get<double>(), 3); };
        t << "  " << std::left << std::setw(13) << c << std::setw(9) << sys << std::setw(9) << num(m["mean"])
          << std::setw(9) << num(m["median"]) << num(m["worst"])
          << (m["worst_table"].get<int>() >= 0 ? " (t" + std::to_string(m["worst_table"].get<int>()) + ")" : "") << "\n";
      }
    const auto width = [](const std::string& c, const std::string& sys) {
      return std::max<int>(9, static_cast<int>(c.size() + sys.size()) + 3);
    };
    t << "\n  table ";
    for (const auto& [c, sys] : columns) t << std::right << std::setw(width(c, sys)) << (sys + " " + c);
    t << "   one-way looks (docs/model.md#revisit)\n";
    for (int k = 0; k < rt["count"].get<int>(); ++k) {
      t << "  t" << std::left << std::setw(5) << k << std::right;
      for (const auto& [c, sys] : columns) {
        const json& v = rt["mae"][c][sys]["per_table"][static_cast<std::size_t>(k)];
        t << std::setw(width(c, sys)) << (v.is_null() ? std::string("-") : fixed(v.get<double>(), 3));
      }
      std::string one_way;
      for (const auto& n : rt["one_way_looks"][static_cast<std::size_t>(k)]) one_way += (one_way.empty() ? "" : ", ") + n.get<std::string>();
      t << "   " << (one_way.empty() ? "-" : one_way);
      t << "\n";
    }
  } else {
  t << "\nLearned affordances after " << runs_steps.get<std::int64_t>() << " steps (mean of " << reps
    << " run(s)); in brackets the paper's table\n";
  for (const auto& sys : plan.systems) {
    const json& js = summary["systems"][sys];
    if (!js.contains("affordance")) continue;
    std::size_t name_width = 17;
    for (const auto& n : object_names) name_width = std::max(name_width, n.size() + 1);
    t << "\n" << std::left << std::setw(static_cast<int>(name_width) + 2) << sys
      << "move        turn green  turn red    turn blue\n";
    for (std::size_t i = 0; i < object_names.size(); ++i) {
      t << "  " << std::left << std::setw(static_cast<int>(name_width)) << object_names[i];
      for (int a = 0; a < kNumActions; ++a)
        t << std::setw(12)
          << (fixed(js["affordance"][i][a].get<double>(), 2) + " (" + fixed(js["target"][i][a].get<double>(), 1) + ")");
      t << "\n";
    }
    t << "  mean absolute error " << fixed(js["affordance_mae"].get<double>(), 3);
    if (js.contains("reference_affordance_mae"))
      t << " (authors' code: " << fixed(js["reference_affordance_mae"].get<double>(), 3) << ")";
    t << "\n";
  }
  }
  bool header = false;
  for (const auto& sys : plan.systems) {
    const json& js = summary["systems"][sys];
    if (!js.contains("extrinsic") || !js["extrinsic"].contains("table_metric")) continue;
    const json& ex = js["extrinsic"];
    if (!header) {
      t << "\nExtrinsic tests (" << ex["tests_per_scenario"].get<int>()
        << " per scenario and trained agent): table metric = share of agents with > 90% of their tests\n"
           "solved; in brackets the paper's; then the raw share of tests solved\n\n"
        << "       ";
      for (const auto& s : ex["scenarios"]) t << std::setw(14) << s.get<std::string>();
      t << "\n";
      header = true;
    }
    t << "  " << std::left << std::setw(5) << sys << std::right;
    for (const auto& s : ex["scenarios"]) {
      const std::string name = s.get<std::string>();
      std::string cell = fixed(ex["table_metric"][name].get<double>(), 2);
      if (js.contains("reference_table_metric") && js["reference_table_metric"].contains(name))
        cell += " (" + fixed(js["reference_table_metric"][name].get<double>(), 1) + ")";
      t << std::setw(14) << cell;
    }
    t << "\n  " << std::setw(5) << "" << std::right;
    for (const auto& s : ex["scenarios"]) t << std::setw(14) << fixed(ex["success_rate"][s.get<std::string>()].get<double>(), 2);
    t << "\n";
  }
  if (header) {
    t << "\nCompletion steps (median over solved tests) by number of sub-goals; fit a x^2 + b x";
    if (summary.contains("reference_completion_fit"))
      t << " (paper, IMP: " << fixed(summary["reference_completion_fit"]["a"].get<double>(), 3) << " x^2 "
        << fixed(summary["reference_completion_fit"]["b"].get<double>(), 3) << " x)";
    t << "\n";
    for (const auto& sys : plan.systems) {
      const json& js = summary["systems"][sys];
      if (!js.contains("extrinsic") || !js["extrinsic"].contains("completion_steps")) continue;
      const json& cs = js["extrinsic"]["completion_steps"];
      t << "  " << std::left << std::setw(5) << sys << std::right;
      for (const auto& s : js["extrinsic"]["scenarios"]) {
        const json& c = cs[s.get<std::string>()];  // none solved: no median to show
        t << std::setw(14) << (c["n"].get<int>() ? fixed(c["median"].get<double>(), 1) : std::string("-"));
      }
      if (cs.contains("fit"))
        t << "   fit " << fixed(cs["fit"]["a"].get<double>(), 3) << " x^2 " << fixed(cs["fit"]["b"].get<double>(), 3) << " x";
      t << "\n";
    }
  }
  const auto p = [](const json& v) { return v.is_null() ? std::string("-") : fixed(v.get<double>(), 4); };
  if (summary.contains("utility")) {  // Figure 12
    const json& u = summary["utility"];
    t << "\nUtility gained per test (" << u["system"].get<std::string>() << ", " << u["scenario"].get<std::string>()
      << "): goal-based vs utility-based planner, Welch's t-test\n  budget   goal     utility  p\n" << std::left;
    for (std::size_t k = 0; k < u["budgets"].size(); ++k)
      t << "  " << std::setw(6) << u["budgets"][k].get<int>() << "   " << fixed(u["goal_mean"][k].get<double>(), 3)
        << "    " << fixed(u["utility_mean"][k].get<double>(), 3) << "    " << p(u["p_values"][k]) << "\n";
  }
  if (summary.contains("forward_models")) {  // Figure 13
    const json& f = summary["forward_models"];
    t << "\nMean utility of the utility planner with agents trained for " << plan.design.after_actions
      << " actions, by action budget\n  " << std::left << std::setw(12) << "system" << std::right;
    for (const auto& b : f["budgets"]) t << std::setw(10) << b.get<int>();
    t << "\n";
    for (const auto& sys : plan.systems) {
      t << "  " << std::left << std::setw(12) << sys << std::right;
      for (const auto& m : summary["systems"][sys]["utility_mean"]) t << std::setw(10) << fixed(m.get<double>(), 3);
      t << "\n";
    }
    for (const auto& [pair, ps] : f["p_values"].items()) {
      t << "  " << std::left << std::setw(12) << ("p " + pair) << std::right;
      for (const auto& v : ps) t << std::setw(10) << p(v);
      t << "\n";
    }
  }
  if (summary.contains("search")) {  // Figure 14
    const json& s = summary["search"];
    t << "\nActions checked per sub-goal (" << s["system"].get<std::string>() << "): with affordance restriction "
      << fixed(s["restricted_mean"].get<double>(), 3) << ", without " << fixed(s["unrestricted_mean"].get<double>(), 3)
      << "; Welch's t-test p = " << (s["p_value"].is_null() ? std::string("-") : fmt::format("{:.3g}", s["p_value"].get<double>()))
      << "\n";
  }
  t << "\nsummary: " << (fs::path(o.out_dir) / "summary.json").string() << "\n";
  std::printf("%s", t.str().c_str());
  std::fflush(stdout);
}

// After a SIGINT or SIGTERM, once the runs under way have stopped: the summary
// of what finished, where the others stopped, and the command that goes on.
// `summary` holds what finished; `phase` is "intrinsic" or "extrinsic".
int stopHere(json& summary, const std::string& phase_name, const std::vector<PlannedRun>& runs, const PhaseRuns& phase,
             bool extrinsic_to_come, const ExperimentOptions& o, json& state, spdlog::logger& log) {
  const std::string signal = signalName(g_signal);
  json cut = json::array(), not_started = json::array();
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (phase.finished[i]) continue;
    const std::string& id = runs[i].spec.run_id;
    const fs::path dir = fs::path(o.log_root) / id;
    if (auto c = phase.cut.find(i); c != phase.cut.end())
      cut.push_back({{"run_id", id}, {"where", c->second}, {"log_dir", fs::exists(dir) ? json(dir.string()) : json(nullptr)}});
    else
      not_started.push_back(id);
  }
  const std::string command = resumeCommand(o);
  const std::string cwd = fs::current_path().string();
  summary["interrupted"] = {{"signal", signal},
                            {"phase", phase_name},
                            {"finished", phase.finishedCount()},
                            {"planned", runs.size()},
                            {"cut", cut},
                            {"not_started", not_started},
                            {"extrinsic_tests_to_come", extrinsic_to_come},
                            {"resume", command},
                            {"resume_in", cwd}};
  writeWhole(fs::path(o.out_dir) / "summary.json", summary.dump(2) + "\n");
  state["state"] = "interrupted";
  state["interruptions"].push_back({{"signal", signal}, {"phase", phase_name}, {"cut", cut}});
  writeWhole(statePath(o.out_dir), state.dump(2) + "\n");

  const std::string what = phase_name == "intrinsic" ? "intrinsic run(s)" : "extrinsic test(s)";
  log.warn("interrupted by {} during the {} phase", signal, phase_name);
  log.info("kept: {} of {} {} finished{}, in {} and the CSV files beside it", phase.finishedCount(), runs.size(), what,
           phase_name == "extrinsic" ? " (and every intrinsic run)" : "",
           (fs::path(o.out_dir) / "summary.json").string());
  for (const auto& c : cut)
    log.info("cut: {} ({}){}", c["run_id"].get<std::string>(), c["where"].get<std::string>(),
             c["log_dir"].is_null() ? std::string()
                                    : "; its log, incomplete, stays in " + c["log_dir"].get<std::string>());
  if (!not_started.empty()) log.info("not started: {} {}", not_started.size(), what);
  if (extrinsic_to_come) log.info("not started: the extrinsic tests");
  log.warn("to resume (in {}): {}", cwd, command);
  return 128 + g_signal;
}

}  // namespace

int runExperiment(const ExperimentOptions& request, spdlog::logger& log) {
  const auto began = std::chrono::steady_clock::now();  // reported only, never decides anything
  // Everything is checked before anything is written or started.
  json state;
  ExperimentOptions o = request;
  if (request.resume) {
    state = unfinishedState(request);
    o = resumedOptions(request, state);
  } else {
    refuseUnfinished(request);
    if (o.run_prefix.empty()) o.run_prefix = defaultPrefix();  // stored: --resume plans the same run ids
  }
  const Plan plan = planExperiment(o, /*fresh=*/!o.resume);
  if (o.resume) {
    refuseChangedPlan(request, optionsFromJson(state.at("options")), plan);
    refuseOtherPlan(state.at("runs"), fingerprint(plan.runs), "intrinsic runs");
  }
  std::string network = "in-process memq://";
  std::string bin;
  if (!o.attach.empty()) {
    network = "attached to " + o.attach;
  } else if (o.transport == "udpm") {
    network = prepareNetwork(o.netns);
    bin = executableDir();
  }
  // From here a signal stops the experiment in order, whenever it comes.
  installInterruptHandlers(resumeCommand(o));
  const fs::path out = o.out_dir;
  fs::create_directories(out);
  lockOutDir(out);
  if (!o.resume) {
    fs::remove_all(out / "runs");  // the outcomes of the finished experiment this one replaces
    state = {{"experiment", o.experiment},
             {"cwd", fs::current_path().string()},
             {"options", optionsToJson(o)},
             {"runs", fingerprint(plan.runs)},
             {"interruptions", json::array()},
             {"moved_aside", json::array()}};
  }
  state["state"] = "running";
  state["resume"] = resumeCommand(o);
  writeWhole(statePath(out), state.dump(2) + "\n");

  PhaseRuns intrinsic = keptRuns(plan.runs, out);
  std::string systems;
  for (const auto& sys : plan.systems) systems += (systems.empty() ? "" : ", ") + sys;
  log.info("experiment {} ({}): {} run(s) of {} steps, {} at a time, over {} ({})", o.experiment, systems, plan.runs.size(),
           plan.runs.front().spec.steps, o.jobs, o.transport, network);
  if (o.resume) {
    log.info("resuming {}: {} of {} run(s) finished already", out.string(), intrinsic.finishedCount(), plan.runs.size());
    moveUnfinishedAside(plan.runs, intrinsic, o, state, log);
  }
  executeRuns(plan.runs, intrinsic, o, plan.protocol, bin, log);
  const auto& outcomes = intrinsic.outcomes;
  json summary = summarise(plan, o, intrinsic, network);
  const auto stamp = [&](std::size_t tests) {
    summary["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    summary["extrinsic_tests"] = tests;
  };
  if (g_signal) {
    stamp(0);
    return stopHere(summary, "intrinsic", plan.runs, intrinsic, plan.tests > 0, o, state, log);
  }
  for (const auto& [sys, js] : summary["systems"].items())
    for (const auto& g : js.value("curve_gaps", json::array()))
      log.warn("run '{}' reported {} affordance tables, not one per run.curve_interval: its curve has gaps",
               g["run_id"].get<std::string>(), g["snapshots"].get<std::size_t>());
  PhaseRuns extrinsic;
  std::vector<std::string> untested;
  if (plan.tests > 0) {
    const std::vector<PlannedRun> tests = planExtrinsic(plan, outcomes, o, untested);
    if (state.contains("tests"))
      refuseOtherPlan(state["tests"], fingerprint(tests), "extrinsic tests");
    else {
      state["tests"] = fingerprint(tests);
      writeWhole(statePath(out), state.dump(2) + "\n");
    }
    for (const auto& e : untested) log.error("{}", e);
    log.info("extrinsic phase: {} test(s): {} condition(s) x {} scenario(s) x {} from each trained agent", tests.size(),
             plan.conditions.size(), plan.scenarios.size(), plan.tests);
    extrinsic = keptRuns(tests, out);
    if (o.resume) {
      if (extrinsic.finishedCount())
        log.info("{} of {} test(s) finished already", extrinsic.finishedCount(), tests.size());
      moveUnfinishedAside(tests, extrinsic, o, state, log);
    }
    executeRuns(tests, extrinsic, o, plan.protocol, bin, log);
    summariseExtrinsic(summary, plan, tests, extrinsic, o);
    std::vector<TestRecord> records;
    for (const auto& t : tests) {
      if (!extrinsic.finished[t.index]) continue;
      const RunOutcome& r = extrinsic.outcomes[t.index];
      TestRecord rec;
      rec.system = t.system;
      rec.agent = t.intrinsic;
      rec.scenario = t.scenario;
      rec.condition = t.condition;
      rec.ok = r.ok;
      rec.success = r.ok && r.extrinsic.success;
      rec.utility = r.extrinsic.utility;
      rec.attempts = r.extrinsic.attempts;
      rec.completion = r.extrinsic.completion;
      rec.sub_goals = plan.sub_goals.at(t.scenario);
      if (const auto spec = plan.specs.find(t.scenario); spec != plan.specs.end()) {
        rec.objects = spec->second.objects;
        rec.multi_step = spec->second.multi_step;
      } else {
        rec.objects = rec.sub_goals;
      }
      for (const auto& g : r.extrinsic.sub_goals) {
        rec.actions_checked += g.actions_checked;
        rec.active_sub_goals += g.iterations > 0;
      }
      records.push_back(rec);
    }
    summariseDesign(summary, records, plan.conditions, plan.design, plan.systems, plan.scenarios);
    json vary = json::object();
    for (const auto& [k, v] : plan.design.vary) vary[k] = v;
    summary["extrinsic_design"] = {{"scenarios", plan.scenarios}, {"tests", plan.tests}, {"vary", vary},
                                   {"analysis", plan.design.analysis}, {"after_actions", plan.design.after_actions}};
    if (plan.design.generate) {
      const GenerateDesign& g = *plan.design.generate;
      summary["extrinsic_design"]["generate"] = {
          {"sub_goals", g.sub_goals}, {"objects", g.objects}, {"per_point", g.per_point}, {"seed", g.seed},
          {"multi_step", g.all_multi_step ? json("all") : json(g.multi_step)}};
    }
    if (plan.design.after_actions > 0) summary["after_actions"] = plan.design.after_actions;
    if (!untested.empty()) summary["untested_agents"] = untested;
    if (g_signal) {
      stamp(extrinsic.finishedCount());
      return stopHere(summary, "extrinsic", tests, extrinsic, false, o, state, log);
    }
  }
  stamp(extrinsic.finishedCount());
  writeWhole(out / "summary.json", summary.dump(2) + "\n");
  state["state"] = "finished";
  writeWhole(statePath(out), state.dump(2) + "\n");
  if (!o.quiet) printTables(summary, plan, o);
  const auto failed = [](const RunOutcome& r) { return !r.ok; };
  const auto failures = std::count_if(outcomes.begin(), outcomes.end(), failed) +
                        std::count_if(extrinsic.outcomes.begin(), extrinsic.outcomes.end(), failed);
  if (failures) log.error("{} run(s) failed; see summary.json failed_runs", failures);
  return failures || !untested.empty() ? 1 : 0;
}

}  // namespace afford

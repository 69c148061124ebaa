#include "afford/experiment.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <thread>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "afford/design.hpp"
#include "afford/driver.hpp"
#include "afford/group.hpp"
#include "afford/logging.hpp"
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
  int tests = 0;                             // extrinsic tests per agent, condition and scenario
  std::vector<Condition> conditions{Condition{}};  // planner settings compared (default: one, no settings)
  ExtrinsicDesign design;                    // the experiment file's extrinsic section, if any
  ProtocolConfig protocol;                   // the runner's between runs (each run's config has its own)
};

// Everything that can be wrong with the request is found here, before any process starts.
Plan planExperiment(const ExperimentOptions& o) {
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
  if (plan.tests > 0) {
    const RunConfig any = parseRunConfig(effectiveConfig(plan.config_dir, RunRequest{o.experiment, System::IMP, o.seed, o.steps, o.settings}));
    plan.scenarios = !o.scenarios.empty() ? o.scenarios
                     : !plan.design.scenarios.empty() ? plan.design.scenarios
                                                       : listScenarios(plan.config_dir);
    for (const auto& name : plan.scenarios)
      plan.sub_goals[name] = static_cast<int>(loadScenario(plan.config_dir, name, any.world).objects.size());
    plan.conditions = conditionsOf(plan.design);
    for (const Condition& c : plan.conditions) {  // every combination must make a valid extrinsic config
      std::vector<std::string> settings = o.settings;
      for (const auto& [k, v] : c.settings) settings.push_back(k + "=" + v);
      extrinsicConfig(plan.config_dir, RunRequest{o.experiment, System::IMP, o.seed, o.steps, settings}, "unchecked",
                      plan.scenarios.front());
    }
  }
  const std::string prefix = o.run_prefix.empty() ? defaultPrefix() : o.run_prefix;
  auto& runs = plan.runs;
  auto& configs = plan.configs;
  for (const auto& sys_name : plan.systems) {
    const System sys = parseSystem(sys_name);
    for (int r = 0; r < reps; ++r) {
      RunRequest req{o.experiment, sys, o.seed + r, o.steps, o.settings};
      YAML::Node node = effectiveConfig(plan.config_dir, req);
      const std::string run_id = prefix + "-" + o.experiment + "-" + sys_name + "-s" + std::to_string(o.seed + r);
      node["run"]["checkpoint"] = (fs::path(o.log_root) / run_id / "predictors.ckpt").string();
      node["run"]["record"] = o.keep_logs == "all" || (o.keep_logs == "first" && r == 0);
      if (plan.design.after_actions > 0) node["run"]["checkpoint_after_actions"] = plan.design.after_actions;
      const RunConfig cfg = parseRunConfig(node);
      if (r == 0) configs[sys_name] = cfg;
      PlannedRun p;
      p.system = sys_name;
      p.keep_log = o.keep_logs == "all" || (o.keep_logs == "first" && r == 0);
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
    if (fs::exists(fs::path(o.log_root) / p.spec.run_id))
      throw ConfigError("the log folder " + (fs::path(o.log_root) / p.spec.run_id).string() +
                        " exists already: choose another --run-prefix or --log-root");

  return plan;
}

// Run every planned run, J at a time; outcomes in plan order.
std::vector<RunOutcome> executeRuns(const std::vector<PlannedRun>& runs, const ExperimentOptions& o,
                                    const ProtocolConfig& protocol, const std::string& bin, spdlog::logger& log) {
  std::vector<RunOutcome> outcomes(runs.size());
  std::atomic<std::size_t> next{0};
  std::atomic<int> done{0};
  std::mutex log_mutex;
  auto worker = [&](int slot_index) {
    Slot slot;
    slot.index = slot_index;
    // A 2 MB receive buffer per socket (the kernel's default is 208 KB): every process hears every
    // datagram of its slot, and one descheduled for a while must not lose any (the kernel caps the
    // request at net.core.rmem_max).
    slot.url = "udpm://239.255.76.67:" + std::to_string(o.base_port + slot_index) + "?ttl=0&recv_buf_size=2097152";
    if (!o.attach.empty()) slot.url = o.attach;
    for (std::size_t i; (i = next.fetch_add(1)) < runs.size();) {
      RunOutcome r;
      try {
        r = o.transport == "memq" ? runInProcess(runs[i], o, protocol, slot_index)
                                  : runOverUdpm(runs[i], o, protocol, slot, bin);
      } catch (const std::exception& e) {
        r.ok = false;
        r.error = "run '" + runs[i].spec.run_id + "': " + e.what();
      }
      if (r.ok && !r.log_dir.empty()) {
        std::error_code ec;
        for (const auto& f : fs::directory_iterator(r.log_dir, ec))
          if (f.path().extension() == ".lcm") r.log_bytes += fs::file_size(f.path(), ec);
      }
      outcomes[i] = std::move(r);
      const RunOutcome& out = outcomes[i];
      std::lock_guard<std::mutex> lock(log_mutex);
      const int k = ++done;
      if (out.ok && runs[i].spec.extrinsic)
        log.info("[{}/{}] {}: {}, {} action(s), utility {}", k, runs.size(), runs[i].spec.run_id,
                 out.extrinsic.success ? "solved in " + std::to_string(out.extrinsic.completion) + " steps" : "not solved",
                 out.extrinsic.attempts, out.extrinsic.utility);
      else if (out.ok)
        log.info("[{}/{}] {} done in {:.1f} s, weights {}", k, runs.size(), runs[i].spec.run_id, out.wall_seconds,
                 out.weights_checksum);
      else
        log.error("[{}/{}] {}", k, runs.size(), out.error);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::min<int>(o.jobs, static_cast<int>(runs.size())); ++j) threads.emplace_back(worker, j);
  for (auto& t : threads) t.join();

  return outcomes;
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
          YAML::Node node = extrinsicConfig(plan.config_dir, req, checkpoint, t.scenario);
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
void summariseExtrinsic(json& summary, const Plan& plan, const std::vector<PlannedRun>& tests,
                        const std::vector<RunOutcome>& outcomes, const ExperimentOptions& o) {
  for (const auto& sys : plan.systems) {
    std::ofstream csv(fs::path(o.out_dir) / ("extrinsic_" + sys + ".csv"));
    csv << "system,intrinsic_run_id,seed,scenario,condition,rep,success,completion,attempts,utility,sub_goals,"
           "active_sub_goals,actions_checked,wall_seconds\n";
    for (const auto& t : tests) {
      if (t.system != sys) continue;
      const RunOutcome& r = outcomes[t.index];
      int checks = 0, active = 0;
      for (const auto& g : r.extrinsic.sub_goals) checks += g.actions_checked, active += g.iterations > 0;
      csv << sys << "," << plan.runs[t.intrinsic].spec.run_id << "," << t.spec.seed << "," << t.scenario << ",\""
          << plan.conditions[t.condition].label << "\"," << t.rep << "," << (r.ok && r.extrinsic.success) << ","
          << r.extrinsic.completion << "," << r.extrinsic.attempts << "," << r.extrinsic.utility << ","
          << r.extrinsic.sub_goals.size() << "," << active << "," << checks << "," << r.wall_seconds << "\n";
    }
    json ex = {{"scenarios", plan.scenarios}, {"tests_per_scenario", plan.tests}};
    if (plan.conditions.size() > 1) {  // the design's summary compares the conditions
      summary["systems"][sys]["extrinsic"] = ex;
      continue;
    }
    double sxx = 0, sxy = 0, sx3 = 0, sx4 = 0, sx2y = 0;  // least squares of y = a x^2 + b x
    for (const auto& scenario : plan.scenarios) {
      std::map<std::size_t, std::pair<int, int>> per_run;  // intrinsic run -> (successes, tests)
      std::vector<double> steps;
      double checked = 0;
      int sub_goal_count = 0, successes = 0, total = 0;
      for (const auto& t : tests) {
        if (t.system != sys || t.scenario != scenario) continue;
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
          const double x = plan.sub_goals.at(scenario), y = r.extrinsic.completion;
          sxx += x * x, sx3 += x * x * x, sx4 += x * x * x * x, sxy += x * y, sx2y += x * x * y;
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
    // Normal equations of y = a x^2 + b x.
    const double det = sx4 * sxx - sx3 * sx3;
    if (std::abs(det) > 1e-12)
      ex["completion_steps"]["fit"] = {{"a", (sx2y * sxx - sxy * sx3) / det}, {"b", (sx4 * sxy - sx3 * sx2y) / det}};
    summary["systems"][sys]["extrinsic"] = ex;
  }
}

// summary.json content (docs/results-schema.md); also writes the CSV files.
json summarise(const Plan& plan, const ExperimentOptions& o, const std::vector<RunOutcome>& outcomes,
               const std::string& network) {
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
    std::ofstream curves_csv(fs::path(o.out_dir) / ("curves_" + sys + ".csv"));
    curves_csv << "system,run_id,seed,step,object,action,prediction\n";
    std::map<std::int64_t, std::pair<Table, int>> curve_sum;
    for (const auto& p : runs) {
      if (p.system != sys) continue;
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
      maes.push_back(meanAbsError(fin, target));
      js["runs"].push_back({{"run_id", p.spec.run_id},
                            {"seed", p.spec.seed},
                            {"log_dir", r.log_dir.empty() ? json(nullptr) : json(r.log_dir)},
                            {"affordance", fin},
                            {"affordance_mae", maes.back()},
                            {"weights_checksum", r.weights_checksum},
                            {"checkpoint", r.checkpoint},
                            {"actions_executed", r.executed},
                            {"successes", r.successes},
                            {"wall_seconds", r.wall_seconds},
                            {"steps_per_second", r.run_seconds > 0 ? p.spec.steps / r.run_seconds : 0.0},
                            {"peak_rss_kb", r.peak_rss_kb},
                            {"log_bytes", r.log_bytes},
                            {"log_bytes_per_step", static_cast<double>(r.log_bytes) / p.spec.steps}});
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
    if (!finals.empty()) {
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
      std::ofstream csv(fs::path(o.out_dir) / ("affordance_" + sys + ".csv"));
      csv << "system,object,action,target,mean,min,max\n";
      for (std::size_t i = 0; i < target.size(); ++i)
        for (int a = 0; a < kNumActions; ++a)
          csv << sys << ",\"" << object_names[i] << "\"," << kActionNames[a] << "," << target[i][a] << ","
              << mean[i][a] << "," << mn[i][a] << "," << mx[i][a] << "\n";
    }
    if (reference && reference["affordance_mae"] && reference["affordance_mae"][sys])
      js["reference_affordance_mae"] = reference["affordance_mae"][sys].as<double>();
    summary["systems"][sys] = js;
  }
  if (reference && reference["source"]) summary["reference_source"] = reference["source"].as<std::string>();
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
  t << "\nLearned affordances after " << runs_steps.get<std::int64_t>() << " steps (mean of " << reps
    << " run(s)); in brackets the paper's table\n";
  for (const auto& sys : plan.systems) {
    const json& js = summary["systems"][sys];
    if (!js.contains("affordance")) continue;
    t << "\n" << sys << "            move        turn green  turn red    turn blue\n";
    for (std::size_t i = 0; i < object_names.size(); ++i) {
      t << "  " << std::left << std::setw(17) << object_names[i];
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
      for (const auto& s : js["extrinsic"]["scenarios"]) t << std::setw(14) << fixed(cs[s.get<std::string>()]["median"].get<double>(), 1);
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

}  // namespace

int runExperiment(const ExperimentOptions& o, spdlog::logger& log) {
  const auto began = std::chrono::steady_clock::now();  // reported only, never decides anything
  const Plan plan = planExperiment(o);
  std::string network = "in-process memq://";
  std::string bin;
  if (!o.attach.empty()) {
    network = "attached to " + o.attach;
  } else if (o.transport == "udpm") {
    network = prepareNetwork(o.netns);
    bin = executableDir();
  }
  fs::create_directories(o.out_dir);
  std::string systems;
  for (const auto& sys : plan.systems) systems += (systems.empty() ? "" : ", ") + sys;
  log.info("experiment {} ({}): {} run(s) of {} steps, {} at a time, over {} ({})", o.experiment, systems, plan.runs.size(),
           plan.runs.front().spec.steps, o.jobs, o.transport, network);
  const std::vector<RunOutcome> outcomes = executeRuns(plan.runs, o, plan.protocol, bin, log);
  json summary = summarise(plan, o, outcomes, network);
  for (const auto& [sys, js] : summary["systems"].items())
    for (const auto& g : js.value("curve_gaps", json::array()))
      log.warn("run '{}' reported {} affordance tables, not one per run.curve_interval: its curve has gaps",
               g["run_id"].get<std::string>(), g["snapshots"].get<std::size_t>());
  std::vector<RunOutcome> test_outcomes;
  std::vector<std::string> untested;
  if (plan.tests > 0) {
    const std::vector<PlannedRun> tests = planExtrinsic(plan, outcomes, o, untested);
    for (const auto& e : untested) log.error("{}", e);
    log.info("extrinsic phase: {} test(s): {} condition(s) x {} scenario(s) x {} from each trained agent", tests.size(),
             plan.conditions.size(), plan.scenarios.size(), plan.tests);
    test_outcomes = executeRuns(tests, o, plan.protocol, bin, log);
    summariseExtrinsic(summary, plan, tests, test_outcomes, o);
    std::vector<TestRecord> records;
    for (const auto& t : tests) {
      const RunOutcome& r = test_outcomes[t.index];
      TestRecord rec;
      rec.system = t.system;
      rec.agent = t.intrinsic;
      rec.scenario = t.scenario;
      rec.condition = t.condition;
      rec.ok = r.ok;
      rec.success = r.ok && r.extrinsic.success;
      rec.utility = r.extrinsic.utility;
      rec.attempts = r.extrinsic.attempts;
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
    if (plan.design.after_actions > 0) summary["after_actions"] = plan.design.after_actions;
    if (!untested.empty()) summary["untested_agents"] = untested;
  }
  summary["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  summary["extrinsic_tests"] = test_outcomes.size();
  std::ofstream(fs::path(o.out_dir) / "summary.json") << summary.dump(2) << "\n";
  if (!o.quiet) printTables(summary, plan, o);
  const auto failed = [](const RunOutcome& r) { return !r.ok; };
  const auto failures = std::count_if(outcomes.begin(), outcomes.end(), failed) +
                        std::count_if(test_outcomes.begin(), test_outcomes.end(), failed);
  if (failures) log.error("{} run(s) failed; see summary.json failed_runs", failures);
  return failures || !untested.empty() ? 1 : 0;
}

}  // namespace afford

#include "afford/experiment.hpp"

#include "afford/auth.hpp"

#include <nlohmann/json.hpp>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "afford/agents.hpp"
#include "afford/config.hpp"
#include "afford/execute.hpp"
#include "afford/group.hpp"
#include "afford/netns.hpp"
#include "afford/node.hpp"
#include "afford/plan.hpp"
#include "afford/present.hpp"
#include "afford/store.hpp"
#include "afford/summary.hpp"
#include "afford/sweep.hpp"
#include "afford/processes.hpp"
#include "motivation/component.hpp"
#include "predictors/affordance.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

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

}  // namespace

InterruptScope::InterruptScope() {
  sigaction(SIGINT, nullptr, &int_);
  sigaction(SIGTERM, nullptr, &term_);
}

InterruptScope::~InterruptScope() {
  sigaction(SIGINT, &int_, nullptr);
  sigaction(SIGTERM, &term_, nullptr);
  g_signal = 0;
  clearStopRequest();
}

int InterruptScope::signal() const { return g_signal; }

namespace {

std::string signalName(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : std::to_string(sig); }

// Intrinsic runs not finished (nor run by another shard) whose agent is
// stored (the same content key) are not run: they take the stored outcome and
// checkpoints, kept as finished.
void takeStoredAgents(const std::vector<PlannedRun>& runs, int after_actions, PhaseRuns& phase,
                      const AgentStore& agents, const ExperimentOptions& o, spdlog::logger& log) {
  std::size_t taken = 0;
  for (const auto& p : runs) {
    if (phase.finished[p.index] || (!phase.elsewhere.empty() && phase.elsewhere[p.index])) continue;
    auto r = agents.find(agentKey(p.spec.config_yaml), after_actions);
    if (!r) continue;
    keepOutcome(o.out_dir, p.spec.run_id, *r);
    phase.outcomes[p.index] = std::move(*r);
    phase.finished[p.index] = 1;
    ++taken;
  }
  if (taken)
    log.info("{} of {} intrinsic run(s) reuse a stored agent of the same configuration and seed ({}; "
             "--no-reuse-agents runs them again)", taken, runs.size(), agents.root());
}

void storeAgents(const std::vector<PlannedRun>& runs, const PhaseRuns& phase, const AgentStore& agents,
                 spdlog::logger& log) {
  for (const auto& p : runs) {
    const RunOutcome& r = phase.outcomes[p.index];
    if (!phase.finished[p.index] || !r.ok || !r.reused_from.empty()) continue;
    try {
      agents.keep(agentKey(p.spec.config_yaml), p.spec.run_id, p.spec.experiment, r);
    } catch (const std::exception& e) {  // the experiment's own results stand; only the reuse is lost
      log.warn("run '{}': its agent could not be stored for reuse ({})", p.spec.run_id, e.what());
    }
  }
}

// --keep-checkpoints first|none: once every test is done, the checkpoints of
// the intrinsic runs not kept go (a stored agent keeps its own link), and the
// summary says so; a run folder left with nothing else goes too.
void removeCheckpoints(const Plan& plan, const PhaseRuns& phase, json& summary, spdlog::logger& log) {
  std::uintmax_t freed = 0;
  std::set<std::string> removed;
  for (const auto& p : plan.runs) {
    const RunOutcome& r = phase.outcomes[p.index];
    if (p.keep_checkpoint || !phase.finished[p.index] || r.checkpoint.empty() || !r.reused_from.empty()) continue;
    const fs::path dir = fs::path(r.checkpoint).parent_path();
    std::error_code ec;
    for (const fs::path& f : checkpointFiles(r.checkpoint)) {
      freed += fs::file_size(f, ec);
      fs::remove(f, ec);
    }
    if (fs::is_directory(dir, ec) && std::distance(fs::directory_iterator(dir, ec), fs::directory_iterator()) ==
                                         (fs::exists(dir / "run.json") ? 1 : 0))
      fs::remove_all(dir, ec);  // nothing left but the note of whose it was
    removed.insert(p.spec.run_id);
  }
  for (auto& [sys, js] : summary["systems"].items())
    for (auto& entry : js["runs"])
      if (removed.count(entry["run_id"].get<std::string>())) entry["checkpoint"] = nullptr;
  if (!removed.empty())
    log.info("--keep-checkpoints: removed the checkpoints of {} run(s), {:.1f} MB", removed.size(), freed / 1e6);
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


// The design's summary of a part's tests (after summariseExtrinsic).
void summariseTests(json& summary, const Part& part, const std::vector<PlannedRun>& tests, const PhaseRuns& phase,
                    const std::vector<std::string>& untested) {
  const Plan& plan = part.plan;
  summariseExtrinsic(summary, plan, tests, phase, part.o);
  summariseDesign(summary, testRecords(plan, tests, phase), plan.conditions, plan.design, plan.systems, plan.scenarios);
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
}

// afford merge: the outcome of every run, and then of every test, from the
// shard that ran it; a run no shard finished is an error naming it (before
// anything is written).
PhaseRuns gatherShards(const std::vector<Part>& parts, const std::vector<PlannedRun>& runs,
                       const std::vector<std::string>& shards, PhaseRuns* tests_out) {
  const auto gather = [&](const std::vector<PlannedRun>& list, const std::string& what) {
    PhaseRuns phase;
    phase.outcomes.resize(list.size());
    phase.finished.assign(list.size(), 0);
    std::vector<std::string> missing;
    for (std::size_t i = 0; i < list.size(); ++i) {
      for (const auto& dir : shards)
        if (auto r = keptOutcome(dir, list[i].spec.run_id)) {
          phase.outcomes[i] = std::move(*r);
          phase.finished[i] = 1;
          break;
        }
      if (!phase.finished[i]) missing.push_back(list[i].spec.run_id);
    }
    if (!missing.empty()) {
      std::string names;
      for (std::size_t k = 0; k < missing.size() && k < 5; ++k) names += (k ? ", " : "") + missing[k];
      if (missing.size() > 5) names += ", ...";
      throw ConfigError("afford merge: " + std::to_string(missing.size()) + " of " + std::to_string(list.size()) + " " +
                        what + " finished in none of the shards (" + names +
                        "): resume the shard that stopped (`afford experiment --resume --out SHARD`), or give every "
                        "shard's folder");
    }
    return phase;
  };
  PhaseRuns intrinsic = gather(runs, "intrinsic run(s)");
  if (parts.front().plan.tests > 0) {
    std::vector<std::vector<PlannedRun>> part_tests;
    std::vector<std::string> untested;
    for (const auto& part : parts)
      part_tests.push_back(planExtrinsic(part.plan,
                                         slicePhase(intrinsic, part.offset, part.plan.runs.size()).outcomes, part.o,
                                         untested));
    std::vector<std::size_t> offsets;
    *tests_out = gather(concatRuns(part_tests, offsets), "extrinsic test(s)");
  }
  return intrinsic;
}

// A sweep's summary.json: each condition's summary (as an experiment of its
// own: DIR/conditions/<folder>/summary.json) under "conditions", every run
// entry naming its condition; and each CSV of the conditions in one, with a
// sweep_condition column first.
json sweepSummary(const std::vector<Part>& parts, std::vector<json>& summaries, const Sweep& sweep,
                  const ExperimentOptions& o) {
  json keys = json::object(), conditions = json::array(), by_name = json::object();
  for (const auto& [k, v] : sweep.keys) keys[k] = v;
  std::map<std::string, std::pair<std::string, std::string>> csvs;  // file -> header, rows
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const Part& part = parts[k];
    json& s = summaries[k];
    s["sweep_condition"] = part.condition;
    s["sweep_settings"] = part.condition_settings;
    for (auto& [sys, js] : s["systems"].items())
      for (auto& entry : js["runs"]) entry["sweep_condition"] = part.condition;
    conditions.push_back({{"name", part.condition},
                          {"settings", part.condition_settings},
                          {"folder", (fs::path("conditions") / fs::path(part.o.out_dir).filename()).string()}});
    by_name[part.condition] = s;
    std::error_code ec;
    std::vector<fs::path> files;
    for (const auto& f : fs::directory_iterator(part.o.out_dir, ec))
      if (f.path().extension() == ".csv") files.push_back(f.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      std::ifstream in(f);
      std::string line;
      if (!std::getline(in, line)) continue;
      auto& [header, all] = csvs[f.filename().string()];
      header = "sweep_condition," + line;
      while (std::getline(in, line)) all += "\"" + part.condition + "\"," + line + "\n";
    }
  }
  for (const auto& [file, hr] : csvs) writeWhole(fs::path(o.out_dir) / file, hr.first + "\n" + hr.second);
  const json& first = summaries.front();
  return {{"experiment", first["experiment"]},
          {"description", first["description"]},
          {"steps", first["steps"]},
          {"repetitions", first["repetitions"]},
          {"seed", first["seed"]},
          {"transport", first["transport"]},
          {"network", first["network"]},
          {"afford_version", first["afford_version"]},
          {"settings", sweep.fixed},
          {"sweep", {{"keys", keys}, {"conditions", conditions}}},
          {"conditions", by_name}};
}

// --process: only where the runner starts real processes. And the motivation that each run's motivation.kind
// names must be one this runner hosts or starts (not checked where someone else's process decides).
void checkProcesses(const ExperimentOptions& o, const std::vector<PlannedRun>& runs) {
  if (!o.processes.empty() && !o.attach.empty())
    throw ConfigError("--process with --attach: the runner starts no process on a bus it attaches to; start "
                      "your own by hand (scripts/procs.sh start RUN --process NAME='CMD')");
  if (!o.processes.empty() && o.transport != "udpm")
    throw ConfigError("--process starts a command in place of a shipped process, which needs real processes "
                      "(--transport udpm, not " + o.transport + "); in one process, a config key chooses the "
                      "component (motivation.kind)");
  if (!o.attach.empty()) return;
  const auto affordance_kinds = affordanceKinds();
  std::set<std::string> seen;
  for (const PlannedRun& run : runs)
    if (seen.insert(run.spec.config_yaml).second) {
      try {
        const RunConfig config = parseRunConfigText(run.spec.config_yaml);
        if (!o.processes.count("motivation")) makeMotivation(config);
        if (!o.processes.count("predictors") && std::find(affordance_kinds.begin(), affordance_kinds.end(),
                                                          config.predictors.affordance_kind) == affordance_kinds.end())
          makeAffordance(config);  // throws, naming the key and the kinds known
      } catch (const ConfigError& e) {
        throw ConfigError("run " + run.spec.run_id + ": " + e.what());
      }
    }
}

}  // namespace

std::map<std::string, std::string> parseProcessSwaps(const std::vector<std::string>& given, const std::string& option) {
  std::string known;
  for (const ProcessInfo& p : processRegistry()) known += (known.empty() ? "" : ", ") + std::string(p.name);
  std::map<std::string, std::string> out;
  for (const std::string& g : given) {
    const auto eq = g.find('=');
    const std::string name = g.substr(0, eq);
    if (eq == std::string::npos || !isProcessName(name))
      throw ConfigError(option + " '" + g + "': give NAME='CMD ARGS', NAME one of " + known);
    const auto first = g.find_first_not_of(" \t", eq + 1);
    if (first == std::string::npos) throw ConfigError(option + " " + name + "=: the command is empty");
    if (!out.emplace(name, g.substr(first)).second)
      throw ConfigError(option + " " + name + " is given twice");
  }
  return out;
}

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
    if (o.run_prefix.empty() && o.shard_count)
      throw ConfigError("--shard needs --run-prefix: every shard must give the runs the same ids "
                        "(scripts/slurm-submit.sh gives one)");
    if (o.run_prefix.empty()) o.run_prefix = defaultPrefix();  // stored: --resume plans the same run ids
  }
  const bool merging = !o.merged_from.empty();  // (a resumed merge too: its shards are gathered again)
  try {
    busKeyFrom(o.bus_key);  // a key file that cannot be read fails here, not in the first run
  } catch (const std::exception& e) {
    throw ConfigError(e.what());
  }
  if (o.shard_count && (o.shard_count < 1 || o.shard_index < 0 || o.shard_index >= o.shard_count))
    throw ConfigError("--shard must be i/n with 0 <= i < n, not " + std::to_string(o.shard_index) + "/" +
                      std::to_string(o.shard_count));
  const Sweep sweep = planSweep(o.settings, o.sweep_file);
  std::vector<Part> parts = planParts(o, sweep);
  std::vector<std::vector<PlannedRun>> part_runs;
  for (const auto& part : parts) part_runs.push_back(part.plan.runs);
  std::vector<std::size_t> offsets;
  const std::vector<PlannedRun> runs = concatRuns(part_runs, offsets);
  for (std::size_t k = 0; k < parts.size(); ++k) parts[k].offset = offsets[k];
  const Plan& plan = parts.front().plan;  // what every part shares: the experiment, its systems and design
  if (o.resume) {
    refuseChangedPlan(request, optionsFromJson(state.at("options")), plan);
    refuseOtherPlan(state.at("runs"), fingerprint(runs), "intrinsic runs");
  }
  if (!merging) checkProcesses(o, runs);
  std::vector<char> elsewhere;  // --shard: the runs other shards run
  if (o.shard_count)
    for (std::size_t i = 0; i < runs.size(); ++i)
      elsewhere.push_back(static_cast<int>(i % static_cast<std::size_t>(o.shard_count)) != o.shard_index);
  if (!o.resume && !merging) refuseUsedLogFolders(runs, elsewhere, o.log_root);
  PhaseRuns merged_tests;
  const PhaseRuns merged = merging ? gatherShards(parts, runs, o.merged_from, &merged_tests) : PhaseRuns{};
  std::string network = "in-process memq://";
  std::string bin;
  if (merging) {
    network = o.merged_network;
  } else if (!o.attach.empty()) {
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
    fs::remove_all(out / "conditions");
    state = {{"experiment", plan.exp.name},
             {"cwd", fs::current_path().string()},
             {"options", optionsToJson(o)},
             {"runs", fingerprint(runs)},
             {"interruptions", json::array()},
             {"moved_aside", json::array()}};
    if (merging) state["merged_from"] = o.merged_from;
  }
  state["state"] = "running";
  state["resume"] = resumeCommand(o);
  writeWhole(statePath(out), state.dump(2) + "\n");
  if (merging) {  // the merged folder holds every outcome, as if it had run them
    for (std::size_t i = 0; i < runs.size(); ++i) keepOutcome(out, runs[i].spec.run_id, merged.outcomes[i]);
    log.info("merging {} shard(s): {} intrinsic run(s), {} test(s)", o.merged_from.size(), runs.size(),
             merged_tests.outcomes.size());
  }

  PhaseRuns intrinsic = keptRuns(runs, out);
  intrinsic.elsewhere = elsewhere;
  if (o.shard_count) {
    const auto mine = static_cast<std::size_t>(std::count(elsewhere.begin(), elsewhere.end(), 0));
    log.info("shard {}/{}: {} of the {} intrinsic run(s) and their tests (`afford merge` joins the shards)",
             o.shard_index, o.shard_count, mine, runs.size());
  }
  std::string systems;
  for (const auto& sys : plan.systems) systems += (systems.empty() ? "" : ", ") + sys;
  log.info("experiment {} ({}{}): {} run(s) of {} steps, {} at a time, over {} ({})", plan.exp.name, systems,
           parts.size() > 1 ? "; " + std::to_string(parts.size()) + " sweep conditions" : std::string(), runs.size(),
           runs.front().spec.steps, o.jobs, o.transport, network);
  if (o.resume) {
    log.info("resuming {}: {} of {} run(s) finished already", out.string(), intrinsic.finishedCount(), runs.size());
    moveUnfinishedAside(runs, intrinsic, o, state, log);
  }
  const AgentStore agents((fs::path(o.log_root) / "agents").string());
  // The store knows the shipped processes' code (its key), not what a swapped command runs.
  if (o.reuse_agents && !o.processes.empty()) {
    o.reuse_agents = false;
    log.info("--process: the agents of this experiment are neither taken from nor kept in {}/agents",
             o.log_root);
  }
  if (o.reuse_agents && !merging) takeStoredAgents(runs, plan.design.after_actions, intrinsic, agents, o, log);
  executeRuns(runs, intrinsic, o, plan.protocol, bin, log);
  if (o.reuse_agents && !merging) storeAgents(runs, intrinsic, agents, log);

  // Each part summarised as an experiment of its own; a sweep's in DIR/conditions/<folder>/.
  std::vector<json> summaries;
  std::vector<PhaseRuns> part_phase;
  for (const Part& part : parts) {
    part_phase.push_back(slicePhase(intrinsic, part.offset, part.plan.runs.size()));
    if (parts.size() > 1) fs::create_directories(part.o.out_dir);
    summaries.push_back(summarise(part.plan, part.o, part_phase.back(), network));
    if (o.shard_count) summaries.back()["shard"] = {{"index", o.shard_index}, {"count", o.shard_count}};
    if (merging) summaries.back()["merged_from"] = o.merged_from;
  }
  const auto stamp = [&](std::size_t tests) {
    for (json& s : summaries) {
      s["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
      if (!s.contains("extrinsic_tests")) s["extrinsic_tests"] = tests;
    }
  };
  // The summaries as they stand: each part's, and a sweep's own (DIR/summary.json).
  const auto whole = [&]() {
    if (parts.size() == 1) return summaries.front();
    json s = sweepSummary(parts, summaries, sweep, o);  // names each condition in its summary too
    for (std::size_t k = 0; k < parts.size(); ++k)
      writeWhole(fs::path(parts[k].o.out_dir) / "summary.json", summaries[k].dump(2) + "\n");
    s["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    return s;
  };
  if (g_signal) {
    stamp(0);
    json s = whole();
    return stopHere(s, "intrinsic", runs, intrinsic, plan.tests > 0, o, state, log);
  }
  for (const json& summary : summaries)
    for (const auto& [sys, js] : summary["systems"].items())
      for (const auto& g : js.value("curve_gaps", json::array()))
        log.warn("run '{}' reported {} affordance tables, not one per run.curve_interval: its curve has gaps",
                 g["run_id"].get<std::string>(), g["snapshots"].get<std::size_t>());
  PhaseRuns extrinsic;
  std::vector<std::string> untested;
  if (plan.tests > 0) {
    std::vector<std::vector<PlannedRun>> part_tests;
    std::vector<std::vector<std::string>> part_untested;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      part_untested.emplace_back();
      part_tests.push_back(planExtrinsic(parts[k].plan, part_phase[k].outcomes, parts[k].o, part_untested.back()));
      untested.insert(untested.end(), part_untested.back().begin(), part_untested.back().end());
    }
    std::vector<std::size_t> test_offsets;
    const std::vector<PlannedRun> tests = concatRuns(part_tests, test_offsets);
    if (state.contains("tests"))
      refuseOtherPlan(state["tests"], fingerprint(tests), "extrinsic tests");
    else {
      state["tests"] = fingerprint(tests);
      writeWhole(statePath(out), state.dump(2) + "\n");
    }
    for (const auto& e : untested) log.error("{}", e);
    log.info("extrinsic phase: {} test(s): {} condition(s) x {} scenario(s) x {} from each trained agent", tests.size(),
             plan.conditions.size(), plan.scenarios.size(), plan.tests);
    if (merging)
      for (std::size_t i = 0; i < tests.size(); ++i) keepOutcome(out, tests[i].spec.run_id, merged_tests.outcomes[i]);
    extrinsic = keptRuns(tests, out);
    if (o.resume) {
      if (extrinsic.finishedCount())
        log.info("{} of {} test(s) finished already", extrinsic.finishedCount(), tests.size());
      moveUnfinishedAside(tests, extrinsic, o, state, log);
    }
    executeRuns(tests, extrinsic, o, plan.protocol, bin, log);
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const PhaseRuns mine = slicePhase(extrinsic, test_offsets[k], part_tests[k].size());
      summariseTests(summaries[k], parts[k], part_tests[k], mine, part_untested[k]);
      summaries[k]["extrinsic_tests"] = mine.finishedCount();
    }
    if (g_signal) {
      stamp(extrinsic.finishedCount());
      json s = whole();
      return stopHere(s, "extrinsic", tests, extrinsic, false, o, state, log);
    }
  }
  stamp(extrinsic.finishedCount());
  // A shard keeps every checkpoint: the merge plans the tests again from the
  // checkpoint files (an after-N-actions one included), then removes them.
  if (!o.shard_count)
    for (std::size_t k = 0; k < parts.size(); ++k) removeCheckpoints(parts[k].plan, part_phase[k], summaries[k], log);
  const json summary = whole();
  writeWhole(out / "summary.json", summary.dump(2) + "\n");
  state["state"] = "finished";
  writeWhole(statePath(out), state.dump(2) + "\n");
  if (!o.quiet)
    for (std::size_t k = 0; k < parts.size(); ++k) {
      if (parts.size() > 1) std::printf("\n== condition %s (%s)\n", parts[k].condition.c_str(), parts[k].o.out_dir.c_str());
      printTables(summaries[k], parts[k].plan, parts[k].o);
    }
  const auto failed = [](const RunOutcome& r) { return !r.ok; };
  std::size_t failures = static_cast<std::size_t>(std::count_if(extrinsic.outcomes.begin(), extrinsic.outcomes.end(), failed));
  for (std::size_t i = 0; i < runs.size(); ++i)
    failures += intrinsic.finished[i] && !intrinsic.outcomes[i].ok;
  if (failures) log.error("{} run(s) failed; see summary.json failed_runs", failures);
  return failures || !untested.empty() ? 1 : 0;
}

}  // namespace afford

#include "afford/experiment.hpp"

#include <nlohmann/json.hpp>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
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

std::string signalName(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : std::to_string(sig); }

// Intrinsic runs not finished whose agent is stored (the same content key) are
// not run: they take the stored outcome and checkpoints, kept as finished.
void takeStoredAgents(const Plan& plan, PhaseRuns& phase, const AgentStore& agents, const ExperimentOptions& o,
                      spdlog::logger& log) {
  std::size_t taken = 0;
  for (const auto& p : plan.runs) {
    if (phase.finished[p.index]) continue;
    auto r = agents.find(agentKey(p.spec.config_yaml), plan.design.after_actions);
    if (!r) continue;
    keepOutcome(o.out_dir, p.spec.run_id, *r);
    phase.outcomes[p.index] = std::move(*r);
    phase.finished[p.index] = 1;
    ++taken;
  }
  if (taken)
    log.info("{} of {} intrinsic run(s) reuse a stored agent of the same configuration and seed ({}; "
             "--no-reuse-agents runs them again)", taken, plan.runs.size(), agents.root());
}

void storeAgents(const Plan& plan, const PhaseRuns& phase, const AgentStore& agents, spdlog::logger& log) {
  for (const auto& p : plan.runs) {
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
    state = {{"experiment", plan.exp.name},
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
  log.info("experiment {} ({}): {} run(s) of {} steps, {} at a time, over {} ({})", plan.exp.name, systems, plan.runs.size(),
           plan.runs.front().spec.steps, o.jobs, o.transport, network);
  if (o.resume) {
    log.info("resuming {}: {} of {} run(s) finished already", out.string(), intrinsic.finishedCount(), plan.runs.size());
    moveUnfinishedAside(plan.runs, intrinsic, o, state, log);
  }
  const AgentStore agents((fs::path(o.log_root) / "agents").string());
  if (o.reuse_agents) takeStoredAgents(plan, intrinsic, agents, o, log);
  executeRuns(plan.runs, intrinsic, o, plan.protocol, bin, log);
  if (o.reuse_agents) storeAgents(plan, intrinsic, agents, log);
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
    const std::vector<TestRecord> records = testRecords(plan, tests, extrinsic);
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
  removeCheckpoints(plan, intrinsic, summary, log);
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

#include "experiment/experiment.hpp"

#include "experiment/pipeline.hpp"

#include <nlohmann/json.hpp>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <thread>

#include "afford/auth.hpp"
#include "afford/config.hpp"
#include "afford/node.hpp"
#include "afford/process_main.hpp"
#include "afford/processes.hpp"
#include "afford/version.hpp"
#include "experiment/execute/agents.hpp"
#include "experiment/execute/bus_note.hpp"
#include "experiment/execute/execute.hpp"
#include "experiment/execute/run_folder.hpp"
#include "experiment/plan/disk.hpp"
#include "experiment/plan/plan.hpp"
#include "experiment/plan/sweep.hpp"
#include "experiment/present/present.hpp"
#include "experiment/results/summary.hpp"
#include "experiment/run/group.hpp"
#include "experiment/run/netns.hpp"
#include "experiment/run/outcome.hpp"
#include "experiment/state.hpp"
#include "motivation/component.hpp"
#include "predictors/affordance.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// --process: only where the runner starts real processes. And the motivation that each run's motivation.kind
// names must be one this runner hosts or starts (not checked where someone else's process decides).
void checkProcesses(const HostRequest& o, const std::vector<PlannedRun>& runs) {
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

// ---- the pipeline -------------------------------------------------------------
//
// An experiment is a short sequence of stages: prepare (check and plan),
// open its folder, run the intrinsic phase, summarise it, run the extrinsic
// tests, summarise them, and present. Where the outcomes come from is the
// executor's business: a fresh or resumed experiment runs what is not kept
// yet (this shard's share), a merge takes them from the shards' folders.

namespace {

// The sweep, the parts and the runs of x.o's plan.
void planRuns(Experiment& x) {
  x.sweep = planSweep(x.o.plan.settings, x.o.plan.sweep_file);
  x.parts = planParts(x.o.plan, x.o.write.out_dir, x.sweep);
  std::vector<std::vector<PlannedRun>> part_runs;
  for (const auto& part : x.parts) part_runs.push_back(part.plan.runs);
  std::vector<std::size_t> offsets;
  x.runs = concatRuns(part_runs, offsets);
  for (std::size_t k = 0; k < x.parts.size(); ++k) x.parts[k].offset = offsets[k];
}

// The intrinsic runs this experiment runs itself (a shard's share).
std::vector<const PlannedRun*> ownRuns(const Experiment& x) {
  std::vector<const PlannedRun*> mine;
  const std::vector<char> elsewhere = shardMask(x.o.host, x.runs.size());
  for (std::size_t i = 0; i < x.runs.size(); ++i)
    if (i >= elsewhere.size() || !elsewhere[i]) mine.push_back(&x.runs[i]);
  return mine;
}

}  // namespace

Experiment prepare(const ExperimentRequest& request) {
  Experiment x;
  x.o = request;
  bool stamped = false;  // the run prefix is the wall clock's, to be reserved once all is checked
  if (request.resume) {
    x.state = unfinishedState(request);
    x.followed = followMovedFolder(x.state, request);
    x.o = resumedRequest(request, x.state);
  } else {
    refuseUsedOutDir(request);
    if (x.o.plan.run_prefix.empty() && x.o.host.shard_count)
      throw ConfigError("--shard needs --run-prefix: every shard must give the runs the same ids "
                        "(scripts/slurm-submit.sh gives one)");
    if (x.o.plan.run_prefix.empty() && !x.merging()) {
      x.o.plan.run_prefix = defaultPrefix();
      stamped = true;
    }
    x.o.resume_with = reachCommand(x.o);
  }
  const ExperimentRequest& o = x.o;
  try {
    busKeyFrom(o.host.bus_key);  // a key file that cannot be read fails here, not in the first run
  } catch (const std::exception& e) {
    throw ConfigError(e.what());
  }
  checkHostRequest(o.host);
  planRuns(x);
  if (o.resume) {
    refuseChangedPlan(request, x.state.options, x.plan());
    refuseOtherPlan(x.state.runs, fingerprint(x.runs, x.moves(), x.plannedBy()), "intrinsic runs");
  }
  if (!x.merging()) checkProcesses(o.host, x.runs);
  // Everything checked: the prefix is reserved in the log root (stored, so --resume plans the same run ids),
  // and if another experiment took this second's, the runs are planned again with the one reserved.
  if (stamped) {
    const std::string reserved = reservePrefix(o.plan.log_root);
    if (reserved != x.o.plan.run_prefix) {
      x.o.plan.run_prefix = reserved;
      planRuns(x);
    }
  }
  if (!o.resume && !x.merging()) refuseHeldRunFolders(ownRuns(x), o.plan.log_root);
  x.hosting = {o.host.transport, "in-process memq://", o.host.processes};
  if (x.merging())
    x.hosting.network = o.merged_network;
  else if (!o.host.attach.empty())
    x.hosting.network = "attached to " + o.host.attach;
  return x;
}

namespace {

// The folder: locked, the run folders of a fresh experiment claimed, its state
// written (the files of the finished one it replaces, with --replace,
// removed), marked running.
void openFolder(Experiment& x) {
  const fs::path out = x.out();
  std::error_code ec;
  const bool made = !fs::exists(out, ec);
  fs::create_directories(out);
  x.lock = OutDirLock(out);
  if (!x.o.resume) {
    refuseUsedOutDir(x.o);  // again, now that no other runner can write here
    // Its runs' folders are its own from here on: another experiment given the same run ids is refused.
    if (!x.merging()) try {
        claimRunFolders(ownRuns(x), x.o.plan.log_root, x.o.write.out_dir);
      } catch (const ConfigError&) {
        if (made) {  // nothing of this experiment is left
          x.lock = OutDirLock();
          fs::remove(out / ".lock", ec);
          fs::remove(out, ec);
        }
        throw;
      }
    clearReplaced(x.o);
    x.state = ExperimentState{};
    x.state.experiment = x.plan().exp.name;
    x.state.cwd = fs::current_path().string();
    x.state.options = x.o;
    x.state.runs = fingerprint(x.runs);
    x.state.planned_by = affordVersion();
    if (x.merging()) x.state.merged_from = x.o.merged_from;
  }
  if (x.o.resume && !x.followed.was.empty() && x.followed.log_root_inside)
    reclaimMovedRunFolders(x.o.plan.log_root, x.followed.was, x.o.write.out_dir);
  x.state.state = "running";
  x.state.resume = resumeCommand(x.o);
  x.saveState();
}

// What the runs will write, before they run (a million steps keep a log of gigabytes).
void sayDisk(const Experiment& x, spdlog::logger& log) {
  std::vector<PlannedRun> mine;
  for (const PlannedRun* p : ownRuns(x)) mine.push_back(*p);
  const DiskNeed need = diskNeed(mine, x.o.host.jobs);
  log.info("{}", diskLine(need));
  std::error_code ec;
  fs::path where = x.o.plan.log_root;
  while (!where.empty() && !fs::exists(where, ec)) where = where.parent_path();
  const fs::space_info space = fs::space(where.empty() ? fs::path(".") : where, ec);
  if (!ec)
    if (const std::string warning = diskWarning(need, space.available, x.o.plan.log_root); !warning.empty())
      log.warn("{}", warning);
}

// Where its runs are heard, for afford watch --out (its lock held: the note is of the runner that holds it).
void noteBus(const Experiment& x) {
  BusNote note;
  note.pid = getpid();
  note.urls = slotUrls(x.o.host);
  if (const std::string key = busKeySource(x.o.host.bus_key); !key.empty()) note.bus_key = fs::absolute(key).string();
  note.experiment = x.plan().exp.name;
  writeBusNote(x.out(), note);
}

void sayWhatRuns(const Experiment& x, spdlog::logger& log) {
  const ExperimentRequest& o = x.o;
  if (o.host.shard_count) {
    const std::vector<char> elsewhere = shardMask(o.host, x.runs.size());
    const auto mine = static_cast<std::size_t>(std::count(elsewhere.begin(), elsewhere.end(), 0));
    log.info("shard {}/{}: {} of the {} intrinsic run(s) and their tests (`afford merge` joins the shards)",
             o.host.shard_index, o.host.shard_count, mine, x.runs.size());
  }
  std::string systems;
  for (const auto& sys : x.plan().systems) systems += (systems.empty() ? "" : ", ") + sys;
  log.info("experiment {} ({}{}): {} run(s) of {} steps, {} at a time, over {} ({}), into {}", x.plan().exp.name,
           systems, x.parts.size() > 1 ? "; " + std::to_string(x.parts.size()) + " sweep conditions" : std::string(),
           x.runs.size(), x.runs.front().spec.steps, o.host.jobs, o.host.transport, x.hosting.network, x.out().string());
  sayDisk(x, log);
}

// One phase: the outcomes kept already (resume; a merge's gathered ones), and the others executed.
PhaseRuns runPhase(Experiment& x, Executor& exec, const std::vector<PlannedRun>& runs, bool extrinsic,
                   spdlog::logger& log) {
  exec.gather(runs, extrinsic);
  PhaseRuns phase = keptRuns(runs, x.out(), x.moves());
  if (!extrinsic) phase.elsewhere = shardMask(x.o.host, runs.size());  // a shard's tests are those of its own agents
  if (x.o.resume) {
    if (!extrinsic)
      log.info("resuming {}: {} of {} run(s) finished already", x.out().string(), phase.finishedCount(), runs.size());
    else if (phase.finishedCount())
      log.info("{} of {} test(s) finished already", phase.finishedCount(), runs.size());
    const std::vector<MovedAside> moved = moveUnfinishedAside(runs, phase, x.o.plan.log_root, x.o.write.out_dir, log);
    x.state.moved_aside.insert(x.state.moved_aside.end(), moved.begin(), moved.end());
    if (!moved.empty()) x.saveState();
  }
  exec.execute(runs, extrinsic, phase);
  // The folders claimed for runs that did not need them (an agent taken from the store) go.
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (phase.finished[i] && phase.outcomes[i].ok) releaseUnused(fs::path(x.o.plan.log_root) / runs[i].spec.run_id, x.o.write.out_dir);
  return phase;
}

// The summaries of an experiment: each part's (a sweep condition's, as an
// experiment of its own), and the whole (a sweep's own).
struct Summaries {
  std::chrono::steady_clock::time_point began;  // reported only, never decides anything
  std::vector<Summary> parts;         // extrinsic_tests: each part's, once its tests are summarised
  std::vector<PhaseRuns> part_phase;  // each part's intrinsic runs

  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count(); }
  // summary.json (a sweep's: each condition's too), with the interruption that stopped it, if one did.
  void write(const Experiment& x, const std::optional<Interruption>& stopped) {
    for (Summary& s : parts) s.wall_seconds = seconds();
    if (x.parts.size() == 1) {
      parts.front().interrupted = stopped;
      writeJsonWhole(x.out() / "summary.json", toJson(parts.front()), 2);
      return;
    }
    SweepSummary whole = sweepSummary(x.parts, parts, x.sweep, x.o.write.out_dir);  // names each condition in its summary too
    for (std::size_t k = 0; k < x.parts.size(); ++k)
      writeJsonWhole(fs::path(x.parts[k].out_dir) / "summary.json", toJson(parts[k]), 2);
    whole.interrupted = stopped;
    whole.wall_seconds = seconds();
    writeJsonWhole(x.out() / "summary.json", toJson(whole), 2);
  }
};

Summaries summariseIntrinsic(const Experiment& x, const PhaseRuns& intrinsic, spdlog::logger& log) {
  Summaries s;
  for (const Part& part : x.parts) {
    s.part_phase.push_back(slicePhase(intrinsic, part.offset, part.plan.runs.size()));
    if (x.parts.size() > 1) fs::create_directories(part.out_dir);
    s.parts.push_back(summarise(part.plan, x.hosting, s.part_phase.back(), part.out_dir));
    if (x.o.host.shard_count) s.parts.back().shard = ShardSummary{x.o.host.shard_index, x.o.host.shard_count};
    if (x.merging()) s.parts.back().merged_from = x.o.merged_from;
  }
  return s;
}

// Runs whose curve misses snapshots, said once the intrinsic phase is whole.
void warnCurveGaps(const Summaries& s, spdlog::logger& log) {
  for (const Summary& summary : s.parts)
    for (const auto& [sys, js] : summary.systems)
      for (const CurveGap& g : js.curve_gaps.value_or(std::vector<CurveGap>{}))
        log.warn("run '{}' reported {} affordance tables, not one per run.curve_interval: its curve has gaps",
                 g.run_id, g.snapshots);
}

// The extrinsic phase: every part's tests planned from its trained agents, run, and summarised.
struct Tests {
  std::vector<PlannedRun> runs;
  PhaseRuns phase;
  std::vector<std::string> untested;  // agents that could not be tested, and why
};

Tests runTests(Experiment& x, Executor& exec, Summaries& s, spdlog::logger& log) {
  Tests t;
  if (x.plan().tests <= 0) return t;
  std::vector<std::vector<PlannedRun>> part_tests;
  std::vector<std::vector<std::string>> part_untested;
  for (std::size_t k = 0; k < x.parts.size(); ++k) {
    part_untested.emplace_back();
    part_tests.push_back(
        planExtrinsic(x.parts[k].plan, s.part_phase[k].outcomes, x.parts[k].request, part_untested.back()));
    t.untested.insert(t.untested.end(), part_untested.back().begin(), part_untested.back().end());
  }
  std::vector<std::size_t> offsets;
  t.runs = concatRuns(part_tests, offsets);
  if (x.state.tests) {
    refuseOtherPlan(*x.state.tests, fingerprint(t.runs, x.moves(), x.plannedBy()), "extrinsic tests");
  } else {
    x.state.tests = fingerprint(t.runs, x.moves(), x.plannedBy());  // (as the experiment was started: see fingerprint)
    x.saveState();
  }
  for (const auto& e : t.untested) log.error("{}", e);
  log.info("extrinsic phase: {} test(s): {} condition(s) x {} scenario(s) x {} from each trained agent", t.runs.size(),
           x.plan().conditions.size(), x.plan().scenarios.size(), x.plan().tests);
  t.phase = runPhase(x, exec, t.runs, true, log);
  for (std::size_t k = 0; k < x.parts.size(); ++k) {
    const PhaseRuns mine = slicePhase(t.phase, offsets[k], part_tests[k].size());
    summariseTests(s.parts[k], x.parts[k], part_tests[k], mine, part_untested[k]);
    s.parts[k].extrinsic_tests = static_cast<std::int64_t>(mine.finishedCount());
  }
  return t;
}

// The end of a finished experiment: checkpoints not kept removed, the summary
// written, the tables presented. Returns the exit code.
int finish(Experiment& x, Summaries& s, const PhaseRuns& intrinsic, const Tests& tests, spdlog::logger& log) {
  // A shard keeps every checkpoint: the merge plans the tests again from the
  // checkpoint files (an after-N-actions one included), then removes them.
  if (!x.o.host.shard_count)
    for (std::size_t k = 0; k < x.parts.size(); ++k) removeCheckpoints(x.parts[k].plan, s.part_phase[k], s.parts[k], log);
  s.write(x, std::nullopt);
  x.state.state = "finished";
  x.saveState();
  if (!x.o.write.quiet)
    for (std::size_t k = 0; k < x.parts.size(); ++k) {
      if (x.parts.size() > 1)
        std::printf("\n== condition %s (%s)\n", x.parts[k].condition.c_str(), x.parts[k].out_dir.c_str());
      printTables(s.parts[k], x.parts[k].plan, x.parts[k].out_dir);
    }
  std::size_t failed_runs = 0, failed_tests = 0;
  for (std::size_t i = 0; i < tests.runs.size(); ++i) failed_tests += tests.phase.finished[i] && !tests.phase.outcomes[i].ok;
  for (std::size_t i = 0; i < x.runs.size(); ++i) failed_runs += intrinsic.finished[i] && !intrinsic.outcomes[i].ok;
  if (failed_runs) log.error("{} intrinsic run(s) failed; see summary.json, systems.<S>.failed_runs", failed_runs);
  if (failed_tests)
    log.error("{} extrinsic test(s) failed to run; see summary.json, systems.<S>.extrinsic.failed_tests", failed_tests);
  return failed_runs || failed_tests || !tests.untested.empty() ? 1 : 0;
}

}  // namespace

int runPrepared(Experiment& x, const std::chrono::steady_clock::time_point began, spdlog::logger& log,
                const Shared& share) {
  std::unique_ptr<SlotPool> own;  // alone: the slots serve this experiment's phases, then stop
  std::unique_ptr<Executor> exec;  // (gone before the slots: it waits for the tests it started on them)
  if (x.merging()) {
    exec = mergedExecutor(x, log);
  } else {
    if (x.o.host.attach.empty() && x.o.host.transport == "udpm") {
      x.hosting.network = share.pool ? share.network : prepareNetwork(x.o.host.netns);
      x.bin = executableDir();
    }
    if (x.o.host.transport == "udpm" && x.o.host.on_bus && !share.pool) x.o.host.on_bus(slotUrls(x.o.host));
    SlotPool* pool = share.pool;
    if (!pool) pool = (own = std::make_unique<SlotPool>(x.o.host, false)).get();
    exec = hostedExecutor(x, log, *pool, share);
  }
  if (!share.pool) installInterruptHandlers(resumeCommand(x.o));  // from here a signal stops the experiment in order
  for (const std::string& note : x.followed.notes) log.warn("{}", note);
  openFolder(x);
  if (x.o.host.transport == "udpm" && !x.merging()) noteBus(x);
  sayWhatRuns(x, log);
  const PhaseRuns intrinsic = runPhase(x, *exec, x.runs, false, log);
  Summaries s = summariseIntrinsic(x, intrinsic, log);
  s.began = began;
  // A phase with runs neither finished nor another shard's (a stop signal, a run that could not begin) ends the
  // experiment short of finished: it stays to be resumed.
  const SlotPool* pool = share.pool ? share.pool : own.get();
  if (const std::string why = stoppedShort(intrinsic, pool); !why.empty()) {
    const Interruption in = interruption("intrinsic", x.runs, intrinsic, x.plan().tests > 0, x.o, why);
    s.write(x, in);
    return stopHere(in, x.o, x.state, log);
  }
  warnCurveGaps(s, log);
  const Tests tests = runTests(x, *exec, s, log);
  if (const std::string why = stoppedShort(tests.phase, pool); !why.empty()) {
    const Interruption in = interruption("extrinsic", tests.runs, tests.phase, false, x.o, why);
    s.write(x, in);
    return stopHere(in, x.o, x.state, log);
  }
  return finish(x, s, intrinsic, tests, log);
}

std::vector<CheckedRun> checkExperiment(const ExperimentRequest& request) {
  if (request.plan.run_prefix.empty() && !request.resume)
    throw ConfigError("checking an experiment needs a run prefix: none is reserved by a check");
  ExperimentRequest checked = request;
  checked.plan.with_truth = false;  // runs nothing, so measures nothing: a table's truth is not estimated for it
  const Experiment x = prepare(checked);
  std::vector<CheckedRun> runs;
  for (const PlannedRun& r : x.runs) runs.push_back({r.spec.run_id, r.system, r.spec.steps});
  return runs;
}

int runExperiment(const ExperimentRequest& request, spdlog::logger& log) {
  const auto began = std::chrono::steady_clock::now();
  Experiment x;
  installInterruptHandlers("");  // planning may take a while (a table's truth is estimated): a signal stops it too
  try {
    x = prepare(request);  // everything is checked before anything is written or started
  } catch (const NothingToResume& e) {
    log.info("{}", e.what());
    return 0;
  }
  return runPrepared(x, began, log, Shared{});
}

}  // namespace afford

#include "experiment/experiment.hpp"

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
#include "afford/processes.hpp"
#include "experiment/execute/agents.hpp"
#include "experiment/execute/execute.hpp"
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

// --keep-checkpoints first|none: once every test is done, the checkpoints of
// the intrinsic runs not kept go (a stored agent keeps its own link), and the
// summary says so; a run folder left with nothing else goes too.
void removeCheckpoints(const Plan& plan, const PhaseRuns& phase, Summary& summary, spdlog::logger& log) {
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
  for (auto& [sys, js] : summary.systems)
    for (RunEntry& entry : js.runs)
      if (removed.count(entry.run_id)) entry.checkpoint = Nullable<std::string>();
  if (!removed.empty())
    log.info("--keep-checkpoints: removed the checkpoints of {} run(s), {:.1f} MB", removed.size(), freed / 1e6);
}

// After a SIGINT or SIGTERM, once the runs under way have stopped: the summary
// of what finished, where the others stopped, and the command that goes on.
// `phase` is "intrinsic" or "extrinsic".
Interruption interruption(const std::string& phase_name, const std::vector<PlannedRun>& runs, const PhaseRuns& phase,
                          bool extrinsic_to_come, const ExperimentRequest& o) {
  Interruption in;
  in.signal = signalName(g_signal);
  in.phase = phase_name;
  in.finished = static_cast<std::int64_t>(phase.finishedCount());
  in.planned = static_cast<std::int64_t>(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (phase.finished[i]) continue;
    const std::string& id = runs[i].spec.run_id;
    const fs::path dir = fs::path(o.plan.log_root) / id;
    if (auto c = phase.cut.find(i); c != phase.cut.end())
      in.cut.push_back({id, c->second, fs::exists(dir) ? Nullable<std::string>(dir.string()) : Nullable<std::string>()});
    else
      in.not_started.push_back(id);
  }
  in.extrinsic_tests_to_come = extrinsic_to_come;
  in.resume = resumeCommand(o);
  in.resume_in = fs::current_path().string();
  return in;
}

// Once `in` is in summary.json: the experiment's state says so, and the log what is kept and what comes.
int stopHere(const Interruption& in, const ExperimentRequest& o, json& state, spdlog::logger& log) {
  const std::string &signal = in.signal, &phase_name = in.phase, &cwd = in.resume_in, &command = in.resume;
  state["state"] = "interrupted";
  state["interruptions"].push_back({{"signal", signal}, {"phase", phase_name}, {"cut", toJson(in)["cut"]}});
  writeWhole(statePath(o.write.out_dir), state.dump(2) + "\n");

  const std::string what = phase_name == "intrinsic" ? "intrinsic run(s)" : "extrinsic test(s)";
  log.warn("interrupted by {} during the {} phase", signal, phase_name);
  log.info("kept: {} of {} {} finished{}, in {} and the CSV files beside it", in.finished, in.planned, what,
           phase_name == "extrinsic" ? " (and every intrinsic run)" : "",
           (fs::path(o.write.out_dir) / "summary.json").string());
  for (const CutRun& c : in.cut)
    log.info("cut: {} ({}){}", c.run_id, c.where, c.log_dir ? "; its log, incomplete, stays in " + *c.log_dir : "");
  if (!in.not_started.empty()) log.info("not started: {} {}", in.not_started.size(), what);
  if (in.extrinsic_tests_to_come) log.info("not started: the extrinsic tests");
  log.warn("to resume (in {}): {}", cwd, command);
  return 128 + g_signal;
}


// The design's summary of a part's tests (after summariseExtrinsic).
void summariseTests(Summary& summary, const Part& part, const std::vector<PlannedRun>& tests, const PhaseRuns& phase,
                    const std::vector<std::string>& untested) {
  const Plan& plan = part.plan;
  summariseExtrinsic(summary, plan, tests, phase, part.out_dir);
  summariseDesign(summary, testRecords(plan, tests, phase), plan.conditions, plan.design, plan.systems, plan.scenarios);
  DesignSummary& d = summary.extrinsic_design.emplace();
  d.scenarios = plan.scenarios;
  d.tests = plan.tests;
  for (const auto& [k, v] : plan.design.vary) d.vary[k] = v;
  d.analysis = plan.design.analysis;
  d.after_actions = plan.design.after_actions;
  if (plan.design.generate) {
    const GenerateDesign& g = *plan.design.generate;
    d.generate = GenerateSummary{{g.sub_goals.begin(), g.sub_goals.end()},
                                 {g.objects.begin(), g.objects.end()},
                                 g.per_point,
                                 g.seed,
                                 {g.all_multi_step, g.multi_step}};
  }
  if (plan.design.after_actions > 0) summary.after_actions = plan.design.after_actions;
  if (!untested.empty()) summary.untested_agents = untested;
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
                                         slicePhase(intrinsic, part.offset, part.plan.runs.size()).outcomes, part.request,
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
SweepSummary sweepSummary(const std::vector<Part>& parts, std::vector<Summary>& summaries, const Sweep& sweep,
                          const std::string& out_dir) {
  SweepSummary whole;
  for (const auto& [k, v] : sweep.keys) whole.sweep.keys[k] = v;
  std::map<std::string, std::pair<std::string, std::string>> csvs;  // file -> header, rows
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const Part& part = parts[k];
    Summary& s = summaries[k];
    s.sweep_condition = part.condition;
    s.sweep_settings = part.condition_settings;
    for (auto& [sys, js] : s.systems)
      for (RunEntry& entry : js.runs) entry.sweep_condition = part.condition;
    whole.sweep.conditions.push_back(
        {part.condition, part.condition_settings, (fs::path("conditions") / fs::path(part.out_dir).filename()).string()});
    whole.conditions[part.condition] = s;
    std::error_code ec;
    std::vector<fs::path> files;
    for (const auto& f : fs::directory_iterator(part.out_dir, ec))
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
  for (const auto& [file, hr] : csvs) writeWhole(fs::path(out_dir) / file, hr.first + "\n" + hr.second);
  static_cast<ExperimentHeader&>(whole) = summaries.front();  // what every condition shares
  whole.settings = sweep.fixed;
  return whole;
}

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

namespace {

// ---- the pipeline -------------------------------------------------------------
//
// An experiment is a short sequence of stages: prepare (check and plan),
// open its folder, run the intrinsic phase, summarise it, run the extrinsic
// tests, summarise them, and present. Where the outcomes come from is the
// executor's business: a fresh or resumed experiment runs what is not kept
// yet (this shard's share), a merge takes them from the shards' folders.

// What an experiment is once checked and planned.
struct Experiment {
  ExperimentRequest o;           // as it runs: a resumed one's stored request, with the run options given now
  nlohmann::json state;          // DIR/experiment.json
  Sweep sweep;
  std::vector<Part> parts;       // one, or one per sweep condition
  std::vector<PlannedRun> runs;  // every part's intrinsic runs, in one list
  Hosting hosting;
  std::string bin;               // the processes' executables (udpm)
  OutDirLock lock;               // its folder's, from openFolder until it is over
  bool merging() const { return !o.merged_from.empty(); }
  const Plan& plan() const { return parts.front().plan; }  // what every part shares
  std::filesystem::path out() const { return o.write.out_dir; }
  void saveState() { writeWhole(statePath(out()), state.dump(2) + "\n"); }
};

// How a phase's runs get their outcomes.
class Executor {
 public:
  virtual ~Executor() = default;
  // Before the phase's kept outcomes are read: a merge keeps the shards' outcomes as its own.
  virtual void gather(const std::vector<PlannedRun>& runs, bool extrinsic) = 0;
  // The runs not finished yet: run them (or, for a merge, nothing is left).
  virtual void execute(const std::vector<PlannedRun>& runs, bool extrinsic, PhaseRuns& phase) = 0;
};

// The experiments of a queue claim their agents in the queue's order (see
// AgentClaims): entry k claims once every entry before it has claimed, or
// will claim nothing.
class Turns {
 public:
  void wait(std::size_t k) {
    std::unique_lock<std::mutex> lock(mutex_);
    moved_.wait(lock, [&] { return turn_ >= k; });
  }
  void pass(std::size_t k) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      passed_.insert(k);
      while (passed_.count(turn_)) ++turn_;
    }
    moved_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable moved_;
  std::set<std::size_t> passed_;
  std::size_t turn_ = 0;  // every entry before it has passed
};

// What an experiment shares with the others of its queue (none when it runs alone).
struct Shared {
  SlotPool* pool = nullptr;
  AgentClaims* claims = nullptr;
  Turns* turns = nullptr;
  std::size_t position = 0;  // in the queue
  std::string network;       // where the queue's slots run
};

// Runs them here on the job slots: a fresh experiment, a resumed one, a shard.
// An agent's tests start as soon as it is trained (or taken from the store):
// they run ahead of the extrinsic phase, which finds their outcomes kept.
class Hosted : public Executor {
 public:
  Hosted(const Experiment& x, spdlog::logger& log, SlotPool& pool, const Shared& share)
      : x_(x), log_(log), pool_(pool), share_(share), agents_((fs::path(x.o.plan.log_root) / "agents").string()),
        // The store knows the shipped processes' code (its key), not what a swapped command runs.
        reuse_(x.o.host.reuse_agents && x.o.host.processes.empty()) {}
  ~Hosted() override { waitAhead(); }
  // Before the extrinsic phase reads the outcomes kept: every test started ahead is over.
  void gather(const std::vector<PlannedRun>&, bool extrinsic) override {
    if (extrinsic) waitAhead();
  }
  void execute(const std::vector<PlannedRun>& runs, bool extrinsic, PhaseRuns& phase) override {
    if (extrinsic) {
      for (std::size_t i = 0; i < runs.size(); ++i)  // a test a stop signal cut while it ran ahead
        if (auto c = ahead_cut_.find(runs[i].spec.run_id); c != ahead_cut_.end() && !phase.finished[i])
          phase.cut[i] = c->second;
      run(runs, phase, {});
      return;
    }
    if (x_.o.host.reuse_agents && !reuse_)
      log_.info("--process: the agents of this experiment are neither taken from nor kept in {}/agents",
                x_.o.plan.log_root);
    const OnFinished trained = [&](std::size_t i) {
      if (reuse_) storeAgent(runs[i], phase, agents_, log_);
      testAhead(i, phase);
    };
    // (The tests of an agent trained before a resume run in the extrinsic phase, which first moves aside
    // the folders a stop signal left.)
    if (reuse_) takeStored(runs, phase);
    if (reuse_ && share_.claims) {
      queued(runs, phase, trained);
      return;
    }
    if (share_.turns) share_.turns->pass(share_.position);  // it claims nothing: the next may
    run(runs, phase, trained);
  }

 private:
  RunContext context() const {
    return RunContext{x_.o.host, x_.o.plan.log_root, x_.o.write.out_dir, x_.plan().protocol, x_.bin, &log_};
  }
  void run(const std::vector<PlannedRun>& runs, PhaseRuns& phase, const OnFinished& on_finished) {
    executeRuns(runs, phase, context(), pool_, on_finished);
  }

  // The agents stored already, taken, and their tests started.
  void takeStored(const std::vector<PlannedRun>& runs, PhaseRuns& phase) {
    const std::vector<char> before = phase.finished;
    takeStoredAgents(runs, x_.plan().design.after_actions, phase, agents_, x_.o.write.out_dir, log_);
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (phase.finished[i] && !before[i]) testAhead(i, phase);
  }

  // The tests of trained agent i not kept yet, started on the slots now (a stop signal: none).
  void testAhead(std::size_t i, const PhaseRuns& phase) {
    if (x_.plan().tests <= 0 || !phase.outcomes[i].ok || stopRequested()) return;
    for (const Part& part : x_.parts) {
      if (i < part.offset || i >= part.offset + part.plan.runs.size()) continue;
      std::vector<RunOutcome> trained(part.plan.runs.size());
      trained[i - part.offset] = phase.outcomes[i];
      std::vector<std::string> errors;  // said when the extrinsic phase plans every test
      std::vector<PlannedRun> tests;
      try {
        for (PlannedRun& t : planExtrinsic(part.plan, trained, part.request, errors))
          if (!keptOutcome(x_.out(), t.spec.run_id)) tests.push_back(std::move(t));
      } catch (const std::exception& e) {
        log_.warn("the tests of run '{}' wait for the extrinsic phase ({})", x_.runs[i].spec.run_id, e.what());
        return;
      }
      if (tests.empty()) return;
      auto ahead = std::make_unique<RunsAhead>(std::move(tests), context(), pool_);
      std::lock_guard<std::mutex> lock(ahead_mutex_);
      ahead_.push_back(std::move(ahead));
    }
  }

  // Every test started ahead has run (or was dropped after a stop signal).
  void waitAhead() {
    std::vector<std::unique_ptr<RunsAhead>> ahead;
    {
      std::lock_guard<std::mutex> lock(ahead_mutex_);
      ahead.swap(ahead_);
    }
    std::size_t ran = 0;
    for (auto& a : ahead) {
      ran += a->wait();
      ahead_cut_.merge(a->cut());
    }
    // In a queue the board counted them as they were started; the phase counts them again as kept.
    if (pool_.queue()) pool_.progress().uncount(ran);
  }

  // In a queue: an agent another experiment of the queue trains already (claimed first, in the queue's
  // order) is waited for and taken from the store, not trained twice.
  void queued(const std::vector<PlannedRun>& runs, PhaseRuns& phase, const OnFinished& trained) {
    using ClaimPtr = std::shared_ptr<AgentClaims::Claim>;
    std::vector<ClaimPtr> mine(runs.size()), theirs(runs.size());
    const std::int64_t after = x_.plan().design.after_actions;
    const std::vector<char> elsewhere = phase.elsewhere;
    share_.turns->wait(share_.position);
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (!phase.finished[i] && (elsewhere.empty() || !elsewhere[i]))
        theirs[i] = share_.claims->claim(agentKey(runs[i].spec.config_yaml), after, runs[i].spec.run_id, mine[i]);
    share_.turns->pass(share_.position);
    std::size_t waiting = 0;
    phase.elsewhere.assign(runs.size(), 0);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      phase.elsewhere[i] = (!elsewhere.empty() && elsewhere[i]) || theirs[i] != nullptr;
      waiting += theirs[i] != nullptr;
    }
    if (waiting)
      log_.info("{}: {} intrinsic run(s) take the agent another experiment of the queue trains (the same "
                "configuration and seed), once it is stored",
                x_.plan().exp.name, waiting);
    run(runs, phase, [&](std::size_t i) {
      trained(i);
      share_.claims->settle(mine[i]);
    });
    for (const ClaimPtr& c : mine) share_.claims->settle(c);  // those not run (a stop signal) or failed
    phase.elsewhere = elsewhere;
    if (!waiting) return;
    for (const ClaimPtr& c : theirs)
      if (c) share_.claims->wait(c);
    takeStored(runs, phase);
    run(runs, phase, trained);  // an agent the other run did not store (it failed, or was stopped): trained here
  }

  const Experiment& x_;
  spdlog::logger& log_;
  SlotPool& pool_;
  const Shared share_;
  const AgentStore agents_;
  const bool reuse_;  // agents taken from and kept in the store
  std::mutex ahead_mutex_;
  std::vector<std::unique_ptr<RunsAhead>> ahead_;  // tests started ahead of the extrinsic phase
  std::map<std::string, std::string> ahead_cut_;   // ... those a stop signal cut (run id -> where)
};

// afford merge: every outcome from the shard that ran it (all gathered, and
// checked complete, before anything is written).
class Merged : public Executor {
 public:
  Merged(const Experiment& x, spdlog::logger& log) : x_(x) {
    intrinsic_ = gatherShards(x.parts, x.runs, x.o.merged_from, &tests_);
    log.info("merging {} shard(s): {} intrinsic run(s), {} test(s)", x.o.merged_from.size(), x.runs.size(),
             tests_.outcomes.size());
  }
  void gather(const std::vector<PlannedRun>& runs, bool extrinsic) override {
    const PhaseRuns& from = extrinsic ? tests_ : intrinsic_;
    for (std::size_t i = 0; i < runs.size(); ++i) keepOutcome(x_.out(), runs[i].spec.run_id, from.outcomes[i]);
  }
  void execute(const std::vector<PlannedRun>&, bool, PhaseRuns&) override {}

 private:
  const Experiment& x_;
  PhaseRuns intrinsic_, tests_;
};

// The request as it will run (a resumed one: as stored), checked and planned.
// Nothing is written or started here.
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

Experiment prepare(const ExperimentRequest& request) {
  Experiment x;
  x.o = request;
  bool stamped = false;  // the run prefix is the wall clock's, to be reserved once all is checked
  if (request.resume) {
    x.state = unfinishedState(request);
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
    refuseChangedPlan(request, requestFromJson(x.state.at("options")), x.plan());
    refuseOtherPlan(x.state.at("runs"), fingerprint(x.runs), "intrinsic runs");
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
  if (!o.resume && !x.merging()) refuseUsedLogFolders(x.runs, shardMask(o.host, x.runs.size()), o.plan.log_root);
  x.hosting = {o.host.transport, "in-process memq://", o.host.processes};
  if (x.merging())
    x.hosting.network = o.merged_network;
  else if (!o.host.attach.empty())
    x.hosting.network = "attached to " + o.host.attach;
  return x;
}

// The folder: locked, the state of a fresh experiment written (the files of
// the finished one it replaces, with --replace, removed), marked running.
void openFolder(Experiment& x) {
  const fs::path out = x.out();
  fs::create_directories(out);
  x.lock = OutDirLock(out);
  if (!x.o.resume) {
    refuseUsedOutDir(x.o);  // again, now that no other runner can write here
    clearReplaced(x.o);
    x.state = {{"experiment", x.plan().exp.name},
               {"cwd", fs::current_path().string()},
               {"options", requestToJson(x.o)},
               {"runs", fingerprint(x.runs)},
               {"interruptions", json::array()},
               {"moved_aside", json::array()}};
    if (x.merging()) x.state["merged_from"] = x.o.merged_from;
  }
  x.state["state"] = "running";
  x.state["resume"] = resumeCommand(x.o);
  x.saveState();
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
  log.info("experiment {} ({}{}): {} run(s) of {} steps, {} at a time, over {} ({})", x.plan().exp.name, systems,
           x.parts.size() > 1 ? "; " + std::to_string(x.parts.size()) + " sweep conditions" : std::string(),
           x.runs.size(), x.runs.front().spec.steps, o.host.jobs, o.host.transport, x.hosting.network);
}

// One phase: the outcomes kept already (resume; a merge's gathered ones), and the others executed.
PhaseRuns runPhase(Experiment& x, Executor& exec, const std::vector<PlannedRun>& runs, bool extrinsic,
                   spdlog::logger& log) {
  exec.gather(runs, extrinsic);
  PhaseRuns phase = keptRuns(runs, x.out());
  if (!extrinsic) phase.elsewhere = shardMask(x.o.host, runs.size());  // a shard's tests are those of its own agents
  if (x.o.resume) {
    if (!extrinsic)
      log.info("resuming {}: {} of {} run(s) finished already", x.out().string(), phase.finishedCount(), runs.size());
    else if (phase.finishedCount())
      log.info("{} of {} test(s) finished already", phase.finishedCount(), runs.size());
    const json moved = moveUnfinishedAside(runs, phase, x.o.plan.log_root, log);
    for (const auto& m : moved) x.state["moved_aside"].push_back(m);
    if (!moved.empty()) x.saveState();
  }
  exec.execute(runs, extrinsic, phase);
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
      writeWhole(x.out() / "summary.json", toJson(parts.front()).dump(2) + "\n");
      return;
    }
    SweepSummary whole = sweepSummary(x.parts, parts, x.sweep, x.o.write.out_dir);  // names each condition in its summary too
    for (std::size_t k = 0; k < x.parts.size(); ++k)
      writeWhole(fs::path(x.parts[k].out_dir) / "summary.json", toJson(parts[k]).dump(2) + "\n");
    whole.interrupted = stopped;
    whole.wall_seconds = seconds();
    writeWhole(x.out() / "summary.json", toJson(whole).dump(2) + "\n");
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
  if (x.state.contains("tests")) {
    refuseOtherPlan(x.state["tests"], fingerprint(t.runs), "extrinsic tests");
  } else {
    x.state["tests"] = fingerprint(t.runs);
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
  x.state["state"] = "finished";
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

namespace {

// A prepared experiment, run: alone (its own slots), or in a queue (`share`).
int runPrepared(Experiment& x, const std::chrono::steady_clock::time_point began, spdlog::logger& log,
                const Shared& share) {
  std::unique_ptr<SlotPool> own;  // alone: the slots serve this experiment's phases, then stop
  std::unique_ptr<Executor> exec;  // (gone before the slots: it waits for the tests it started on them)
  if (x.merging()) {
    exec = std::make_unique<Merged>(x, log);
  } else {
    if (x.o.host.attach.empty() && x.o.host.transport == "udpm") {
      x.hosting.network = share.pool ? share.network : prepareNetwork(x.o.host.netns);
      x.bin = executableDir();
    }
    SlotPool* pool = share.pool;
    if (!pool) pool = (own = std::make_unique<SlotPool>(x.o.host, false)).get();
    exec = std::make_unique<Hosted>(x, log, *pool, share);
  }
  if (!share.pool) installInterruptHandlers(resumeCommand(x.o));  // from here a signal stops the experiment in order
  openFolder(x);
  sayWhatRuns(x, log);
  const PhaseRuns intrinsic = runPhase(x, *exec, x.runs, false, log);
  Summaries s = summariseIntrinsic(x, intrinsic, log);
  s.began = began;
  if (g_signal) {
    const Interruption in = interruption("intrinsic", x.runs, intrinsic, x.plan().tests > 0, x.o);
    s.write(x, in);
    return stopHere(in, x.o, x.state, log);
  }
  warnCurveGaps(s, log);
  const Tests tests = runTests(x, *exec, s, log);
  if (g_signal) {
    const Interruption in = interruption("extrinsic", tests.runs, tests.phase, false, x.o);
    s.write(x, in);
    return stopHere(in, x.o, x.state, log);
  }
  return finish(x, s, intrinsic, tests, log);
}

}  // namespace

int runExperiment(const ExperimentRequest& request, spdlog::logger& log) {
  const auto began = std::chrono::steady_clock::now();
  Experiment x = prepare(request);  // everything is checked before anything is written or started
  return runPrepared(x, began, log, Shared{});
}

int runQueue(const std::vector<ExperimentRequest>& requests, const std::string& resume, spdlog::logger& log) {
  const auto began = std::chrono::steady_clock::now();
  if (requests.empty()) throw ConfigError("the queue is empty: give experiment names, or a --plan file with entries");
  // Every experiment is checked and planned before any is written or started.
  std::vector<Experiment> xs;
  std::map<std::string, std::string> folders;  // out dir -> the experiment writing there
  for (const ExperimentRequest& r : requests) {
    const std::string name = r.plan.experiment.empty() ? r.write.out_dir : r.plan.experiment;
    try {
      xs.push_back(prepare(r));
    } catch (const ConfigError& e) {
      throw ConfigError("queue entry " + std::to_string(xs.size() + 1) + " (" + name + "): " + e.what());
    }
    const std::string dir = fs::weakly_canonical(fs::absolute(r.write.out_dir)).string();
    if (const auto [it, fresh] = folders.emplace(dir, name); !fresh)
      throw ConfigError("queue entries " + it->second + " and " + name + " would both write to " + r.write.out_dir +
                        ": give each its own --out");
  }
  const HostRequest& host = xs.front().o.host;
  Shared share;
  if (host.transport == "udpm") share.network = prepareNetwork(host.netns);
  installInterruptHandlers(resume);
  SlotPool pool(host, true, "queue of " + std::to_string(xs.size()) + " experiment(s), runs and tests");
  AgentClaims claims;
  Turns turns;
  share.pool = &pool;
  share.claims = &claims;
  share.turns = &turns;
  log.info("queue: {} experiment(s) side by side on {} job slot(s) over {}", xs.size(), host.jobs, host.transport);
  std::vector<int> codes(xs.size(), 0);
  std::vector<std::thread> threads;
  for (std::size_t k = 0; k < xs.size(); ++k)
    threads.emplace_back([&, k] {
      Shared mine = share;
      mine.position = k;
      try {
        codes[k] = runPrepared(xs[k], std::chrono::steady_clock::now(), log, mine);
      } catch (const ConfigError& e) {
        log.error("{}: {}", xs[k].plan().exp.name, e.what());
        codes[k] = 2;
      } catch (const std::exception& e) {
        log.error("{}: {}", xs[k].plan().exp.name, e.what());
        codes[k] = 1;
      }
      turns.pass(k);  // one that stopped before claiming its agents lets the next claim
    });
  for (auto& t : threads) t.join();
  int code = 0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    if (codes[k] != 0) log.warn("queue: {} ({}) exited with status {}", xs[k].plan().exp.name, xs[k].out().string(), codes[k]);
    code = std::max(code, codes[k]);
  }
  if (g_signal) log.warn("to resume the whole queue: {}", resume);
  log.info("queue: {} experiment(s) in {}", xs.size(),
           durationText(std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count()));
  return code;
}

}  // namespace afford

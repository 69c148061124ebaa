// The runs and tests of an experiment run here, on the job slots (experiment/pipeline.hpp):
// a fresh experiment, a resumed one, a shard; stored agents taken, and an
// agent's tests started as soon as it is trained.
#include "experiment/execute/agents.hpp"
#include "experiment/run/outcome.hpp"
#include <nlohmann/json.hpp>

#include <filesystem>

#include "experiment/pipeline.hpp"

namespace afford {
namespace fs = std::filesystem;

namespace {

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
    takeStoredAgents(runs, x_.plan().design.after_actions, phase, agents_, x_.o.write.out_dir, log_,
                     static_cast<bool>(x_.o.host.on_bus));
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
      std::size_t kept = 0;
      try {
        for (PlannedRun& t : planExtrinsic(part.plan, trained, part.request, errors))
          if (keptOutcome(x_.out(), t.spec))
            ++kept;
          else
            tests.push_back(std::move(t));
      } catch (const std::exception& e) {
        log_.warn("the tests of run '{}' wait for the extrinsic phase ({})", x_.runs[i].spec.run_id, e.what());
        return;
      }
      const std::shared_ptr<Tally> tally = aheadTally();
      tally->done += kept;
      if (tests.empty()) return;
      auto ahead = std::make_unique<RunsAhead>(std::move(tests), context(), pool_, tally);
      std::lock_guard<std::mutex> lock(ahead_mutex_);
      ahead_.push_back(std::move(ahead));
    }
  }

  // The count of every test started ahead, for their [k/N] lines: N the tests of every agent the parts train.
  std::shared_ptr<Tally> aheadTally() {
    std::lock_guard<std::mutex> lock(ahead_mutex_);
    if (!tally_) {
      tally_ = std::make_shared<Tally>();
      for (const Part& p : x_.parts)
        tally_->total += p.plan.runs.size() * p.plan.conditions.size() * p.plan.scenarios.size() *
                         static_cast<std::size_t>(std::max(0, p.plan.tests));
    }
    return tally_;
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
  std::shared_ptr<Tally> tally_;                   // ... counted together
  std::map<std::string, std::string> ahead_cut_;   // ... those a stop signal cut (run id -> where)
};

}  // namespace

std::unique_ptr<Executor> hostedExecutor(const Experiment& x, spdlog::logger& log, SlotPool& pool, const Shared& share) {
  return std::make_unique<Hosted>(x, log, pool, share);
}

}  // namespace afford

// afford merge (experiment/pipeline.hpp): the outcomes of every run and test,
// from the shard that ran it, kept as the merged experiment's own.
#include "experiment/run/outcome.hpp"
#include <nlohmann/json.hpp>

#include <filesystem>

#include "experiment/pipeline.hpp"

namespace afford {
namespace fs = std::filesystem;

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
        if (auto r = keptOutcome(dir, list[i].spec)) {
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

namespace {

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
}  // namespace

std::unique_ptr<Executor> mergedExecutor(const Experiment& x, spdlog::logger& log) {
  return std::make_unique<Merged>(x, log);
}

}  // namespace afford

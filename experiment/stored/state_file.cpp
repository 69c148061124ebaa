#include "experiment/stored/state_file.hpp"

#include <algorithm>

#include "afford/checksum.hpp"
#include "afford/config.hpp"
#include "afford/migrations.hpp"
#include "afford/version.hpp"
#include "experiment/run/outcome.hpp"
#include "experiment/schema/codec.hpp"

namespace afford {
namespace fs = std::filesystem;

fs::path statePath(const fs::path& out) { return out / "experiment.json"; }

ExperimentState readState(const fs::path& out) {
  const fs::path file = statePath(out);
  try {
    ExperimentState state = fromJsonOf<ExperimentState>(readJsonFile(file, kMostStateBytes), file.string());
    // 0.1.0 and 0.2.0 kept extrinsic_reps, 0 standing for "not given" (the design's count).
    PlanRequest& plan = state.options.plan;
    if (!plan.extrinsic_reps && plan.extrinsic_reps_010 > 0) plan.extrinsic_reps = plan.extrinsic_reps_010;
    plan.extrinsic_reps_010.reset();
    return state;
  } catch (const std::exception& e) {
    throw ConfigError("cannot read " + file.string() + ": " + e.what());
  }
}

void writeState(const fs::path& out, const ExperimentState& state) {
  ExperimentState written = state;
  written.afford_version = affordVersion();
  writeWhole(statePath(out), toJsonOf(written).dump(2) + "\n");
}

std::vector<RunFingerprint> fingerprint(const std::vector<PlannedRun>& runs, const std::vector<PathMove>& moves,
                                        const std::string& planned_by) {
  std::vector<RunFingerprint> f;
  for (const auto& p : runs) {
    // A configuration names its folders as paths (its checkpoint's: <log root>/<run>/predictors.ckpt): as
    // they were stored, each moved folder's path where the text names it, the last move first.
    std::string text = planned_by.empty() ? p.spec.config_yaml : configAsWrittenBy(p.spec.config_yaml, planned_by, configMigrations());
    for (auto m = moves.rbegin(); m != moves.rend(); ++m) {
      const std::string now = m->to + "/";
      for (std::size_t at = 0; (at = text.find(now, at)) != std::string::npos;) {
        const bool starts = at == 0 || text[at - 1] == ' ' || text[at - 1] == '"' || text[at - 1] == '\'';
        if (starts) text.replace(at, m->to.size(), m->from);
        at += (starts ? m->from : m->to).size() + 1;
      }
    }
    Fnv1a h;
    h.add(text.data(), text.size());
    f.push_back({p.spec.run_id, h.hex()});
  }
  return f;
}

void refuseOtherPlan(const std::vector<RunFingerprint>& stored, const std::vector<RunFingerprint>& now,
                     const std::string& what) {
  for (std::size_t i = 0; i < std::max(stored.size(), now.size()); ++i) {
    if (i < stored.size() && i < now.size() && stored[i] == now[i]) continue;
    const std::string id = (i < stored.size() ? stored[i] : now[i]).run_id;
    throw ConfigError("--resume: the " + what + " differ from those stored: run '" + id +
                      (i < stored.size() && i < now.size() && stored[i].run_id == now[i].run_id
                           ? "' now has another configuration (did the config folder change since?)"
                           : "' is not in both") +
                      "; start a new experiment with another --out instead");
  }
}

}  // namespace afford

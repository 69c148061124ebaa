// The summaries an experiment writes besides each part's own (experiment/pipeline.hpp):
// the checkpoints not kept removed, the tests' design summary, a sweep's whole.
#include <algorithm>
#include <fstream>
#include <map>

#include "experiment/design/design.hpp"
#include "experiment/design/experiment_file.hpp"
#include "experiment/results/summary.hpp"
#include "experiment/run/outcome.hpp"
#include <nlohmann/json.hpp>

#include <filesystem>

#include "experiment/pipeline.hpp"

namespace afford {
namespace fs = std::filesystem;

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

}  // namespace afford

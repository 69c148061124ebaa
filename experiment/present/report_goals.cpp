// The report's section on GOALS agents (docs/model.md#goals-of-its-own): the
// agent that sets its own goals beside IMP, run for run in the same folders.
#include <sstream>

#include "experiment/present/report_parts.hpp"

namespace afford::report {

namespace {

double meanActions(const SystemSummary& s) {
  if (s.runs.empty()) return 0;
  double total = 0;
  for (const auto& r : s.runs)
    for (std::int64_t a : r.actions_executed) total += static_cast<double>(a);
  return total / static_cast<double>(s.runs.size());
}

std::string cell(const std::optional<double>& v, int digits = 3) { return v ? num(*v, digits) : "-"; }

// The mean success rate over the scenarios a system was tested on.
std::optional<double> meanSuccess(const SystemSummary& s) {
  if (!s.extrinsic || !s.extrinsic->success_rate || s.extrinsic->success_rate->empty()) return std::nullopt;
  double total = 0;
  for (const auto& [scenario, rate] : *s.extrinsic->success_rate) total += rate;
  return total / static_cast<double>(s.extrinsic->success_rate->size());
}

}  // namespace

std::string goalsSections(const std::vector<Folder>& folders, const Docs& docs) {
  std::ostringstream md;
  bool any = false;
  for (const auto& f : folders) any = any || f.summary.systems.count("GOALS");
  if (!any) return "";
  md << "\n## Goals of its own (beyond the paper)\n\nThe GOALS agent sets its own goals, chooses a module by the progress "
     << "of its competence and pursues each goal with the planner, learning as Algorithm 1 does ("
     << docs.link("model.md", "goals-of-its-own") << "). Beside IMP in the same folder: the mean absolute error of the "
     << "learned affordances, the actions executed per run, and the mean success rate of the extrinsic tests over the "
     << "scenarios tested.\n\n| experiment | steps | IMP error | GOALS error | IMP actions | GOALS actions | IMP success | "
     << "GOALS success |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& f : folders) {
    const auto g = f.summary.systems.find("GOALS");
    if (g == f.summary.systems.end()) continue;
    const auto i = f.summary.systems.find("IMP");
    const SystemSummary* imp = i == f.summary.systems.end() ? nullptr : &i->second;
    md << "| " << f.label << " | " << f.summary.steps << " | "
       << (imp ? cell(imp->affordance_mae) : "-") << " | " << cell(g->second.affordance_mae) << " | "
       << (imp ? num(meanActions(*imp), 0) : "-") << " | " << num(meanActions(g->second), 0) << " | "
       << (imp ? cell(meanSuccess(*imp), 2) : "-") << " | " << cell(meanSuccess(g->second), 2) << " |\n";
  }
  md << "\nWhat became of its goals, per module, over all runs: goals set, reached, and found reached when set (no "
     << "action taken: left out of the competence), competence (reached / ended, of those pursued) in the first and "
     << "last tenth of the steps, and actions spent per goal.\n\n| experiment | module | set | reached | found reached | "
     << "first tenth | last tenth | actions per goal |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& f : folders) {
    const auto g = f.summary.systems.find("GOALS");
    if (g == f.summary.systems.end() || !g->second.goals) continue;
    for (const auto& [module, m] : g->second.goals->modules)
      md << "| " << f.label << " | " << module << " | " << m.set << " | " << m.reached << " | " << m.found << " | "
         << (m.first_tenth ? num(*m.first_tenth) : "-") << " | " << (m.last_tenth ? num(*m.last_tenth) : "-") << " | "
         << (m.set > 0 ? num(static_cast<double>(m.actions) / static_cast<double>(m.set)) : "-") << " |\n";
  }
  md << "\nExplorations (`explore`) are random actions, not goals to reach: their competence is not measured. Where "
     << "GOALS is better, equal or worse than IMP, and why, is in " << docs.link("results-discussion.md") << ".\n";
  return md.str();
}

}  // namespace afford::report

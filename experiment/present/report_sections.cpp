// The report's sections beyond the paper's tables, and of the paper's section
// 3.2 (experiment/present/report_parts.hpp).
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>

#include "experiment/present/present.hpp"
#include "experiment/present/report_parts.hpp"

namespace afford::report {

namespace {

// The folder of an experiment among the report's (the first, if several), or null.
const Folder* folderOf(const std::vector<Folder>& folders, const std::string& experiment) {
  for (const auto& f : folders)
    if (f.summary.experiment == experiment) return &f;
  return nullptr;
}

// A row of a table-metric comparison: system, agent, scenarios 1-5 (the
// paper's, from reference.yaml, when `reference`), the affordance error.
void tableMetricRow(std::ostream& md, const std::string& sys, const std::string& agent, const SystemSummary& js,
                    bool reference) {
  md << "| " << sys << " | " << agent << " |";
  const std::optional<std::map<std::string, double>>& metric =
      reference ? js.reference_table_metric
                : (js.extrinsic ? js.extrinsic->table_metric : std::optional<std::map<std::string, double>>());
  for (int k = 1; k <= 5; ++k) {
    const auto v = metric ? metric->find("scenario" + std::to_string(k)) : std::map<std::string, double>::const_iterator();
    md << " " << (metric && v != metric->end() ? num(v->second, reference ? 1 : 2) : std::string("-")) << " |";
  }
  md << " " << (reference || !js.affordance_mae ? std::string("-") : num(*js.affordance_mae, 3)) << " |\n";
}

}  // namespace

std::vector<std::string> systemsOf(const std::vector<Folder>& folders) {
  std::vector<std::string> out;
  for (const auto& sys : kPaperSystems)
    for (const auto& f : folders)
      if (f.summary.systems.count(sys)) {
        out.push_back(sys);
        break;
      }
  for (const auto& f : folders)
    for (const auto& [sys, js] : f.summary.systems)
      if (std::find(out.begin(), out.end(), sys) == out.end()) out.push_back(sys);
  return out;
}

// Completion steps by number of sub-goals and their fit (paper Figure 6).
void completionSection(std::ostream& md, const std::vector<Folder>& folders) {
  const std::vector<std::string> systems = systemsOf(folders);
  md << "\n## Completion steps (paper Figure 6)\n\nMedian iterations of the solved tests, by number of sub-goals, "
        "and the least-squares fit of a x^2 + b x";
  for (const auto& f : folders)
    if (f.summary.reference_completion_fit) {
      const Fit& fit = *f.summary.reference_completion_fit;
      md << " (paper, IMP, base: " << fitText(fit.a, fit.b) << ")";
      break;
    }
  md << ":\n\n| experiment | system | 1 | 2 | 3 | 4 | 5 | fit |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& f : folders)
    for (const auto& sys : systems) {
      const auto js = f.summary.systems.find(sys);
      if (js == f.summary.systems.end() || !js->second.extrinsic || !js->second.extrinsic->completion_steps) continue;
      const SystemExtrinsic& ex = *js->second.extrinsic;
      const CompletionSteps& cs = *ex.completion_steps;
      md << "| " << f.label << " | " << sys << " |";
      for (const auto& sc : ex.scenarios) {
        const auto c = cs.scenarios.find(sc);
        md << " " << (c != cs.scenarios.end() && c->second.n ? num(c->second.median, 1) : std::string("-")) << " |";
      }
      md << " " << (cs.fit ? fitText(cs.fit->a, cs.fit->b) : "-") << " |\n";
    }
}

// Section 3.2 of the paper: stochastic affordances (Figure 11) and the planner tests (Figures 12-14).
std::string stochasticSections(const std::vector<Folder>& folders, const Reference& ref) {
  const double turn_blue = ref.required("thresholds.stochastic_checks.turn_blue");
  const double move_red = ref.required("thresholds.stochastic_checks.move_red");
  std::ostringstream md;
  for (const auto& f : folders) {
    const Summary& s = f.summary;
    if (s.experiment == "stochastic") {
      md << "\n## Stochastic affordances (paper 3.2.1, Table 7, Figure 11)" << labelled(f) << "\n" << claim(ref, s)
         << "\n| system | mean absolute error vs Table 7 | IMP check: turn blue (" << num(turn_blue, 1)
         << ") | move, red objects (" << num(move_red, 1) << ") |\n|---|---|---|---|\n";
      for (const auto& [sys, js] : s.systems) {
        if (!js.affordance || !js.target) continue;
        double blue = 0, move = 0;
        int nb = 0, nm = 0;
        for (std::size_t i = 0; i < js.target->size() && i < js.affordance->size(); ++i) {
          const auto &target = js.target->at(i), &learned = js.affordance->at(i);
          if (std::abs(target.at(3) - turn_blue) < 1e-9) blue += learned.at(3), ++nb;
          if (std::abs(target.at(0) - move_red) < 1e-9) move += learned.at(0), ++nm;
        }
        md << "| " << sys << " | " << num(js.affordance_mae.value_or(0.0), 3);
        if (js.reference_affordance_mae) md << " (" << num(*js.reference_affordance_mae, 3) << " authors' code)";
        md << " | " << (nb ? num(blue / nb) : "-") << " | " << (nm ? num(move / nm) : "-") << " |\n";
      }
    }
    if (s.utility) {
      const UtilityAnalysis& u = *s.utility;
      md << "\n## Goal-based vs utility-based planner (paper 3.2.2, Table 8, Figure 12)" << labelled(f) << "\n"
         << claim(ref, s) << "\nMean utility gained per test (" << u.system << " agents, scenario " << u.scenario
         << "), with Welch's two-sided t-test:\n\n"
         << "| action budget | goal-based | utility-based | p |\n|---|---|---|---|\n";
      for (std::size_t k = 0; k < u.budgets.size() && k < u.goal_mean.size() && k < u.utility_mean.size(); ++k)
        md << "| " << u.budgets[k] << " | " << num(u.goal_mean[k], 3) << " | " << num(u.utility_mean[k], 3) << " | "
           << pValue(k < u.p_values.size() ? u.p_values[k] : Nullable<double>()) << " |\n";
    }
    if (s.forward_models && !withTheAuthorsEye(s.experiment)) {
      const ForwardModelsAnalysis& fm = *s.forward_models;
      md << "\n## Forward models after " << s.after_actions.value_or(0) << " actions (paper 3.2.3, Figure 13)"
         << labelled(f) << "\n" << claim(ref, s)
         << "\nMean utility of the utility planner, by action budget, and Welch's t-test p values:\n\n| system |";
      for (const auto b : fm.budgets) md << " budget " << b << " |";
      md << "\n|---|";
      for (std::size_t k = 0; k < fm.budgets.size(); ++k) md << "---|";
      md << "\n";
      for (const auto& [sys, js] : s.systems) {
        if (!js.utility_mean) continue;
        md << "| " << sys << " |";
        for (const double m : *js.utility_mean) md << " " << num(m, 3) << " |";
        md << "\n";
      }
      for (const auto& [pair, ps] : fm.p_values) {
        md << "| p " << pair << " |";
        for (const auto& p : ps) md << " " << pValue(p) << " |";
        md << "\n";
      }
    }
    if (s.search) {
      const SearchAnalysis& r = *s.search;
      md << "\n## Affordance-restricted search (paper 3.2.4, Figure 14)" << labelled(f) << "\n" << claim(ref, s)
         << "\nMean actions checked per sub-goal (" << r.system << " agents): with restriction "
         << num(r.restricted_mean, 3) << ", without " << num(r.unrestricted_mean, 3)
         << "; Welch's t-test p = " << pValue(r.p_value) << ".\n";
    }
  }
  return md.str();
}

// Issue 28: an experiment with the authors' eye (NAME-true-centre) beside the
// same experiment with ours (NAME) and, where the paper has a table, the paper's.
std::string authorsEyeSections(const std::vector<Folder>& folders, const Docs& docs) {
  std::ostringstream md;
  bool header = false;
  for (const auto& tf : folders) {
    const std::string& exp = tf.summary.experiment;
    if (!withTheAuthorsEye(exp)) continue;
    const std::string plain = exp.substr(0, exp.size() - kAuthorsEyeSuffix.size());
    const Folder* ours = folderOf(folders, plain);
    if (!header)
      md << "\n## Beyond the paper: the authors' eye (issue 28)\n\nThe same experiments with `eye.fovea: true_centre`: "
         << "the eye's window goes on the true centre of the object whose blob it found, as the authors' eye does, "
         << "and the environment lists its objects' centres in every SCENE for it, so the eye no longer works from "
         << "the image alone (" << docs.link("model.md", "fovea") << "). Ours places the window on the blob's "
         << "centroid. What changes, and why: " << docs.link("results-discussion.md", "authors-eye") << ".\n";
    header = true;
    const std::string ours_label = ours ? ours->label : plain;
    if (tf.summary.forward_models) {
      md << "\n### " << plain << " with the authors' eye" << labelled(tf) << "\n\nMean utility of the utility planner "
         << "by action budget: ours (" << ours_label << "), with the authors' eye (" << tf.label << ").\n\n| system | eye |";
      for (const auto b : tf.summary.forward_models->budgets) md << " budget " << b << " |";
      md << "\n|---|---|";
      for (std::size_t k = 0; k < tf.summary.forward_models->budgets.size(); ++k) md << "---|";
      md << "\n";
      for (const auto& [sys, js] : tf.summary.systems) {
        const auto utility = [&](const std::string& eye, const SystemSummary& one) {
          if (!one.utility_mean) return;
          md << "| " << sys << " | " << eye << " |";
          for (const double m : *one.utility_mean) md << " " << num(m, 3) << " |";
          md << "\n";
        };
        if (ours)
          if (const auto oj = ours->summary.systems.find(sys); oj != ours->summary.systems.end()) utility("ours", oj->second);
        utility("authors'", js);
      }
      for (const auto& [pair, ps] : tf.summary.forward_models->p_values) {
        md << "| p " << pair << " | authors' |";
        for (const auto& p : ps) md << " " << pValue(p) << " |";
        md << "\n";
      }
      continue;
    }
    md << "\n### " << plain << " with the authors' eye" << labelled(tf) << "\n\nTable metric per scenario: the "
       << "paper's, ours (" << ours_label << "), with the authors' eye (" << tf.label << "); then the mean absolute error "
       << "of the learned affordances.\n\n| system | agent | scenario1 | scenario2 | scenario3 | scenario4 | scenario5 | "
       << "affordance error |\n|---|---|---|---|---|---|---|---|\n";
    for (const std::string sys : {"FIX", "IGN", "IMP"}) {
      const auto tj = tf.summary.systems.find(sys);
      if (tj == tf.summary.systems.end()) continue;
      if (tj->second.reference_table_metric) tableMetricRow(md, sys, "paper", tj->second, true);
      if (ours)
        if (const auto oj = ours->summary.systems.find(sys); oj != ours->summary.systems.end())
          tableMetricRow(md, sys, "ours", oj->second, false);
      tableMetricRow(md, sys, "authors' eye", tj->second, false);
    }
  }
  return md.str();
}

// Beyond the paper (issue 11): random tables, and the late-object tests with the memory options beside the paper's
// agent and the paper's tables.
std::string memorySections(const std::vector<Folder>& folders, const Docs& docs) {
  std::ostringstream md;
  bool header = false;
  const auto heading = [&] {
    if (!header)
      md << "\n## Beyond the paper: experience replay and revisits (issue 11)\n\nThe memory options of "
         << docs.link("model.md", "memory") << ": `predictors.replay.enabled` and `motivation.revisit.enabled`, with the "
         << "shipped values of their other keys.\n";
    header = true;
  };
  for (const auto& f : folders) {
    const Summary& s = f.summary;
    if (!s.random_tables) continue;
    heading();
    const RandomTables& rt = *s.random_tables;
    md << "\n### Random affordance tables (" << f.label << ")\n\n" << rt.count << " tables drawn from seed " << rt.seed
       << " (entries 0 or 1, every row and column mixed, an object's own colour never afforded), the base test's nine "
       << "objects, " << s.steps << " steps, " << s.repetitions << " run(s) per table, system and condition. Mean "
       << "absolute error of each learned table against its own table, over the tables";
    if (rt.floors) md << " (" << rt.floors->source << ")";
    md << ":\n\n| condition | system | mean | median | quartiles | worst (table) |\n|---|---|---|---|---|---|\n";
    for (const auto& c : rt.condition_order)
      for (const auto& sys : rt.system_order) {
        const auto by_condition = rt.mae.find(c);
        if (by_condition == rt.mae.end()) continue;
        const auto e = by_condition->second.find(sys);
        if (e == by_condition->second.end() || !e->second.mean) continue;
        const TableErrors& m = e->second;
        md << "| " << c << " | " << sys << " | " << num(*m.mean, 3) << " | " << num(m.median, 3) << " | "
           << num(m.q1, 3) << " - " << num(m.q3, 3) << " | " << num(m.worst.value.value_or(0.0), 3) << " (t"
           << m.worst_table << ") |\n";
      }
  }
  for (const std::string n : {"1", "2", "3"}) {
    const Folder* paper_agent = folderOf(folders, "late" + n);
    for (const auto& mf : folders) {
      if (mf.summary.experiment != "late" + n + "-memory") continue;
      const Summary& memory = mf.summary;
      heading();
      const std::string ours = paper_agent ? paper_agent->label : "late" + n;
      md << "\n### late" << n << " with the memory options" << labelled(mf) << "\n\nTable metric per scenario: the paper's, "
         << "ours with the paper's agent (" << ours << "), ours with replay and revisits (" << mf.label << "); then the mean "
         << "absolute error of the learned affordances.\n\n| system | agent | scenario1 | scenario2 | scenario3 | "
         << "scenario4 | scenario5 | affordance error |\n|---|---|---|---|---|---|---|---|\n";
      for (const std::string sys : {"FIX", "IGN", "IMP"}) {
        const auto mj = memory.systems.find(sys);
        if (mj == memory.systems.end()) continue;
        tableMetricRow(md, sys, "paper", mj->second, true);
        if (paper_agent)
          if (const auto pj = paper_agent->summary.systems.find(sys); pj != paper_agent->summary.systems.end())
            tableMetricRow(md, sys, "ours", pj->second, false);
        tableMetricRow(md, sys, "ours, memory", mj->second, false);
      }
    }
  }
  return md.str();
}

// Issue 12: designs of generated scenarios (top-down attention, multi-step
// plans, larger worlds), per condition and point, with the floors of reference.yaml.
std::string generatedSections(const std::vector<Folder>& folders, const Reference& reference, const Docs& docs) {
  const YAML::Node ref = reference.entry("generated");
  std::ostringstream md;
  bool header = false;
  for (const auto& f : folders) {
    const Summary& s = f.summary;
    if (!s.extrinsic_design || !s.extrinsic_design->generate) continue;
    if (!header)
      md << "\n## Beyond the paper: top-down attention, multi-step plans, larger worlds (issue 12)\n\nScenarios drawn by "
            "the generator ("
         << docs.link("scenarios.md", "generated-scenarios")
         << "): k sub-goals on n objects, m of them needing "
            "a colour change and a move; the options are `eye.attention` and `planner.search.max_depth` ("
         << docs.link("model.md", "top-down-attention")
         << "). Completion steps are planner iterations of solved tests; "
            "steps per sub-goal are completion / k.\n";
    header = true;
    const std::string& exp = s.experiment;
    const GenerateSummary& gen = *s.extrinsic_design->generate;
    md << "\n### " << f.label << "\n\n" << s.description << ". " << gen.per_point << " scenarios per point (seed "
       << gen.seed << "), " << s.repetitions
       << " trained agent(s) per system, one test of each scenario per agent and condition.\n";
    if (!s.experiment_file && ref && ref[exp] && ref[exp]["floors"])
      md << "\nFloors (" << reference.text(ref[exp]["source"], "generated." + exp + ".source") << "): "
         << reference.text(ref[exp]["floors"], "generated." + exp + ".floors") << ".\n";

    for (const auto& [sys, js] : s.systems) {
      if (!js.extrinsic || !js.extrinsic->conditions) continue;
      const std::vector<PlannerCondition>& conditions = *js.extrinsic->conditions;
      md << "\n| " << sys << ": condition | k | n | m | tests | solved | completion median (quartiles) | steps per sub-goal |\n"
         << "|---|---|---|---|---|---|---|---|\n";
      for (const PlannerCondition& c : conditions)
        for (const DesignPoint& p : c.points) {
          const Stats& cs = p.completion_steps;
          md << "| " << c.label << " | " << p.sub_goals << " | " << p.objects << " | " << p.multi_step << " | "
             << p.tests_completed << " | " << num(p.success_rate) << " | ";
          if (cs.n > 0)
            md << num(cs.median, 1) << " (" << num(cs.q1, 1) << " - " << num(cs.q3, 1) << ") | "
               << num(p.steps_per_sub_goal.median) << " |\n";
          else
            md << "- | - |\n";
        }
      bool fits = false;
      for (const PlannerCondition& c : conditions) fits |= c.completion_fit.has_value();
      if (fits && gen.objects.empty()) {
        md << "\nCompletion fit a x^2 + b x over the solved tests (the paper's bottom-up IMP: 1.364 x^2 - 0.808 x):\n\n"
              "| condition | a | b |\n|---|---|---|\n";
        for (const PlannerCondition& c : conditions)
          if (c.completion_fit)
            md << "| " << c.label << " | " << num(c.completion_fit->a, 3) << " | " << num(c.completion_fit->b, 3) << " |\n";
      }
    }
  }
  return md.str();
}

}  // namespace afford::report

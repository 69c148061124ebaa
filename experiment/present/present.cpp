#include "experiment/present/present.hpp"

#include <spdlog/fmt/fmt.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "afford/actions.hpp"

namespace afford {
namespace fs = std::filesystem;

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

std::string fitText(double a, double b, int digits) {
  return fixed(a, digits) + " x^2 " + (b < 0 ? "- " : "+ ") + fixed(std::abs(b), digits) + " x";
}

namespace {

std::string number(const Nullable<double>& v, int digits) { return v ? fixed(*v, digits) : std::string("-"); }

// Random tables: no one table to show, but the error of each run's learned table against its own.
void randomTablesText(std::ostringstream& t, const Summary& summary) {
  const RandomTables& rt = *summary.random_tables;
  t << "\nRandom affordance tables: " << rt.count << " tables drawn from seed " << rt.seed << ", " << summary.steps
    << " steps, " << summary.repetitions
    << " run(s) per table, system and condition.\nMean absolute error of each run's learned table against its own table";
  if (rt.floors) t << "; " << rt.floors->source;
  std::size_t cw = 13;  // the column of conditions: 13, or the longest name and a space
  for (const auto& c : rt.condition_order) cw = std::max(cw, c.size() + 1);
  t << "\n\n  " << std::left << std::setw(static_cast<int>(cw)) << "condition" << "system   mean     median   worst (table)\n";
  std::vector<std::pair<std::string, std::string>> columns;
  for (const auto& c : rt.condition_order)
    for (const auto& sys : rt.system_order) {
      const TableErrors& m = rt.mae.at(c).at(sys);
      columns.emplace_back(c, sys);
      t << "  " << std::left << std::setw(static_cast<int>(cw)) << c << std::setw(9) << sys << std::setw(9)
        << number(m.mean, 3) << std::setw(9) << fixed(m.median, 3) << number(m.worst, 3)
        << (m.worst_table >= 0 ? " (t" + std::to_string(m.worst_table) + ")" : "") << "\n";
    }
  const auto width = [](const std::string& c, const std::string& sys) {
    return std::max<int>(9, static_cast<int>(c.size() + sys.size()) + 3);
  };
  t << "\n  table ";
  for (const auto& [c, sys] : columns) t << std::right << std::setw(width(c, sys)) << (sys + " " + c);
  t << "   one-way looks (docs/model.md#revisit)\n";
  for (std::size_t k = 0; k < static_cast<std::size_t>(rt.count); ++k) {
    t << "  t" << std::left << std::setw(5) << k << std::right;
    for (const auto& [c, sys] : columns) {
      const auto& per_table = rt.mae.at(c).at(sys).per_table;
      t << std::setw(width(c, sys)) << (k < per_table.size() ? number(per_table[k], 3) : std::string("-"));
    }
    std::string one_way;
    if (k < rt.one_way_looks.size())
      for (const auto& n : rt.one_way_looks[k]) one_way += (one_way.empty() ? "" : ", ") + n;
    t << "   " << (one_way.empty() ? "-" : one_way);
    t << "\n";
  }
}

// A goals agent's modules: the goals each pursued and reached, and its competence early and late in the runs.
void goalsText(std::ostringstream& t, const GoalsSummary& g) {
  int w = 14;  // the module column: 14, or the longest name and two spaces
  for (const auto& [name, m] : g.modules) w = std::max(w, static_cast<int>(name.size()) + 2);
  t << "  goals per module: reached of pursued, competence in the first / last tenth of the steps, share chosen in "
       "the last interval\n";
  for (const auto& [name, m] : g.modules) {
    t << "    " << std::left << std::setw(w) << name;
    if (name == "explore")  // random actions, no goal to reach: no competence (docs/model.md#goals-of-its-own)
      t << std::setw(30) << (std::to_string(m.set) + " random actions");
    else
      t << std::setw(14) << (std::to_string(m.reached - m.found) + " of " + std::to_string(m.set - m.found))
        << std::setw(16) << (number(m.first_tenth, 2) + " / " + number(m.last_tenth, 2));
    t << (m.chosen.empty() ? std::string("-") : fixed(m.chosen.back(), 2)) << "\n";
  }
}

// The mean learned table of each system beside the experiment's table.
void learnedTablesText(std::ostringstream& t, const Summary& summary, const Plan& plan) {
  const auto& object_names = summary.objects;
  t << "\nLearned affordances after " << summary.steps << " steps (mean of " << summary.repetitions
    << " run(s)); in brackets the world's own table ("
    << (summary.actions.empty() || summary.actions.front() == "move" ? "the paper's, for its experiments"
                                                                     : "its truth, which physics decided")
    << ")\n";
  for (const auto& sys : plan.systems) {
    const auto it = summary.systems.find(sys);
    if (it == summary.systems.end() || !it->second.affordance || !it->second.target) continue;
    const SystemSummary& js = it->second;
    std::size_t name_width = 17;
    for (const auto& n : object_names) name_width = std::max(name_width, n.size() + 1);
    t << "\n" << std::left << std::setw(static_cast<int>(name_width) + 2) << sys;
    for (std::size_t a = 0; a < summary.actions.size(); ++a)
      t << std::setw(a + 1 < summary.actions.size() ? 12 : 0) << summary.actions[a];
    t << "\n";
    for (std::size_t i = 0; i < object_names.size() && i < js.affordance->size(); ++i) {
      t << "  " << std::left << std::setw(static_cast<int>(name_width)) << object_names[i];
      for (std::size_t a = 0; a < (*js.affordance)[i].size(); ++a)
        t << std::setw(12) << (fixed((*js.affordance)[i][a], 2) + " (" + fixed(js.target->at(i).at(a), 1) + ")");
      t << "\n";
    }
    t << "  mean absolute error " << fixed(js.affordance_mae.value_or(0.0), 3);
    if (js.reference_affordance_mae) t << " (authors' code: " << fixed(*js.reference_affordance_mae, 3) << ")";
    t << "\n";
    if (js.goals) goalsText(t, *js.goals);
  }
}

const SystemExtrinsic* extrinsicOf(const Summary& summary, const std::string& sys) {
  const auto it = summary.systems.find(sys);
  return it == summary.systems.end() || !it->second.extrinsic ? nullptr : &*it->second.extrinsic;
}

// Tests under the planner conditions a design compares (extrinsic.vary): each condition's share of tests solved
// and mean utility, per scenario when they are few and named, else per number of sub-goals (generated ones).
void conditionsText(std::ostringstream& t, const Summary& summary, const Plan& plan) {
  bool header = false;
  for (const auto& sys : plan.systems) {
    const SystemExtrinsic* ex = extrinsicOf(summary, sys);
    if (!ex || !ex->conditions || ex->conditions->size() < 2) continue;  // one condition: the table above is it
    const bool by_scenario = ex->scenarios.size() <= 6;
    std::vector<std::string> columns;
    if (by_scenario) {
      columns = ex->scenarios;
    } else {
      for (const DesignPoint& p : ex->conditions->front().points) columns.push_back(std::to_string(p.sub_goals) + " sub-goals");
    }
    std::size_t cw = 12;
    for (const PlannerCondition& c : *ex->conditions) cw = std::max(cw, c.label.size() + 2);
    if (!header) {
      t << "\nExtrinsic tests by condition (" << ex->tests_per_scenario
        << " per scenario and trained agent): share of tests solved" << (by_scenario ? ", mean utility in brackets" : "")
        << "\n";
      header = true;
    }
    t << "\n  " << std::left << std::setw(5) << sys << std::setw(static_cast<int>(cw)) << "" << std::right;
    for (const auto& c : columns) t << std::setw(14) << c;
    t << "\n";
    for (const PlannerCondition& c : *ex->conditions) {
      t << "  " << std::setw(5) << "" << std::left << std::setw(static_cast<int>(cw)) << c.label << std::right;
      if (by_scenario) {
        for (const auto& name : columns) {
          const auto it = c.scenarios.find(name);
          t << std::setw(14)
            << (it == c.scenarios.end() || it->second.tests_completed == 0
                    ? std::string("-")
                    : fixed(it->second.success_rate, 2) + " (" + fixed(it->second.utility.mean, 1) + ")");
        }
      } else {
        for (const DesignPoint& p : c.points) t << std::setw(14) << (p.tests_completed ? fixed(p.success_rate, 2) : std::string("-"));
      }
      t << "\n";
    }
  }
}

// The extrinsic tests: the table metric and share solved per scenario, the completion steps and their fit.
void extrinsicText(std::ostringstream& t, const Summary& summary, const Plan& plan) {
  bool header = false;
  bool paper = false;  // a cell has the paper's number beside it
  for (const auto& sys : plan.systems)
    if (const SystemExtrinsic* ex = extrinsicOf(summary, sys); ex && ex->table_metric)
      for (const auto& name : ex->scenarios)
        paper |= summary.systems.at(sys).reference_table_metric && summary.systems.at(sys).reference_table_metric->count(name);
  for (const auto& sys : plan.systems) {
    const SystemExtrinsic* ex = extrinsicOf(summary, sys);
    if (!ex || !ex->table_metric || !ex->success_rate) continue;
    const SystemSummary& js = summary.systems.at(sys);
    if (!header) {
      t << "\nExtrinsic tests (" << ex->tests_per_scenario
        << " per scenario and trained agent): table metric = share of agents with > 90% of their tests\n"
           "solved"
        << (paper ? "; in brackets the paper's" : "") << "; then the raw share of tests solved\n\n"
        << "       ";
      for (const auto& s : ex->scenarios) t << std::setw(14) << s;
      t << "\n";
      header = true;
    }
    const auto at = [](const std::map<std::string, double>& m, const std::string& k) {
      const auto it = m.find(k);
      return it == m.end() ? std::string("-") : fixed(it->second, 2);
    };
    t << "  " << std::left << std::setw(5) << sys << std::right;
    for (const auto& name : ex->scenarios) {
      std::string cell = at(*ex->table_metric, name);
      if (js.reference_table_metric && js.reference_table_metric->count(name))
        cell += " (" + fixed(js.reference_table_metric->at(name), 1) + ")";
      t << std::setw(14) << cell;
    }
    t << "\n  " << std::setw(5) << "" << std::right;
    for (const auto& name : ex->scenarios) t << std::setw(14) << at(*ex->success_rate, name);
    t << "\n";
  }
  conditionsText(t, summary, plan);
  for (const auto& sys : plan.systems)  // a test that failed to run is no result: "-" where none ran
    if (const SystemExtrinsic* ex = extrinsicOf(summary, sys); ex && ex->failed_tests && !ex->failed_tests->empty())
      t << "  " << sys << ": " << ex->failed_tests->size() << " test(s) failed to run and are not counted (summary.json: "
        << "systems." << sys << ".extrinsic.failed_tests); the first: " << ex->failed_tests->front().error << "\n";
  if (!header) return;
  t << "\nCompletion steps (median over solved tests) by number of sub-goals; fit a x^2 + b x";
  if (summary.reference_completion_fit)
    t << " (paper, IMP: " << fitText(summary.reference_completion_fit->a, summary.reference_completion_fit->b) << ")";
  t << "\n";
  for (const auto& sys : plan.systems) {
    const SystemExtrinsic* ex = extrinsicOf(summary, sys);
    if (!ex || !ex->completion_steps) continue;
    const CompletionSteps& cs = *ex->completion_steps;
    t << "  " << std::left << std::setw(5) << sys << std::right;
    for (const auto& s : ex->scenarios) {
      const auto c = cs.scenarios.find(s);  // none solved: no median to show
      t << std::setw(14) << (c != cs.scenarios.end() && c->second.n ? fixed(c->second.median, 1) : std::string("-"));
    }
    if (cs.fit) t << "   fit " << fitText(cs.fit->a, cs.fit->b);
    t << "\n";
  }
}

// The design's analysis: Figures 12, 13 and 14.
void analysisText(std::ostringstream& t, const Summary& summary, const Plan& plan) {
  if (summary.utility) {  // Figure 12
    const UtilityAnalysis& u = *summary.utility;
    t << "\nUtility gained per test (" << u.system << ", " << u.scenario
      << "): goal-based vs utility-based planner, Welch's t-test\n  budget   goal     utility  p\n" << std::left;
    for (std::size_t k = 0; k < u.budgets.size() && k < u.goal_mean.size() && k < u.utility_mean.size() &&
                            k < u.p_values.size();
         ++k)
      t << "  " << std::setw(6) << u.budgets[k] << "   " << fixed(u.goal_mean[k], 3) << "    "
        << fixed(u.utility_mean[k], 3) << "    " << number(u.p_values[k], 4) << "\n";
  }
  if (summary.forward_models) {  // Figure 13
    const ForwardModelsAnalysis& f = *summary.forward_models;
    t << "\nMean utility of the utility planner with agents trained for " << plan.design.after_actions
      << " actions, by action budget\n  " << std::left << std::setw(12) << "system" << std::right;
    for (const auto b : f.budgets) t << std::setw(10) << b;
    t << "\n";
    for (const auto& sys : plan.systems) {
      t << "  " << std::left << std::setw(12) << sys << std::right;
      if (const auto it = summary.systems.find(sys); it != summary.systems.end() && it->second.utility_mean)
        for (const double m : *it->second.utility_mean) t << std::setw(10) << fixed(m, 3);
      t << "\n";
    }
    for (const auto& [pair, ps] : f.p_values) {
      t << "  " << std::left << std::setw(12) << ("p " + pair) << std::right;
      for (const auto& v : ps) t << std::setw(10) << number(v, 4);
      t << "\n";
    }
  }
  if (summary.search) {  // Figure 14
    const SearchAnalysis& s = *summary.search;
    t << "\nActions checked per sub-goal (" << s.system << "): with affordance restriction "
      << fixed(s.restricted_mean, 3) << ", without " << fixed(s.unrestricted_mean, 3)
      << "; Welch's t-test p = " << (s.p_value ? fmt::format("{:.3g}", *s.p_value) : std::string("-")) << "\n";
  }
}

}  // namespace

std::string tablesText(const Summary& summary, const Plan& plan, const std::string& out_dir) {
  std::ostringstream t;
  if (summary.random_tables)
    randomTablesText(t, summary);
  else
    learnedTablesText(t, summary, plan);
  extrinsicText(t, summary, plan);
  analysisText(t, summary, plan);
  t << "\nsummary: " << (fs::path(out_dir) / "summary.json").string() << "\n";
  return t.str();
}

void printTables(const Summary& summary, const Plan& plan, const std::string& out_dir) {
  std::printf("%s", tablesText(summary, plan, out_dir).c_str());
  std::fflush(stdout);
}

}  // namespace afford

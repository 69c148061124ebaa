// The figures of the planner's tests (paper section 3.2) and of generated
// designs (experiment/present/plots_parts.hpp).
#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "experiment/design/design.hpp"
#include "experiment/present/plots_parts.hpp"

namespace afford::plots {

using nlohmann::json;

void plotStochastic(Figures& f) {
  const fs::path& dir = f.dir;
  const std::vector<std::string>& objects = f.objects;
  const std::vector<std::string>& actions = f.actions;
  const std::vector<std::string>& systems = f.systems;
  const std::string& title_base = f.title;
  std::vector<std::string>& written = f.written;
  bool stochastic = false;
  for (const auto& sys : systems)
    for (const auto& row : systemOf(f.s, sys).target.value_or(SummaryTable{}))
      for (const double v : row) stochastic |= v > 0 && v < 1;
  if (stochastic) {
    const fs::path csv = dir / "fig_stochastic.csv", gp = dir / "fig_stochastic.gp", png = dir / "fig_stochastic.png";
    std::ofstream out(csv);
    out << "system,action,object,x,target,mean,min,max\n";
    for (std::size_t k = 0; k < systems.size(); ++k) {
      const SystemSummary& js = systemOf(f.s, systems[k]);
      if (!js.affordance || !js.target || !js.affordance_min || !js.affordance_max) continue;
      for (std::size_t a = 0; a < actions.size(); ++a)
        for (std::size_t i = 0; i < objects.size(); ++i)
          out << systems[k] << "," << a << ",\"" << objects[i] << "\","
              << i + 1 + (static_cast<double>(k) - (systems.size() - 1) / 2.0) * 0.22 << "," << js.target->at(i).at(a)
              << "," << js.affordance->at(i).at(a) << "," << js.affordance_min->at(i).at(a) << ","
              << js.affordance_max->at(i).at(a) << "\n";
    }
    out.close();
    std::ofstream g(gp);
    g << "set terminal pngcairo size 1400,1000 font 'DejaVu Sans,10'\nset output " << quoted(png.string()) << "\n"
      << "set datafile separator ','\nset multiplot layout 2,2 title "
      << quoted("Stochastic affordances: mean final prediction (bars: min-max over runs) and the true probability (" + title_base + ")")
      << "\nset yrange [-0.05:1.05]\nset xrange [0.4:" << objects.size() + 0.6 << "]\nset grid ytics\n"
      << "set key outside bottom center horizontal\nset xtics (";
    for (std::size_t i = 0; i < objects.size(); ++i) g << (i ? ", " : "") << quoted(objects[i]) << " " << i + 1;
    g << ") rotate by 30 right\n";
    for (std::size_t a = 0; a < actions.size(); ++a) {
      g << "set title " << quoted(actions[a]) << "\nplot ";
      for (std::size_t k = 0; k < systems.size(); ++k)
        g << (k ? ", " : "") << quoted(csv.string()) << " using ($2==" << a << " && strcol(1) eq " << quoted(systems[k])
          << " ? $4 : NaN):6:7:8 with yerrorbars pt 7 ps 1.1 lc rgb '" << kSystemColour(systems[k]) << "' title "
          << quoted(systems[k]);
      g << ", " << quoted(csv.string()) << " using ($2==" << a << " && strcol(1) eq " << quoted(systems.front())
        << " ? $4 : NaN):5 with points pt 6 ps 2 lc rgb 'black' title "
        << quoted(f.s.experiment == "stochastic" ? "true probability (Table 7)" : "true probability (the world's table)")
        << "\n";
    }
    g << "unset multiplot\n";
    g.close();
    runGnuplot(gp);
    written.push_back(png.string());
  }
}

// Goal-based vs utility-based planner (Figure 12)
void plotUtility(Figures& f) {
  const fs::path& dir = f.dir;
  std::vector<std::string>& written = f.written;
  if (f.s.utility) {
    const UtilityAnalysis& u = *f.s.utility;
    const std::string &sys = u.system, &sc = u.scenario;
    const SystemSummary& js = systemOf(f.s, sys);
    std::vector<BoxItem> items;
    std::vector<std::pair<double, std::string>> xtics, labels;
    for (std::size_t k = 0; k < u.budgets.size(); ++k) {
      const std::string b = std::to_string(u.budgets[k]);
      const double x = static_cast<double>(k + 1);
      const auto& goal = conditionWith(js, "planner.kind", "goal", "planner.max_attempts", b);
      const auto& utility = conditionWith(js, "planner.kind", "utility", "planner.max_attempts", b);
      items.push_back({x - 0.15, "goal-based", scenarioOf(goal, sc).utility_agent_means});
      items.push_back({x + 0.15, "utility-based", scenarioOf(utility, sc).utility_agent_means});
      xtics.emplace_back(x, b);
      labels.emplace_back(x, pText(k < u.p_values.size() ? u.p_values[k] : Nullable<double>()));
    }
    written.push_back(boxPlot(dir, "fig_utility", "Utility gained per test (" + sys + "; boxes over agents, x: mean)",
                              "action budget", "utility", items, xtics, labels,
                              {{"goal-based", "#999999"}, {"utility-based", "#009e73"}}));
  }
}

// Forward models after a number of actions (Figure 13)
void plotForwardModels(Figures& f) {
  const fs::path& dir = f.dir;
  const std::vector<std::string>& systems = f.systems;
  std::vector<std::string>& written = f.written;
  if (f.s.forward_models) {
    const ForwardModelsAnalysis& fm = *f.s.forward_models;
    const std::string& sc = fm.scenario;
    std::vector<BoxItem> items;
    std::vector<std::pair<double, std::string>> xtics, labels;
    std::map<std::string, std::string> colours;
    for (std::size_t k = 0; k < fm.budgets.size(); ++k) {
      const std::string b = std::to_string(fm.budgets[k]);
      const double x = static_cast<double>(k + 1);
      for (std::size_t j = 0; j < systems.size(); ++j) {
        const SystemSummary& js = systemOf(f.s, systems[j]);
        items.push_back({x + (static_cast<double>(j) - (systems.size() - 1) / 2.0) * 0.28, systems[j],
                         scenarioOf(conditionWith(js, "planner.max_attempts", b), sc).utility_agent_means});
        colours[systems[j]] = kSystemColour(systems[j]);
      }
      xtics.emplace_back(x, b);
      std::string text;
      for (const auto& [pair, ps] : fm.p_values)
        text += (text.empty() ? "" : "\\n") + pair + " " + pText(k < ps.size() ? ps[k] : Nullable<double>());
      labels.emplace_back(x, text);
    }
    written.push_back(boxPlot(dir, "fig_forward_models", "Utility planner with the weights after " +
                                  std::to_string(f.s.after_actions.value_or(0)) + " actions (boxes over agents, x: mean)",
                              "action budget", "utility", items, xtics, labels, colours));
  }
}

// Affordance-restricted search (Figure 14)
void plotSearch(Figures& f) {
  const fs::path& dir = f.dir;
  std::vector<std::string>& written = f.written;
  if (f.s.search) {
    const SearchAnalysis& r = *f.s.search;
    const std::string &sys = r.system, &sc = r.scenario;
    const SystemSummary& js = systemOf(f.s, sys);
    const auto means = [&](const char* restricted) {
      return scenarioOf(conditionWith(js, "planner.restrict_by_affordance", restricted), sc).actions_checked_agent_means;
    };
    std::vector<BoxItem> items{{1, "restricted", means("true")}, {2, "not restricted", means("false")}};
    written.push_back(boxPlot(dir, "fig_search", "Actions checked per sub-goal (" + sys + "; boxes over agents, x: mean)",
                              "", "actions checked per sub-goal", items,
                              {{1, "affordance > 0.5 only"}, {2, "all actions"}}, {{1.5, pText(r.p_value)}},
                              {{"restricted", "#009e73"}, {"not restricted", "#999999"}}));
  }
}

// Generated scenarios (issue 12): completion steps and success per point, one line per condition
void plotGenerated(Figures& f) {
  const fs::path& dir = f.dir;
  const Summary& s = f.s;
  const std::vector<std::string>& systems = f.systems;
  std::vector<std::string>& written = f.written;
  if (s.extrinsic_design && s.extrinsic_design->generate) {
    const GenerateSummary& gen = *s.extrinsic_design->generate;
    const bool by_objects = gen.objects.size() > 1;  // else by sub-goals
    const auto xOf = [&](const DesignPoint& p) { return static_cast<double>(by_objects ? p.objects : p.sub_goals); };
    static const char* kColour[] = {"#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9"};
    for (const auto& sys : systems) {
      const SystemSummary& js = systemOf(s, sys);
      if (!js.extrinsic || !js.extrinsic->conditions) continue;
      const std::vector<PlannerCondition>& conds = *js.extrinsic->conditions;
      const std::string stem = "fig_generated" + (systems.size() > 1 ? "_" + sys : std::string());
      const fs::path csv = dir / (stem + ".csv"), gp = dir / (stem + ".gp"), png = dir / (stem + ".png");
      std::ofstream out(csv);
      out << "condition,label,sub_goals,objects,multi_step,x,tests,success_rate,completion_n,q1,median,q3,"
             "steps_per_sub_goal_median,fit_a,fit_b\n";
      double top = 1, xmin = 1e9, xmax = 0;
      for (std::size_t c = 0; c < conds.size(); ++c) {
        const PlannerCondition& cd = conds[c];
        const double a = cd.completion_fit ? cd.completion_fit->a : 0;
        const double b = cd.completion_fit ? cd.completion_fit->b : 0;
        for (const DesignPoint& p : cd.points) {
          const double x = xOf(p) + (static_cast<double>(c) - (conds.size() - 1) / 2.0) * 0.12;
          const Stats& cs = p.completion_steps;
          top = std::max(top, cs.q3);
          xmin = std::min(xmin, xOf(p));
          xmax = std::max(xmax, xOf(p));
          out << c << ",\"" << cd.label << "\"," << p.sub_goals << "," << p.objects << "," << p.multi_step << "," << x
              << "," << p.tests_completed << "," << asWritten(p.success_rate) << "," << cs.n << "," << asWritten(cs.q1)
              << "," << asWritten(cs.median) << "," << asWritten(cs.q3) << "," << asWritten(p.steps_per_sub_goal.median)
              << "," << a << "," << b << "\n";
        }
      }
      out.close();
      std::ofstream g(gp);
      g << "set terminal pngcairo size 1200,520 font 'DejaVu Sans,11' noenhanced\nset output " << quoted(png.string())
        << "\nset datafile separator ','\nset multiplot layout 1,2 title "
        << quoted(s.experiment + ", " + sys + ": generated scenarios, " + std::to_string(gen.per_point) +
                  " per point, seed " + std::to_string(gen.seed))
        << "\nset grid\nset key left top\nset xrange [" << xmin - 0.6 << ":" << xmax + 0.6 << "]\n"
        << "set xlabel " << quoted(by_objects ? "objects in the scene" : "sub-goals") << "\n"
        << "set title 'completion steps of solved tests (median, quartiles)'\nset ylabel 'steps'\nset yrange [0:"
        << top * 1.1 << "]\nplot ";
      for (std::size_t c = 0; c < conds.size(); ++c) {
        const std::string colour = kColour[c % 6];
        g << (c ? ", " : "") << quoted(csv.string()) << " using ($1 == " << c << " ? $6 : NaN):11:10:12 with yerrorlines lc rgb '"
          << colour << "' pt 7 title " << quoted(conds[c].label);
        if (!by_objects && conds[c].completion_fit)
          g << ", " << conds[c].completion_fit->a << "*x**2 + (" << conds[c].completion_fit->b << ")*x lc rgb '"
            << colour << "' dt 2 notitle";
      }
      g << "\nset key right bottom\nset title 'tests solved'\nset ylabel 'share solved'\nset yrange [0:1.05]\nplot ";
      for (std::size_t c = 0; c < conds.size(); ++c)
        g << (c ? ", " : "") << quoted(csv.string()) << " using ($1 == " << c << " ? $6 : NaN):8 with linespoints lc rgb '"
          << kColour[c % 6] << "' pt 7 title " << quoted(conds[c].label);
      g << "\nunset multiplot\n";
      g.close();
      runGnuplot(gp);
      written.push_back(png.string());
    }
  }
}

}  // namespace afford::plots

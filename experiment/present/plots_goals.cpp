// The figures of GOALS agents (docs/model.md#goals-of-its-own): competence per
// module over the run, the modules chosen over time, and the goals reached.
#include <algorithm>
#include <fstream>

#include "experiment/present/plots_parts.hpp"

namespace afford::plots {

namespace {
const char* moduleColour(const std::string& m) {
  return m == "colour" ? "#d62728" : m == "move" ? "#1f77b4" : m == "colour_place" ? "#9467bd" : "#7f7f7f";
}
}  // namespace

void plotGoals(Figures& f) {
  std::vector<std::string> systems;
  for (const auto& sys : f.systems)
    if (systemOf(f.s, sys).goals) systems.push_back(sys);
  if (systems.empty()) return;
  const fs::path csv = f.dir / "fig_goals.csv", gp = f.dir / "fig_goals.gp", png = f.dir / "fig_goals.png";
  std::vector<std::string> modules;
  {
    std::ofstream out(csv);
    out << "system,module,step,competence,chosen,reached_per_run\n";
    for (const auto& sys : systems) {
      const GoalsSummary& g = *systemOf(f.s, sys).goals;
      for (const auto& [name, m] : g.modules) {
        if (std::find(modules.begin(), modules.end(), name) == modules.end()) modules.push_back(name);
        for (std::size_t i = 0; i < g.steps.size() && i < m.chosen.size(); ++i) {
          out << sys << "," << name << "," << g.steps[i] << ",";
          if (m.competence[i]) out << asWritten(*m.competence[i]).dump();  // empty: no goal ended there
          out << "," << asWritten(m.chosen[i]).dump() << "," << asWritten(m.reached_per_run[i]).dump() << "\n";
        }
      }
    }
  }
  std::ofstream g(gp);
  g << "set terminal pngcairo noenhanced size 1500,520 font 'DejaVu Sans,10'\nset output " << quoted(png.string()) << "\n"
    << "set datafile separator ','\nset datafile missing ''\nset multiplot layout 1,3 title "
    << quoted("Goals of its own: competence, the modules chosen, the goals reached (" + f.title + ")") << "\n"
    << "set grid\nset key top left\nset xlabel 'step'\n";
  const auto panel = [&](const std::string& title, const std::string& ylabel, int column, bool unit_range,
                         bool skip_explore) {
    g << "set title " << quoted(title) << "\nset ylabel " << quoted(ylabel) << "\n"
      << (unit_range ? "set yrange [-0.02:1.02]\n" : "set autoscale y\n") << "plot ";
    bool first = true;
    for (const auto& sys : systems)
      for (const auto& m : modules) {
        if (skip_explore && m == "explore") continue;
        g << (first ? "" : ", ") << quoted(csv.string()) << " using (strcol(1) eq " << quoted(sys)
          << " && strcol(2) eq " << quoted(m) << " ? $3 : NaN):" << column << " with linespoints pt 7 ps 0.4 lc rgb '"
          << moduleColour(m) << "' title " << quoted(systems.size() > 1 ? sys + " " + m : m);
        first = false;
      }
    g << "\n";
  };
  panel("competence per module (goals reached / ended, per interval)", "competence", 4, true, true);
  panel("modules chosen (share of the goals set)", "share", 5, true, false);
  panel("goals reached per run, per interval", "goals reached", 6, false, true);
  g << "unset multiplot\n";
  g.close();
  runGnuplot(gp);
  f.written.push_back(png.string());
}

}  // namespace afford::plots

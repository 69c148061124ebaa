#include "experiment/present/plots.hpp"

#include "experiment/present/plots_parts.hpp"

#include "experiment/design/design.hpp"
#include "experiment/schema/summary.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace plots {

struct Box {
  double min = 0, q1 = 0, median = 0, q3 = 0, max = 0;
};

Box box(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return {v.front(), quantile(v, 0.25), quantile(v, 0.5), quantile(v, 0.75), v.back()};
}

const char* kSystemColour(const std::string& s) {
  return s == "FIX" ? "#e69f00" : s == "IGN" ? "#56b4e9" : s == "GOALS" ? "#cc79a7" : "#009e73";
}

// gnuplot colour and point type for an object name like "green circle"; an object whose name has no colour
// of the paper's world (the physical table's "cube", "ball") takes the `index`-th of a palette.
std::string objectStyle(const std::string& name, std::size_t index) {
  static const char* const palette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                                        "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  const bool named = name.find("red") != std::string::npos || name.find("green") != std::string::npos ||
                     name.find("blue") != std::string::npos;
  const std::string colour = !named                                    ? palette[index % 10]
                             : name.find("red") != std::string::npos   ? "#d62728"
                             : name.find("green") != std::string::npos ? "#2ca02c"
                                                                       : "#1f77b4";
  // The colour is the object's; its shape gives the line's dashes and the marker, so that the three objects of a
  // colour differ all along their lines, not only at the markers.
  const bool square = name.find("square") != std::string::npos, circle = name.find("circle") != std::string::npos;
  const int pt = square ? 5 : circle ? 7 : 3;
  const std::string dash = square ? "1" : circle ? "(10,5)" : "(2,4)";
  return "lc rgb '" + colour + "' lw 1.6 pt " + std::to_string(pt) + " dt " + dash;
}

void runGnuplot(const fs::path& script) {
  const std::string cmd = "gnuplot " + script.string() + " 2>&1";
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("gnuplot failed on " + script.string());
}

// A gnuplot string in single quotes, in which a single quote is written twice (an object named "bob's cube",
// a title "the world's table").
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string pText(const Nullable<double>& p) {
  if (!p) return "p: -";
  char buf[32];
  std::snprintf(buf, sizeof buf, "p=%.2g", *p);
  return buf;
}

// A number in a figure's CSV as summary.json writes it (all its digits).
json asWritten(double v) { return json(v); }


// Box plots (quartiles, min-max bars, median line, mean as a cross) of groups
// at labelled x positions, with optional labels (p values) above the groups.
std::string boxPlot(const fs::path& dir, const std::string& name, const std::string& title, const std::string& xlabel,
                    const std::string& ylabel, const std::vector<BoxItem>& items,
                    const std::vector<std::pair<double, std::string>>& xtics,
                    const std::vector<std::pair<double, std::string>>& labels,
                    const std::map<std::string, std::string>& colours) {
  const fs::path csv = dir / (name + ".csv"), gp = dir / (name + ".gp"), png = dir / (name + ".png");
  std::ofstream out(csv);
  out << "series,x,n,min,q1,median,q3,max,mean\n";
  double top = 0, lo = 0, left = 1e9, right = -1e9;
  for (const auto& it : items) {
    if (it.values.empty()) continue;
    const Box b = box(it.values);
    double mean = 0;
    for (double v : it.values) mean += v / it.values.size();
    out << it.series << "," << it.x << "," << it.values.size() << "," << b.min << "," << b.q1 << "," << b.median << ","
        << b.q3 << "," << b.max << "," << mean << "\n";
    top = std::max(top, b.max);
    lo = std::min(lo, b.min);
    left = std::min(left, it.x);
    right = std::max(right, it.x);
  }
  out.close();
  std::ofstream g(gp);
  g << "set terminal pngcairo size 1000,650 font 'DejaVu Sans,11'\nset output " << quoted(png.string()) << "\n"
    << "set datafile separator ','\nset title " << quoted(title) << "\nset xlabel " << quoted(xlabel)
    << "\nset ylabel " << quoted(ylabel) << "\nset grid ytics\nset boxwidth 0.25\nset key outside right top vertical\n"
    << "set xrange [" << left - 0.7 << ":" << right + 0.7 << "]\nset yrange [" << lo << ":" << (top > 0 ? top * 1.2 : 1) << "]\n";
  g << "set xtics (";
  for (std::size_t i = 0; i < xtics.size(); ++i) g << (i ? ", " : "") << quoted(xtics[i].second) << " " << xtics[i].first;
  g << ")\n";
  for (const auto& [x, text] : labels)
    g << "set label \"" << text << "\" at " << x << "," << (top > 0 ? top * 1.1 : 0.9) << " center\n";
  g << "plot ";
  bool first = true;
  for (const auto& [series, colour] : colours) {
    g << (first ? "" : ", ") << quoted(csv.string()) << " using (strcol(1) eq " << quoted(series)
      << " ? $2 : NaN):5:4:8:7 with candlesticks whiskerbars lc rgb '" << colour << "' fs solid 0.4 title "
      << quoted(series) << ", '' using (strcol(1) eq " << quoted(series)
      << " ? $2 : NaN):6:6:6:6 with candlesticks lc rgb 'black' notitle, '' using (strcol(1) eq " << quoted(series)
      << " ? $2 : NaN):9 with points pt 2 ps 1.3 lc rgb 'black' notitle";
    first = false;
  }
  g << "\n";
  g.close();
  runGnuplot(gp);
  return png.string();
}

const SystemSummary& systemOf(const Summary& s, const std::string& sys) {
  const auto it = s.systems.find(sys);
  if (it == s.systems.end()) throw std::runtime_error("summary.json has no system " + sys);
  return it->second;
}

// The planner conditions of a system's tests.
const std::vector<PlannerCondition>& conditionsOf(const SystemSummary& system) {
  if (!system.extrinsic || !system.extrinsic->conditions)
    throw std::runtime_error("summary.json has no planner conditions of the extrinsic tests");
  return *system.extrinsic->conditions;
}

// The condition whose settings give key=value (and key2=value2, if given).
const PlannerCondition& conditionWith(const SystemSummary& system, const std::string& key, const std::string& value,
                                      const std::string& key2, const std::string& value2) {
  const auto setting = [](const PlannerCondition& c, const std::string& k) {
    const auto it = c.settings.find(k);
    return it == c.settings.end() ? std::string() : it->second;
  };
  for (const PlannerCondition& c : conditionsOf(system))
    if (setting(c, key) == value && (key2.empty() || setting(c, key2) == value2)) return c;
  throw std::runtime_error("summary.json has no condition with " + key + "=" + value);
}

// One scenario's statistics under a condition.
const ConditionScenario& scenarioOf(const PlannerCondition& c, const std::string& scenario) {
  const auto it = c.scenarios.find(scenario);
  if (it == c.scenarios.end()) throw std::runtime_error("summary.json: condition '" + c.label + "' has no scenario " + scenario);
  return it->second;
}

// A sweep (issue 13): each condition's own figures in its folder, and
// figures comparing the conditions: the runs' final errors, and the tests'
// success rates over the scenarios, per condition and system.
std::vector<std::string> plotSweep(const fs::path& dir, const SweepSummary& s) {
  std::vector<std::string> written;
  const std::vector<SweepEntry>& conditions = s.sweep.conditions;
  std::string keys;
  for (const auto& [k, _] : s.sweep.keys) keys += (keys.empty() ? "" : ", ") + k;
  for (std::size_t at = 0; (at = keys.find('_', at)) != std::string::npos; at += 2) keys.insert(at, "\\");  // not a subscript
  const auto summaryOf = [&](const std::string& name) -> const Summary& {
    const auto it = s.conditions.find(name);
    if (it == s.conditions.end()) throw std::runtime_error("summary.json: sweep condition " + name + " has no summary");
    return it->second;
  };
  std::vector<std::string> systems;
  for (const auto& c : conditions)
    for (const auto& [sys, _] : summaryOf(c.name).systems)
      if (std::find(systems.begin(), systems.end(), sys) == systems.end()) systems.push_back(sys);
  std::vector<std::pair<double, std::string>> xtics;
  std::map<std::string, std::string> colours;
  for (const auto& sys : systems) colours[sys] = kSystemColour(sys);
  std::vector<BoxItem> mae, success;
  for (std::size_t k = 0; k < conditions.size(); ++k) {
    for (const auto& f : plotExperiment((dir / conditions[k].folder).string())) written.push_back(f);
    std::string tic;  // the values only: the keys are in the axis label
    for (const std::string& setting : conditions[k].settings)
      tic += (tic.empty() ? "" : ", ") + setting.substr(setting.find('=') + 1);
    xtics.emplace_back(k + 1.0, tic);
    const Summary& cs = summaryOf(conditions[k].name);
    for (std::size_t j = 0; j < systems.size(); ++j) {
      const auto it = cs.systems.find(systems[j]);
      if (it == cs.systems.end()) continue;
      const SystemSummary& js = it->second;
      const double x = k + 1 + (static_cast<double>(j) - (systems.size() - 1) / 2.0) * 0.28;
      BoxItem e{x, systems[j], {}}, t{x, systems[j], {}};
      for (const RunEntry& r : js.runs) e.values.push_back(r.affordance_mae);
      if (js.extrinsic && js.extrinsic->conditions)
        for (const PlannerCondition& c : *js.extrinsic->conditions)
          for (const auto& [scn, sc] : c.scenarios) t.values.push_back(sc.success_rate);
      mae.push_back(e);
      if (!t.values.empty()) success.push_back(t);
    }
  }
  const std::string title = s.experiment + ", " + std::to_string(s.steps) + " steps, swept over " + keys;
  written.push_back(boxPlot(dir, "fig_sweep_mae", "Final mean absolute error per run (" + title + ")", keys,
                            "mean absolute error of the learned table", mae, xtics, {}, colours));
  if (!success.empty())
    written.push_back(boxPlot(dir, "fig_sweep_success",
                              "Extrinsic success rate per scenario (" + title + ")", keys, "success rate", success,
                              xtics, {}, colours));
  return written;
}

}  // namespace plots

using namespace plots;

namespace {


// Random tables (issue 11): one box per system and condition, of the tables' errors (as Figure 5's boxes)
void plotRandomTables(Figures& f) {
  const fs::path& dir = f.dir;
  const std::string& title_base = f.title;
  std::vector<std::string>& written = f.written;
  const RandomTables& rt = *f.s.random_tables;
  const std::vector<std::string>& conditions = rt.condition_order;
  const std::vector<std::string>& order = rt.system_order;
  static const char* kConditionColour[] = {"#999999", "#009e73", "#e69f00", "#56b4e9", "#cc79a7", "#0072b2"};
  std::vector<BoxItem> items;
  std::vector<std::pair<double, std::string>> xtics;
  std::map<std::string, std::string> colours;
  for (std::size_t k = 0; k < order.size(); ++k) {
    xtics.emplace_back(k + 1.0, order[k]);
    for (std::size_t c = 0; c < conditions.size(); ++c) {
      BoxItem it;
      it.x = k + 1 + (static_cast<double>(c) - (conditions.size() - 1) / 2.0) * 0.3;
      it.series = conditions[c];
      const auto by_condition = rt.mae.find(conditions[c]);
      if (by_condition != rt.mae.end())
        if (const auto e = by_condition->second.find(order[k]); e != by_condition->second.end())
          for (const auto& v : e->second.per_table)
            if (v) it.values.push_back(*v);
      items.push_back(it);
      colours[conditions[c]] = kConditionColour[c % 6];
    }
  }
  written.push_back(boxPlot(dir, "fig_random_tables",
                            "Mean absolute error on " + std::to_string(rt.count) +
                                " random affordance tables (" + title_base + "); box: quartiles, bars: min-max, x: mean",
                            "system", "mean absolute error of the learned table", items, xtics, {}, colours));
}

// Final affordances: box plots (Figures 5, 10)
void plotAffordances(Figures& f) {
  const fs::path& dir = f.dir;
  const Summary& s = f.s;
  const std::vector<std::string>& objects = f.objects;
  const std::vector<std::string>& actions = f.actions;
  const std::vector<std::string>& systems = f.systems;
  const std::string& title_base = f.title;
  std::vector<std::string>& written = f.written;
  {
    const fs::path csv = dir / "fig_affordances.csv", gp = dir / "fig_affordances.gp", png = dir / "fig_affordances.png";
    std::ofstream out(csv);
    out << "action,object,system,x,min,q1,median,q3,max,target,n\n";
    bool single = false, several = false;  // a system with one run: a bar of its prediction, not a flat box
    for (std::size_t a = 0; a < actions.size(); ++a)
      for (std::size_t i = 0; i < objects.size(); ++i)
        for (std::size_t k = 0; k < systems.size(); ++k) {
          const SystemSummary& js = systemOf(s, systems[k]);
          std::vector<double> v;
          for (const RunEntry& r : js.runs) v.push_back(r.affordance.at(i).at(a));
          if (v.empty() || !js.target) continue;
          (v.size() == 1 ? single : several) = true;
          const Box b = box(v);
          const double x = i + 1 + (static_cast<double>(k) - (systems.size() - 1) / 2.0) * 0.25;
          out << a << ",\"" << objects[i] << "\"," << systems[k] << "," << x << "," << b.min << "," << b.q1 << ","
              << b.median << "," << b.q3 << "," << b.max << "," << js.target->at(i).at(a) << "," << v.size() << "\n";
        }
    out.close();
    const std::string legend = std::string(several ? "box: quartiles over the runs, bars: min-max" : "") +
                               (several && single ? "; " : "") + (single ? "a filled bar: the prediction of the one run" : "");
    std::ofstream g(gp);
    g << "set terminal pngcairo size 1400,1000 font 'DejaVu Sans,10'\nset output " << quoted(png.string()) << "\n"
      << "set datafile separator ','\nset multiplot layout 2,2 title " << quoted("Final affordance predictions (" + title_base + "), " + legend) << "\n"
      << "set yrange [-0.05:1.05]\nset xrange [0.4:" << objects.size() + 0.6 << "]\nset boxwidth 0.2\nset grid ytics\n"
      << "set key outside bottom center horizontal\n";
    g << "set xtics (";
    for (std::size_t i = 0; i < objects.size(); ++i) g << (i ? ", " : "") << quoted(objects[i]) << " " << i + 1;
    g << ") rotate by 30 right\n";
    for (std::size_t a = 0; a < actions.size(); ++a) {
      g << "set title " << quoted(actions[a]) << "\nplot ";
      for (std::size_t k = 0; k < systems.size(); ++k) {
        const std::string mine = "$1==" + std::to_string(a) + " && strcol(3) eq " + quoted(systems[k]);
        g << (k ? ", " : "") << quoted(csv.string()) << " using (" << mine
          << " && $11 > 1 ? $4 : NaN):6:5:9:8 with candlesticks whiskerbars lc rgb '" << kSystemColour(systems[k])
          << "' fs solid 0.4 " << (several ? "title " + quoted(systems[k]) : "notitle") << ", '' using (" << mine
          << " && $11 > 1 ? $4 : NaN):7:7:7:7 with candlesticks lc rgb 'black' notitle, '' using (" << mine
          << " && $11 == 1 ? $4 : NaN):7 with boxes lc rgb '" << kSystemColour(systems[k]) << "' fs solid 0.6 "
          << (several ? "notitle" : "title " + quoted(systems[k]));
      }
      g << ", " << quoted(csv.string()) << " using ($1==" << a
        << " ? $4 : NaN):10 with points pt 1 ps 1.2 lc rgb 'black' title 'table'\n";
    }
    g << "unset multiplot\n";
    g.close();
    runGnuplot(gp);
    written.push_back(png.string());
  }
}

// Learning curves (Figures 7-9)
void plotCurves(Figures& f) {
  const fs::path& dir = f.dir;
  const std::vector<std::string>& objects = f.objects;
  const std::vector<std::string>& actions = f.actions;
  const std::vector<std::string>& systems = f.systems;
  const std::string& title_base = f.title;
  std::vector<std::string>& written = f.written;
  for (const auto& sys : systems) {
    const SystemSummary& js = systemOf(f.s, sys);
    if (!js.curves) continue;
    const Curves& curves = *js.curves;
    const fs::path csv = dir / ("fig_curves_" + sys + ".csv"), gp = dir / ("fig_curves_" + sys + ".gp"),
                   png = dir / ("fig_curves_" + sys + ".png");
    std::ofstream out(csv);
    out << "step";
    for (std::size_t a = 0; a < actions.size(); ++a)
      for (const auto& o : objects) out << ",\"" << actions[a] << ": " << o << "\"";
    out << "\n";
    for (std::size_t t = 0; t < curves.steps.size() && t < curves.mean.size(); ++t) {
      out << curves.steps[t];
      for (std::size_t a = 0; a < actions.size(); ++a)
        for (std::size_t i = 0; i < objects.size(); ++i) out << "," << curves.mean[t].at(i).at(a);
      out << "\n";
    }
    out.close();
    std::ofstream g(gp);
    g << "set terminal pngcairo size 1400,1000 font 'DejaVu Sans,10'\nset output " << quoted(png.string()) << "\n"
      << "set datafile separator ','\nset multiplot layout 2,2 title "
      << quoted(sys + ": mean affordance predictions over " + std::to_string(js.runs.size()) + " run(s), " + title_base) << "\n"
      << "set yrange [-0.05:1.05]\nset grid\nset xlabel 'step'\nset key outside right\n";
    const std::size_t marker_every = std::max<std::size_t>(1, curves.steps.size() / 8);  // about 8 markers a line
    for (std::size_t a = 0; a < actions.size(); ++a) {
      g << "set title " << quoted(actions[a]) << "\nplot ";
      for (std::size_t i = 0; i < objects.size(); ++i)
        g << (i ? ", " : "") << quoted(csv.string()) << " using 1:" << 2 + a * objects.size() + i
          << " with linespoints pi " << marker_every << " " << objectStyle(objects[i], i) << " title " << quoted(objects[i]);
      g << "\n";
    }
    g << "unset multiplot\n";
    g.close();
    runGnuplot(gp);
    written.push_back(png.string());
  }
}

// The completion steps of a system's tests per scenario, if it has them.
const CompletionSteps* completionOf(const Summary& s, const std::string& sys) {
  const SystemSummary& js = systemOf(s, sys);
  return js.extrinsic && js.extrinsic->completion_steps ? &*js.extrinsic->completion_steps : nullptr;
}

// Completion steps (Figure 6)
void plotCompletion(Figures& f) {
  const fs::path& dir = f.dir;
  const Summary& s = f.s;
  const std::vector<std::string>& systems = f.systems;
  const std::string& title_base = f.title;
  std::vector<std::string>& written = f.written;
  bool any_extrinsic = false;
  for (const auto& sys : systems) any_extrinsic |= completionOf(s, sys) != nullptr;
  if (any_extrinsic) {
    const fs::path csv = dir / "fig_completion.csv", gp = dir / "fig_completion.gp", png = dir / "fig_completion.png";
    std::ofstream out(csv);
    out << "system,sub_goals,x,n,min,q1,median,q3,max,fit_a,fit_b\n";
    double top = 1;
    for (std::size_t k = 0; k < systems.size(); ++k) {
      const CompletionSteps* cs = completionOf(s, systems[k]);
      if (!cs) continue;
      const double a = cs->fit ? cs->fit->a : 0, b = cs->fit ? cs->fit->b : 0;
      for (const auto& sc : systemOf(s, systems[k]).extrinsic->scenarios) {
        const auto it = cs->scenarios.find(sc);
        if (it == cs->scenarios.end()) continue;
        const ScenarioSteps& c = it->second;
        const auto x = c.sub_goals;
        top = std::max(top, c.max);
        out << systems[k] << "," << x << "," << x + (static_cast<double>(k) - (systems.size() - 1) / 2.0) * 0.2 << ","
            << c.n << "," << asWritten(c.min) << "," << asWritten(c.q1) << "," << asWritten(c.median) << ","
            << asWritten(c.q3) << "," << asWritten(c.max) << "," << a << "," << b << "\n";
      }
    }
    out.close();
    std::ofstream g(gp);
    g << "set terminal pngcairo size 900,650 font 'DejaVu Sans,11'\nset output " << quoted(png.string()) << "\n"
      << "set datafile separator ','\nset title " << quoted("Completion steps of solved tests (" + title_base + ")") << "\n"
      << "set xlabel 'sub-goals (scenario)'\nset ylabel 'steps'\nset grid\nset boxwidth 0.15\nset key left top\n"
      << "set xrange [0.4:5.6]\nset yrange [0:" << top * 1.08 << "]\nplot ";
    bool first = true;
    for (std::size_t k = 0; k < systems.size(); ++k) {
      const CompletionSteps* cs = completionOf(s, systems[k]);
      if (!cs) continue;
      g << (first ? "" : ", ") << quoted(csv.string()) << " using (strcol(1) eq " << quoted(systems[k])
        << " ? $3 : NaN):6:5:9:8 with candlesticks whiskerbars lc rgb '" << kSystemColour(systems[k])
        << "' fs solid 0.4 title " << quoted(systems[k]) << ", '' using (strcol(1) eq " << quoted(systems[k])
        << " ? $3 : NaN):7:7:7:7 with candlesticks lc rgb 'black' notitle";
      if (cs->fit) {
        std::ostringstream f;
        f << cs->fit->a << "*x**2 + (" << cs->fit->b << ")*x";
        g << ", " << f.str() << " lc rgb '" << kSystemColour(systems[k]) << "' dt 2 title "
          << quoted(systems[k] + " fit");
      }
      first = false;
    }
    if (s.reference_completion_fit)
      g << ", " << s.reference_completion_fit->a << "*x**2 + (" << s.reference_completion_fit->b
        << ")*x lc rgb 'black' dt 3 title 'paper, IMP'";
    g << "\n";
    g.close();
    runGnuplot(gp);
    written.push_back(png.string());
  }
}

// Stochastic affordances: final predictions against the probabilities (Figure 11)
}  // namespace

std::vector<std::string> plotExperiment(const std::string& dir_name) {
  Figures f;
  f.dir = dir_name;
  const json j = readSummaryJson(dir_name);
  const std::string file = (f.dir / "summary.json").string();
  if (isSweepSummary(j)) return plotSweep(f.dir, sweepSummaryFromJson(j, file));
  f.s = summaryFromJson(j, file);
  f.objects = f.s.objects;
  f.actions = f.s.actions;
  for (const auto& [name, _] : f.s.systems) f.systems.push_back(name);
  f.title = f.s.experiment + ", " + std::to_string(f.s.steps) + " steps";
  if (f.s.random_tables) {  // its own figure only
    plotRandomTables(f);
    return f.written;
  }
  for (auto plot : {plotAffordances, plotCurves, plotCompletion, plotStochastic, plotUtility, plotForwardModels,
                    plotSearch, plotGenerated, plotGoals})
    plot(f);
  return f.written;
}

}  // namespace afford

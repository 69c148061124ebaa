// What the figures' files share (experiment/present/plots.cpp: the paper's
// section 3.1 figures and the sweeps'; plots_planner.cpp: the planner's and the
// generated designs' figures): gnuplot, box plots, the summary's parts. Not for
// use outside present/.
#pragma once
#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "experiment/schema/summary.hpp"

namespace afford::plots {
namespace fs = std::filesystem;

const char* kSystemColour(const std::string& s);
void runGnuplot(const fs::path& script);
std::string quoted(const std::string& s);
std::string pText(const Nullable<double>& p);
// A number in a figure's CSV as summary.json writes it (all its digits).
nlohmann::json asWritten(double v);

// One box of a box plot: its x, series (colour and legend) and values.
struct BoxItem {
  double x = 0;
  std::string series;
  std::vector<double> values;
};

// Box plots (quartiles, min-max bars, median line, mean as a cross) of groups
// at labelled x positions, with optional labels (p values) above the groups.
std::string boxPlot(const fs::path& dir, const std::string& name, const std::string& title, const std::string& xlabel,
                    const std::string& ylabel, const std::vector<BoxItem>& items,
                    const std::vector<std::pair<double, std::string>>& xtics,
                    const std::vector<std::pair<double, std::string>>& labels,
                    const std::map<std::string, std::string>& colours);

const SystemSummary& systemOf(const Summary& s, const std::string& sys);
// The planner conditions of a system's tests.
const std::vector<PlannerCondition>& conditionsOf(const SystemSummary& system);
// The condition whose settings give key=value (and key2=value2, if given).
const PlannerCondition& conditionWith(const SystemSummary& system, const std::string& key, const std::string& value,
                                      const std::string& key2 = "", const std::string& value2 = "");
// One scenario's statistics under a condition.
const ConditionScenario& scenarioOf(const PlannerCondition& c, const std::string& scenario);

// What every figure of an experiment folder is drawn from.
struct Figures {
  fs::path dir;
  Summary s;  // its summary.json
  std::vector<std::string> objects, actions, systems;
  std::string title;                 // "<experiment>, <steps> steps"
  std::vector<std::string> written;  // the figures drawn so far
};

// The figures of plots_planner.cpp, each drawn only when the summary has what it shows.
void plotStochastic(Figures& f);     // stochastic affordances (paper Figure 11)
void plotGoals(Figures& f);          // GOALS agents: competence, modules chosen, goals reached (plots_goals.cpp)
void plotUtility(Figures& f);        // the utility tests (paper Figure 12)
void plotForwardModels(Figures& f);  // the forward models' tests (paper Figure 13)
void plotSearch(Figures& f);         // the search reduction (paper Figure 14)
void plotGenerated(Figures& f);      // generated designs' success and effort

}  // namespace afford::plots

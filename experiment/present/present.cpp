#include "experiment/present/present.hpp"

#include <spdlog/fmt/fmt.h>

#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "afford/actions.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

namespace {

// Random tables: no one table to show, but the error of each run's learned table against its own.
void randomTablesText(std::ostringstream& t, const json& summary) {
  const auto& runs_steps = summary["steps"];
  const int reps = summary["repetitions"].get<int>();
  const json& rt = summary["random_tables"];
  t << "\nRandom affordance tables: " << rt["count"].get<int>() << " tables drawn from seed " << rt["seed"].get<std::int64_t>()
    << ", " << runs_steps.get<std::int64_t>() << " steps, " << reps
    << " run(s) per table, system and condition.\nMean absolute error of each run's learned table against its own table";
  if (rt.contains("floors"))
    t << "; " << rt["floors"]["source"].get<std::string>();
  std::size_t cw = 13;  // the column of conditions: 13, or the longest name and a space
  for (const auto& cj : rt["condition_order"]) cw = std::max(cw, cj.get<std::string>().size() + 1);
  t << "\n\n  " << std::left << std::setw(static_cast<int>(cw)) << "condition" << "system   mean     median   worst (table)\n";
  std::vector<std::pair<std::string, std::string>> columns;
  for (const auto& cj : rt["condition_order"])
    for (const auto& sj : rt["system_order"]) {
      const std::string c = cj.get<std::string>(), sys = sj.get<std::string>();
      const json& m = rt["mae"][c][sys];
      columns.emplace_back(c, sys);
      const auto num = [](const json& v) { return v.is_null() ? std::string("-") : fixed(v.get<double>(), 3); };
      t << "  " << std::left << std::setw(static_cast<int>(cw)) << c << std::setw(9) << sys << std::setw(9) << num(m["mean"])
        << std::setw(9) << num(m["median"]) << num(m["worst"])
        << (m["worst_table"].get<int>() >= 0 ? " (t" + std::to_string(m["worst_table"].get<int>()) + ")" : "") << "\n";
    }
  const auto width = [](const std::string& c, const std::string& sys) {
    return std::max<int>(9, static_cast<int>(c.size() + sys.size()) + 3);
  };
  t << "\n  table ";
  for (const auto& [c, sys] : columns) t << std::right << std::setw(width(c, sys)) << (sys + " " + c);
  t << "   one-way looks (docs/model.md#revisit)\n";
  for (int k = 0; k < rt["count"].get<int>(); ++k) {
    t << "  t" << std::left << std::setw(5) << k << std::right;
    for (const auto& [c, sys] : columns) {
      const json& v = rt["mae"][c][sys]["per_table"][static_cast<std::size_t>(k)];
      t << std::setw(width(c, sys)) << (v.is_null() ? std::string("-") : fixed(v.get<double>(), 3));
    }
    std::string one_way;
    for (const auto& n : rt["one_way_looks"][static_cast<std::size_t>(k)]) one_way += (one_way.empty() ? "" : ", ") + n.get<std::string>();
    t << "   " << (one_way.empty() ? "-" : one_way);
    t << "\n";
  }
}

// The mean learned table of each system beside the experiment's table.
void learnedTablesText(std::ostringstream& t, const json& summary, const Plan& plan) {
  const auto& runs_steps = summary["steps"];
  const auto object_names = summary["objects"].get<std::vector<std::string>>();
  const int reps = summary["repetitions"].get<int>();
  t << "\nLearned affordances after " << runs_steps.get<std::int64_t>() << " steps (mean of " << reps
    << " run(s)); in brackets the paper's table\n";
  for (const auto& sys : plan.systems) {
    const json& js = summary["systems"][sys];
    if (!js.contains("affordance")) continue;
    std::size_t name_width = 17;
    for (const auto& n : object_names) name_width = std::max(name_width, n.size() + 1);
    t << "\n" << std::left << std::setw(static_cast<int>(name_width) + 2) << sys
      << "move        turn green  turn red    turn blue\n";
    for (std::size_t i = 0; i < object_names.size(); ++i) {
      t << "  " << std::left << std::setw(static_cast<int>(name_width)) << object_names[i];
      for (int a = 0; a < kNumActions; ++a)
        t << std::setw(12)
          << (fixed(js["affordance"][i][a].get<double>(), 2) + " (" + fixed(js["target"][i][a].get<double>(), 1) + ")");
      t << "\n";
    }
    t << "  mean absolute error " << fixed(js["affordance_mae"].get<double>(), 3);
    if (js.contains("reference_affordance_mae"))
      t << " (authors' code: " << fixed(js["reference_affordance_mae"].get<double>(), 3) << ")";
    t << "\n";
  }
}

// The extrinsic tests: the table metric and share solved per scenario, the completion steps and their fit.
void extrinsicText(std::ostringstream& t, const json& summary, const Plan& plan) {
  bool header = false;
  for (const auto& sys : plan.systems) {
    const json& js = summary["systems"][sys];
    if (!js.contains("extrinsic") || !js["extrinsic"].contains("table_metric")) continue;
    const json& ex = js["extrinsic"];
    if (!header) {
      t << "\nExtrinsic tests (" << ex["tests_per_scenario"].get<int>()
        << " per scenario and trained agent): table metric = share of agents with > 90% of their tests\n"
           "solved; in brackets the paper's; then the raw share of tests solved\n\n"
        << "       ";
      for (const auto& s : ex["scenarios"]) t << std::setw(14) << s.get<std::string>();
      t << "\n";
      header = true;
    }
    t << "  " << std::left << std::setw(5) << sys << std::right;
    for (const auto& s : ex["scenarios"]) {
      const std::string name = s.get<std::string>();
      std::string cell = fixed(ex["table_metric"][name].get<double>(), 2);
      if (js.contains("reference_table_metric") && js["reference_table_metric"].contains(name))
        cell += " (" + fixed(js["reference_table_metric"][name].get<double>(), 1) + ")";
      t << std::setw(14) << cell;
    }
    t << "\n  " << std::setw(5) << "" << std::right;
    for (const auto& s : ex["scenarios"]) t << std::setw(14) << fixed(ex["success_rate"][s.get<std::string>()].get<double>(), 2);
    t << "\n";
  }
  if (header) {
    t << "\nCompletion steps (median over solved tests) by number of sub-goals; fit a x^2 + b x";
    if (summary.contains("reference_completion_fit"))
      t << " (paper, IMP: " << fixed(summary["reference_completion_fit"]["a"].get<double>(), 3) << " x^2 "
        << fixed(summary["reference_completion_fit"]["b"].get<double>(), 3) << " x)";
    t << "\n";
    for (const auto& sys : plan.systems) {
      const json& js = summary["systems"][sys];
      if (!js.contains("extrinsic") || !js["extrinsic"].contains("completion_steps")) continue;
      const json& cs = js["extrinsic"]["completion_steps"];
      t << "  " << std::left << std::setw(5) << sys << std::right;
      for (const auto& s : js["extrinsic"]["scenarios"]) {
        const json& c = cs[s.get<std::string>()];  // none solved: no median to show
        t << std::setw(14) << (c["n"].get<int>() ? fixed(c["median"].get<double>(), 1) : std::string("-"));
      }
      if (cs.contains("fit"))
        t << "   fit " << fixed(cs["fit"]["a"].get<double>(), 3) << " x^2 " << fixed(cs["fit"]["b"].get<double>(), 3) << " x";
      t << "\n";
    }
  }
}

// The design's analysis: Figures 12, 13 and 14.
void analysisText(std::ostringstream& t, const json& summary, const Plan& plan) {
  const auto p = [](const json& v) { return v.is_null() ? std::string("-") : fixed(v.get<double>(), 4); };
  if (summary.contains("utility")) {  // Figure 12
    const json& u = summary["utility"];
    t << "\nUtility gained per test (" << u["system"].get<std::string>() << ", " << u["scenario"].get<std::string>()
      << "): goal-based vs utility-based planner, Welch's t-test\n  budget   goal     utility  p\n" << std::left;
    for (std::size_t k = 0; k < u["budgets"].size(); ++k)
      t << "  " << std::setw(6) << u["budgets"][k].get<int>() << "   " << fixed(u["goal_mean"][k].get<double>(), 3)
        << "    " << fixed(u["utility_mean"][k].get<double>(), 3) << "    " << p(u["p_values"][k]) << "\n";
  }
  if (summary.contains("forward_models")) {  // Figure 13
    const json& f = summary["forward_models"];
    t << "\nMean utility of the utility planner with agents trained for " << plan.design.after_actions
      << " actions, by action budget\n  " << std::left << std::setw(12) << "system" << std::right;
    for (const auto& b : f["budgets"]) t << std::setw(10) << b.get<int>();
    t << "\n";
    for (const auto& sys : plan.systems) {
      t << "  " << std::left << std::setw(12) << sys << std::right;
      for (const auto& m : summary["systems"][sys]["utility_mean"]) t << std::setw(10) << fixed(m.get<double>(), 3);
      t << "\n";
    }
    for (const auto& [pair, ps] : f["p_values"].items()) {
      t << "  " << std::left << std::setw(12) << ("p " + pair) << std::right;
      for (const auto& v : ps) t << std::setw(10) << p(v);
      t << "\n";
    }
  }
  if (summary.contains("search")) {  // Figure 14
    const json& s = summary["search"];
    t << "\nActions checked per sub-goal (" << s["system"].get<std::string>() << "): with affordance restriction "
      << fixed(s["restricted_mean"].get<double>(), 3) << ", without " << fixed(s["unrestricted_mean"].get<double>(), 3)
      << "; Welch's t-test p = " << (s["p_value"].is_null() ? std::string("-") : fmt::format("{:.3g}", s["p_value"].get<double>()))
      << "\n";
  }
}

}  // namespace

void printTables(const json& summary, const Plan& plan, const std::string& out_dir) {
  std::ostringstream t;
  if (summary.contains("random_tables"))
    randomTablesText(t, summary);
  else
    learnedTablesText(t, summary, plan);
  extrinsicText(t, summary, plan);
  analysisText(t, summary, plan);
  t << "\nsummary: " << (fs::path(out_dir) / "summary.json").string() << "\n";
  std::printf("%s", t.str().c_str());
  std::fflush(stdout);
}

}  // namespace afford

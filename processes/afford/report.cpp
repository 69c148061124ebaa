#include "afford/report.hpp"

#include <nlohmann/json.hpp>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "afford/reference.hpp"
#include <cmath>

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string num(double v, int digits = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

json load(const std::string& dir) {
  std::ifstream in(fs::path(dir) / "summary.json");
  if (!in) throw std::runtime_error("no summary.json in " + dir);
  return json::parse(in);
}

}  // namespace

namespace {
std::string pValue(const json& p) {
  if (p.is_null()) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g", p.get<double>());
  return buf;
}

std::string claim(const Reference& ref, const std::string& key) {
  const YAML::Node c = ref.entry(key + "_claims");
  if (!c || !c["claim"]) return "";
  std::string source = ref.text(c["source"], key + "_claims.source");
  if (source.rfind("paper ", 0) == 0) source = source.substr(6);
  return "\nThe paper (" + source + "): " + ref.text(c["claim"], key + "_claims.claim") + ".\n";
}

// Section 3.2 of the paper: stochastic affordances (Figure 11) and the planner tests (Figures 12-14).
std::string stochasticSections(const std::vector<json>& all, const Reference& ref) {
  const double turn_blue = ref.required("thresholds.stochastic_checks.turn_blue");
  const double move_red = ref.required("thresholds.stochastic_checks.move_red");
  std::ostringstream md;
  for (const auto& s : all) {
    const std::string exp = s["experiment"];
    if (exp == "stochastic") {
      md << "\n## Stochastic affordances (paper 3.2.1, Table 7, Figure 11)\n" << claim(ref, exp)
         << "\n| system | mean absolute error vs Table 7 | IMP check: turn blue (" << num(turn_blue, 1)
         << ") | move, red objects (" << num(move_red, 1) << ") |\n|---|---|---|---|\n";
      for (const auto& [sys, js] : s["systems"].items()) {
        if (!js.contains("affordance")) continue;
        double blue = 0, move = 0;
        int nb = 0, nm = 0;
        for (std::size_t i = 0; i < js["target"].size(); ++i) {
          if (std::abs(js["target"][i][3].get<double>() - turn_blue) < 1e-9) blue += js["affordance"][i][3].get<double>(), ++nb;
          if (std::abs(js["target"][i][0].get<double>() - move_red) < 1e-9) move += js["affordance"][i][0].get<double>(), ++nm;
        }
        md << "| " << sys << " | " << num(js["affordance_mae"].get<double>(), 3);
        if (js.contains("reference_affordance_mae"))
          md << " (" << num(js["reference_affordance_mae"].get<double>(), 3) << " authors' code)";
        md << " | " << (nb ? num(blue / nb) : "-") << " | " << (nm ? num(move / nm) : "-") << " |\n";
      }
    }
    if (s.contains("utility")) {
      const json& u = s["utility"];
      md << "\n## Goal-based vs utility-based planner (paper 3.2.2, Table 8, Figure 12)\n" << claim(ref, exp)
         << "\nMean utility gained per test (" << u["system"].get<std::string>() << " agents, scenario "
         << u["scenario"].get<std::string>() << "), with Welch's two-sided t-test:\n\n"
         << "| action budget | goal-based | utility-based | p |\n|---|---|---|---|\n";
      for (std::size_t k = 0; k < u["budgets"].size(); ++k)
        md << "| " << u["budgets"][k].get<int>() << " | " << num(u["goal_mean"][k].get<double>(), 3) << " | "
           << num(u["utility_mean"][k].get<double>(), 3) << " | " << pValue(u["p_values"][k]) << " |\n";
    }
    if (s.contains("forward_models")) {
      const json& f = s["forward_models"];
      md << "\n## Forward models after " << s.value("after_actions", 0) << " actions (paper 3.2.3, Figure 13)\n"
         << claim(ref, exp) << "\nMean utility of the utility planner, by action budget, and Welch's t-test p values:\n\n| system |";
      for (const auto& b : f["budgets"]) md << " budget " << b.get<int>() << " |";
      md << "\n|---|";
      for (std::size_t k = 0; k < f["budgets"].size(); ++k) md << "---|";
      md << "\n";
      for (const auto& [sys, js] : s["systems"].items()) {
        if (!js.contains("utility_mean")) continue;
        md << "| " << sys << " |";
        for (const auto& m : js["utility_mean"]) md << " " << num(m.get<double>(), 3) << " |";
        md << "\n";
      }
      for (const auto& [pair, ps] : f["p_values"].items()) {
        md << "| p " << pair << " |";
        for (const auto& p : ps) md << " " << pValue(p) << " |";
        md << "\n";
      }
    }
    if (s.contains("search")) {
      const json& r = s["search"];
      md << "\n## Affordance-restricted search (paper 3.2.4, Figure 14)\n" << claim(ref, exp)
         << "\nMean actions checked per sub-goal (" << r["system"].get<std::string>() << " agents): with restriction "
         << num(r["restricted_mean"].get<double>(), 3) << ", without " << num(r["unrestricted_mean"].get<double>(), 3)
         << "; Welch's t-test p = " << pValue(r["p_value"]) << ".\n";
    }
  }
  return md.str();
}
}  // namespace

namespace {
// Beyond the paper (issue 11): random tables, and the late-object tests with the memory options beside the paper's
// agent and the paper's tables.
std::string memorySections(const std::vector<json>& all) {
  std::ostringstream md;
  const auto find = [&](const std::string& exp) -> const json* {
    for (const auto& s : all)
      if (s["experiment"] == exp) return &s;
    return nullptr;
  };
  bool header = false;
  const auto heading = [&] {
    if (!header)
      md << "\n## Beyond the paper: experience replay and revisits (issue 11)\n\nThe memory options of "
            "[model.md](model.md#memory): `predictors.replay.enabled` and `motivation.revisit.enabled`, with the "
            "shipped values of their other keys.\n";
    header = true;
  };
  for (const auto& s : all) {
    if (!s.contains("random_tables")) continue;
    heading();
    const json& rt = s["random_tables"];
    md << "\n### Random affordance tables (" << s["experiment"].get<std::string>() << ")\n\n" << rt["count"].get<int>()
       << " tables drawn from seed " << rt["seed"].get<std::int64_t>() << " (entries 0 or 1, every row and column mixed, "
       << "an object's own colour never afforded), the base test's nine objects, " << s["steps"] << " steps, "
       << s["repetitions"] << " run(s) per table, system and condition. Mean absolute error of each learned table "
       << "against its own table, over the tables";
    if (rt.contains("floors")) md << " (" << rt["floors"]["source"].get<std::string>() << ")";
    md << ":\n\n| condition | system | mean | median | quartiles | worst (table) |\n|---|---|---|---|---|---|\n";
    for (const auto& c : rt["condition_order"])
      for (const auto& sys : rt["system_order"]) {
        const json& m = rt["mae"][c.get<std::string>()][sys.get<std::string>()];
        if (m["mean"].is_null()) continue;
        md << "| " << c.get<std::string>() << " | " << sys.get<std::string>() << " | " << num(m["mean"].get<double>(), 3)
           << " | " << num(m["median"].get<double>(), 3) << " | " << num(m["q1"].get<double>(), 3) << " - "
           << num(m["q3"].get<double>(), 3) << " | " << num(m["worst"].get<double>(), 3) << " (t"
           << m["worst_table"].get<int>() << ") |\n";
      }
  }
  for (const std::string n : {"1", "2", "3"}) {
    const json* paper_agent = find("late" + n);
    const json* memory = find("late" + n + "-memory");
    if (!memory) continue;
    heading();
    md << "\n### late" << n << " with the memory options\n\nTable metric per scenario: the paper's, ours with the "
       << "paper's agent (late" << n << "), ours with replay and revisits (late" << n << "-memory); then the mean "
       << "absolute error of the learned affordances.\n\n| system | agent | scenario1 | scenario2 | scenario3 | "
       << "scenario4 | scenario5 | affordance error |\n|---|---|---|---|---|---|---|---|\n";
    for (const std::string sys : {"FIX", "IGN", "IMP"}) {
      if (!(*memory)["systems"].contains(sys)) continue;
      const json& mj = (*memory)["systems"][sys];
      const auto row = [&](const std::string& agent, const json& js, bool reference) {
        md << "| " << sys << " | " << agent << " |";
        for (int k = 1; k <= 5; ++k) {
          const std::string sc = "scenario" + std::to_string(k);
          const json* v = nullptr;
          if (reference && js.contains("reference_table_metric") && js["reference_table_metric"].contains(sc))
            v = &js["reference_table_metric"][sc];
          if (!reference && js.contains("extrinsic") && js["extrinsic"].contains("table_metric") &&
              js["extrinsic"]["table_metric"].contains(sc))
            v = &js["extrinsic"]["table_metric"][sc];
          md << " " << (v ? num(v->get<double>(), reference ? 1 : 2) : std::string("-")) << " |";
        }
        md << " " << (reference || !js.contains("affordance_mae") ? std::string("-") : num(js["affordance_mae"].get<double>(), 3))
           << " |\n";
      };
      row("paper", mj, true);
      if (paper_agent && (*paper_agent)["systems"].contains(sys)) row("ours", (*paper_agent)["systems"][sys], false);
      row("ours, memory", mj, false);
    }
  }
  return md.str();
}
// Issue 12: designs of generated scenarios (top-down attention, multi-step
// plans, larger worlds), per condition and point, with the floors of reference.yaml.
std::string generatedSections(const std::vector<json>& all, const Reference& reference) {
  const YAML::Node ref = reference.entry("generated");
  std::ostringstream md;
  bool header = false;
  for (const auto& s : all) {
    if (!s.contains("extrinsic_design") || !s["extrinsic_design"].contains("generate")) continue;
    if (!header)
      md << "\n## Beyond the paper: top-down attention, multi-step plans, larger worlds (issue 12)\n\nScenarios drawn by "
            "the generator ([scenarios.md](scenarios.md#generated-scenarios)): k sub-goals on n objects, m of them needing "
            "a colour change and a move; the options are `eye.attention` and `planner.search.max_depth` "
            "([model.md](model.md#top-down-attention)). Completion steps are planner iterations of solved tests; "
            "steps per sub-goal are completion / k.\n";
    header = true;
    const std::string exp = s["experiment"];
    const json& gen = s["extrinsic_design"]["generate"];
    md << "\n### " << exp << "\n\n" << s.value("description", std::string("")) << ". " << gen["per_point"].get<int>()
       << " scenarios per point (seed " << gen["seed"].get<std::int64_t>() << "), " << s["repetitions"]
       << " trained agent(s) per system, one test of each scenario per agent and condition.\n";
    if (ref && ref[exp] && ref[exp]["floors"])
      md << "\nFloors (" << reference.text(ref[exp]["source"], "generated." + exp + ".source") << "): "
         << reference.text(ref[exp]["floors"], "generated." + exp + ".floors") << ".\n";

    for (const auto& [sys, js] : s["systems"].items()) {
      if (!js.contains("extrinsic") || !js["extrinsic"].contains("conditions")) continue;
      md << "\n| " << sys << ": condition | k | n | m | tests | solved | completion median (quartiles) | steps per sub-goal |\n"
         << "|---|---|---|---|---|---|---|---|\n";
      for (const auto& c : js["extrinsic"]["conditions"])
        for (const auto& p : c["points"]) {
          const json& cs = p["completion_steps"];
          md << "| " << c["label"].get<std::string>() << " | " << p["sub_goals"] << " | " << p["objects"] << " | "
             << p["multi_step"] << " | " << p["tests_completed"] << " | " << num(p["success_rate"].get<double>()) << " | ";
          if (cs["n"].get<int>() > 0)
            md << num(cs["median"].get<double>(), 1) << " (" << num(cs["q1"].get<double>(), 1) << " - "
               << num(cs["q3"].get<double>(), 1) << ") | " << num(p["steps_per_sub_goal"]["median"].get<double>()) << " |\n";
          else
            md << "- | - |\n";
        }
      bool fits = false;
      for (const auto& c : js["extrinsic"]["conditions"]) fits |= c.contains("completion_fit");
      if (fits && gen["objects"].empty()) {
        md << "\nCompletion fit a x^2 + b x over the solved tests (the paper's bottom-up IMP: 1.364 x^2 - 0.808 x):\n\n"
              "| condition | a | b |\n|---|---|---|\n";
        for (const auto& c : js["extrinsic"]["conditions"])
          if (c.contains("completion_fit"))
            md << "| " << c["label"].get<std::string>() << " | " << num(c["completion_fit"]["a"].get<double>(), 3) << " | "
               << num(c["completion_fit"]["b"].get<double>(), 3) << " |\n";
      }
    }
  }
  return md.str();
}

}  // namespace

std::string writeReport(const std::vector<std::string>& dirs, const std::string& figures_dir,
                        const std::string& link_prefix, double wall_seconds, const std::string& note,
                        const std::string& config_dir) {
  const Reference reference(config_dir);  // before anything is written: a broken file fails the report
  std::vector<json> all;
  for (const auto& d : dirs) all.push_back(load(d));
  std::ostringstream md;
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  md << "# Results\n\nRegenerated by `scripts/reproduce.sh` on " << date << ", over "
     << all.front().value("network", std::string("?")) << ". The deterministic experiments: 10 intrinsic runs per system (seeds from 1), then 10 tests of every"
        " scenario with each trained agent (the paper's counts); the stochastic ones: the counts of their"
        " experiment files (the paper's).";
  if (wall_seconds > 0) md << " Wall time of the reproduction: " << num(wall_seconds / 60.0, 1) << " min.";
  md << "\n\n| experiment | afford | runs | tests | wall time |\n|---|---|---|---|---|\n";
  double total = 0;
  for (const auto& s : all) {
    std::size_t runs = 0, tests = 0;
    for (const auto& [sys, js] : s["systems"].items()) runs += js.contains("runs") ? js["runs"].size() : 0;
    tests = s.value("extrinsic_tests", static_cast<std::size_t>(0));
    const double w = s.value("wall_seconds", 0.0);
    total += w;
    md << "| " << s["experiment"].get<std::string>() << " | " << s.value("afford_version", std::string("?")) << " | "
       << runs << " | " << tests << " | "
       << (w > 0 ? num(w / 60.0, 1) + " min" : std::string("-")) << " |\n";
  }
  md << "| all | | | | " << num(total / 60.0, 1) << " min (2 cores) |";
  if (!note.empty()) md << "\n\n" << note;
  md << "\n\nWhere our numbers differ from the paper's, what we measured about why is in "
        "[results-discussion.md](results-discussion.md).";
  md << "\n\nNumbers in brackets are the paper's (or, where marked, the authors' code's).\n";

  // ---- intrinsic phase
  md << "\n## Intrinsic phase: learned affordances (paper Table 1, Figure 5)\n\n"
     << "Mean absolute error of the final affordance predictions against the experiment's table, mean over runs:\n\n"
     << "| experiment | steps |";
  std::vector<std::string> systems{"FIX", "IGN", "IMP"};
  for (const auto& s : systems) md << " " << s << " |";
  md << "\n|---|---|---|---|---|\n";
  for (const auto& s : all) {
    if (s.contains("random_tables")) continue;  // no one table: see the random-tables section
    md << "| " << s["experiment"].get<std::string>() << " | " << s["steps"] << " |";
    for (const auto& sys : systems) {
      if (!s["systems"].contains(sys)) {
        md << " |";
        continue;
      }
      const json& js = s["systems"][sys];
      md << " " << num(js.value("affordance_mae", 0.0), 3);
      if (js.contains("reference_affordance_mae")) md << " (" << num(js["reference_affordance_mae"].get<double>(), 3) << " authors' code)";
      md << " |";
    }
    md << "\n";
  }
  for (const auto& s : all) {
    if (s["experiment"] != "base") continue;
    md << "\nBase test, mean final prediction per object and action (FIX / IGN / IMP; the paper's table in brackets):\n\n"
       << "| object | move | turn green | turn red | turn blue |\n|---|---|---|---|---|\n";
    const auto objects = s["objects"].get<std::vector<std::string>>();
    for (std::size_t i = 0; i < objects.size(); ++i) {
      md << "| " << objects[i] << " |";
      for (int a = 0; a < 4; ++a) {
        std::string cell;
        for (const auto& sys : systems)
          if (s["systems"].contains(sys))
            cell += (cell.empty() ? "" : " / ") + num(s["systems"][sys]["affordance"][i][a].get<double>());
        md << " " << cell << " (" << num(s["systems"]["IMP"]["target"][i][a].get<double>(), 0) << ") |";
      }
      md << "\n";
    }
  }

  // ---- extrinsic phase
  md << "\n## Extrinsic phase: goal-based planner (paper Tables 2, 4, 5, 6)\n\n"
     << "Table metric: the share of trained agents that solved more than 90% of their tests of the scenario. "
        "Below it, the share of all tests solved.\n";
  for (const auto& s : all) {
    bool any = false;
    for (const auto& sys : systems)
      any |= s["systems"].contains(sys) && s["systems"][sys].contains("extrinsic") &&
             s["systems"][sys]["extrinsic"].contains("table_metric");
    if (!any) continue;
    md << "\n### " << s["experiment"].get<std::string>();
    if (s.contains("reference_extrinsic_source")) md << " (" << s["reference_extrinsic_source"].get<std::string>() << ")";
    md << "\n\n| system |";
    for (const auto& sys : systems)
      if (s["systems"].contains(sys) && s["systems"][sys].contains("extrinsic") &&
          s["systems"][sys]["extrinsic"].contains("table_metric")) {
        for (const auto& sc : s["systems"][sys]["extrinsic"]["scenarios"]) md << " " << sc.get<std::string>() << " |";
        md << "\n|---|";
        for (std::size_t k = 0; k < s["systems"][sys]["extrinsic"]["scenarios"].size(); ++k) md << "---|";
        md << "\n";
        break;
      }
    for (const auto& sys : systems) {
      if (!s["systems"].contains(sys) || !s["systems"][sys].contains("extrinsic") ||
          !s["systems"][sys]["extrinsic"].contains("table_metric"))
        continue;
      const json& js = s["systems"][sys];
      const json& ex = js["extrinsic"];
      md << "| " << sys << " |";
      for (const auto& sc : ex["scenarios"]) {
        const std::string name = sc.get<std::string>();
        md << " " << num(ex["table_metric"][name].get<double>());
        if (js.contains("reference_table_metric") && js["reference_table_metric"].contains(name))
          md << " (" << num(js["reference_table_metric"][name].get<double>(), 1) << ")";
        md << " |";
      }
      md << "\n| " << sys << " tests solved |";
      for (const auto& sc : ex["scenarios"]) md << " " << num(ex["success_rate"][sc.get<std::string>()].get<double>()) << " |";
      md << "\n";
    }
  }

  // ---- completion steps
  md << "\n## Completion steps (paper Figure 6)\n\nMedian iterations of the solved tests, by number of sub-goals, "
        "and the least-squares fit of a x^2 + b x";
  if (all.front().contains("reference_completion_fit"))
    md << " (paper, IMP, base: " << num(all.front()["reference_completion_fit"]["a"].get<double>(), 3) << " x^2 "
       << num(all.front()["reference_completion_fit"]["b"].get<double>(), 3) << " x)";
  md << ":\n\n| experiment | system | 1 | 2 | 3 | 4 | 5 | fit |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& s : all)
    for (const auto& sys : systems) {
      if (!s["systems"].contains(sys) || !s["systems"][sys].contains("extrinsic") ||
          !s["systems"][sys]["extrinsic"].contains("completion_steps"))
        continue;
      const json& ex = s["systems"][sys]["extrinsic"];
      md << "| " << s["experiment"].get<std::string>() << " | " << sys << " |";
      for (const auto& sc : ex["scenarios"]) {
        const json& c = ex["completion_steps"][sc.get<std::string>()];
        md << " " << (c["n"].get<int>() ? num(c["median"].get<double>(), 1) : std::string("-")) << " |";
      }
      const json& cs = ex["completion_steps"];
      md << " " << (cs.contains("fit") ? num(cs["fit"]["a"].get<double>(), 3) + " x^2 " + num(cs["fit"]["b"].get<double>(), 3) + " x" : "-")
         << " |\n";
    }

  md << stochasticSections(all, reference);
  md << memorySections(all);
  md << generatedSections(all, reference);

  // ---- figures
  md << "\n## Figures\n";
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    const std::string exp = all[i]["experiment"].get<std::string>();
    const fs::path target = fs::path(figures_dir) / exp;
    fs::create_directories(target);
    std::vector<std::string> pngs;
    for (const auto& f : fs::directory_iterator(dirs[i]))
      if (f.path().extension() == ".png" && f.path().filename().string().rfind("fig_", 0) == 0)
        pngs.push_back(f.path().filename().string());
    std::sort(pngs.begin(), pngs.end());
    if (pngs.empty()) continue;
    md << "\n### " << exp << "\n\n";
    for (const auto& p : pngs) {
      fs::copy_file(fs::path(dirs[i]) / p, target / p, fs::copy_options::overwrite_existing);
      const fs::path csv = fs::path(dirs[i]) / (fs::path(p).stem().string() + ".csv");
      if (fs::exists(csv)) fs::copy_file(csv, target / csv.filename(), fs::copy_options::overwrite_existing);
      md << "![" << exp << " " << p << "](" << link_prefix << "/" << exp << "/" << p << ")\n";
    }
  }
  return md.str();
}

}  // namespace afford

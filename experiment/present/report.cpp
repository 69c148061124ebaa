#include "experiment/present/report.hpp"

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "experiment/design/reference.hpp"
#include "experiment/run/outcome.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string num(double v, int digits = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// One experiment output folder, as read.
struct Folder {
  std::string dir;    // as given
  json summary;       // summary.json
  json state;         // experiment.json; null when the folder has none
  std::string label;  // unique among the report's folders: headings and figure subfolder
  std::string shown;  // the folder's path relative to the report's folder
  std::string sweep;  // a sweep's condition: the sweep's folder (its comparison figures), else ""
};

json readJson(const fs::path& file, const std::string& dir) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("report: cannot read " + file.string() + " (folder " + dir + ")");
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw std::runtime_error("report: " + file.string() + " (folder " + dir + ") is not valid JSON: " + e.what());
  }
}

// The folder's summary.json, checked for the keys every part of the report reads.
json loadSummary(const std::string& dir) {
  if (!fs::is_directory(dir)) throw std::runtime_error("report: no folder " + dir);
  const fs::path file = fs::path(dir) / "summary.json";
  if (!fs::exists(file))
    throw std::runtime_error("report: folder " + dir + " has no summary.json (is it an `afford experiment --out` folder?)");
  json s = readJson(file, dir);
  const auto need = [&](const char* key, bool ok) {
    if (!ok)
      throw std::runtime_error("report: " + file.string() + " (folder " + dir + ") has no valid \"" + key +
                               "\" (docs/results-schema.md)");
  };
  need("experiment", s.is_object() && s.contains("experiment") && s["experiment"].is_string());
  need("systems", s.contains("systems") && s["systems"].is_object());
  need("steps", s.contains("steps") && s["steps"].is_number());
  need("repetitions", s.contains("repetitions") && s["repetitions"].is_number());
  return s;
}

// experiment.json beside it (the options of the command), or null when there is none.
json loadState(const std::string& dir) {
  const fs::path file = fs::path(dir) / "experiment.json";
  if (!fs::exists(file)) return nullptr;
  json j = readJson(file, dir);
  if (!j.is_object()) throw std::runtime_error("report: " + file.string() + " (folder " + dir + ") is not a JSON object");
  return j;
}

// A path in a markdown link: what would end or break the link, percent-encoded.
std::string linkPath(const std::string& path) {
  std::string out;
  for (const char c : path) {
    if (c == ' ' || c == '(' || c == ')' || c == '<' || c == '>' || c == '[' || c == ']' || c == '#' || c == '%' ||
        c == '?' || c == '"') {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", static_cast<unsigned char>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out;
}

// `target` as seen from folder `from` ('/'-separated; absolute only if no relative path exists).
std::string relativeTo(const fs::path& target, const fs::path& from) {
  std::error_code ec;
  const fs::path rel = fs::relative(target, from, ec);
  if (ec || rel.empty()) return fs::absolute(target).lexically_normal().generic_string();
  return rel.generic_string();
}

std::string sanitize(const std::string& name) {
  std::string out;
  for (const char c : name)
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_') ? c : '-';
  while (!out.empty() && out.front() == '.') out.erase(out.begin());  // never "." or ".."
  return out;
}

std::string folderName(const std::string& dir) {
  fs::path p = fs::path(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  std::string name = p.filename().string();
  if (name.empty() || name == "." || name == "..") {
    std::error_code ec;
    name = fs::weakly_canonical(fs::absolute(dir), ec).filename().string();
  }
  return name;
}

// Does the folder's summary hold numbers of the paper (or the authors' code) beside ours?
bool hasPaperNumbers(const json& s) {
  if (s.contains("experiment_file")) return false;
  if (s.contains("reference_extrinsic_source") || s.contains("reference_completion_fit")) return true;
  for (const auto& [sys, js] : s["systems"].items())
    if (js.contains("reference_affordance_mae") || js.contains("reference_table_metric")) return true;
  return false;
}

std::string joined(const std::vector<std::string>& items, const std::string& sep = ", ") {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : sep) + i;
  return out;
}

// The seeds of a folder's runs (finished and failed), first-last when they are consecutive.
std::string seedsOf(const json& s) {
  std::set<std::int64_t> seeds;
  for (const auto& [sys, js] : s["systems"].items())
    for (const char* key : {"runs", "failed_runs"})
      if (js.contains(key))
        for (const auto& r : js[key])
          if (r.contains("seed") && r["seed"].is_number_integer()) seeds.insert(r["seed"].get<std::int64_t>());
  if (seeds.empty()) return "-";
  const std::int64_t first = *seeds.begin(), last = *seeds.rbegin();
  if (last - first + 1 == static_cast<std::int64_t>(seeds.size()))
    return first == last ? std::to_string(first) : std::to_string(first) + "-" + std::to_string(last);
  if (seeds.size() <= 6) {
    std::vector<std::string> each;
    for (const auto v : seeds) each.push_back(std::to_string(v));
    return joined(each);
  }
  return std::to_string(first) + "-" + std::to_string(last) + " (" + std::to_string(seeds.size()) + " seeds, with gaps)";
}

// The row of the header's table, and what does not fit in a table cell.
struct Ran {
  std::size_t runs = 0, failed = 0, tests = 0;
  double wall = 0;
  std::string row;
  std::vector<std::string> remarks;
};

Ran whatRan(const Folder& f, bool one_network) {
  const json& s = f.summary;
  Ran r;
  std::vector<std::string> systems;
  std::optional<std::int64_t> tests_per_scenario;
  for (const auto& [sys, js] : s["systems"].items()) {
    systems.push_back(sys);
    r.runs += js.contains("runs") ? js["runs"].size() : 0;
    r.failed += js.contains("failed_runs") ? js["failed_runs"].size() : 0;
    if (js.contains("extrinsic") && js["extrinsic"].contains("tests_per_scenario"))
      tests_per_scenario = js["extrinsic"]["tests_per_scenario"].get<std::int64_t>();
  }
  r.tests = s.value("extrinsic_tests", static_cast<std::size_t>(0));
  r.wall = s.value("wall_seconds", 0.0);
  const json design = s.value("extrinsic_design", json::object());
  const bool varied = design.contains("vary") && design["vary"].is_object() && !design["vary"].empty();
  std::string tests = std::to_string(r.tests);
  if (design.contains("generate") && design.contains("tests"))
    tests += " (" + design["tests"].dump() + " of each generated scenario per agent" + (varied ? " and condition)" : ")");
  else if (varied && design.contains("tests"))
    tests += " (" + design["tests"].dump() + " per scenario, condition and agent)";
  else if (tests_per_scenario)
    tests += " (" + std::to_string(*tests_per_scenario) + " per scenario and agent)";
  std::ostringstream row;
  row << "| " << f.label << " | `" << f.shown << "` | " << joined(systems) << " | " << s["repetitions"].dump() << " | "
      << r.runs << (r.failed ? " (" + std::to_string(r.failed) + " failed)" : std::string()) << " | " << seedsOf(s)
      << " | " << s["steps"].dump() << " | " << (r.tests || s.contains("extrinsic_design") ? tests : std::string("none"))
      << " | " << s.value("afford_version", std::string("?")) << " | "
      << (r.wall > 0 ? num(r.wall / 60.0, 1) + " min" : std::string("-")) << " |\n";
  r.row = row.str();

  // --set, the experiment file, the conditions, the network, an interruption.
  std::vector<std::string>& m = r.remarks;
  if (s.contains("description") && s["description"].is_string() && !s["description"].get<std::string>().empty())
    m.push_back(s["description"].get<std::string>());
  if (f.state.is_null() || !f.state.contains("options") || !f.state["options"].contains("settings")) {
    m.push_back("its `--set` settings are not recorded (no experiment.json)");
  } else {
    std::vector<std::string> sets;
    for (const auto& v : f.state["options"]["settings"]) sets.push_back("`--set " + v.get<std::string>() + "`");
    m.push_back(sets.empty() ? "no `--set`" : joined(sets));
  }
  if (s.contains("sweep_condition") && s["sweep_condition"].is_string())
    m.push_back("sweep condition `" + s["sweep_condition"].get<std::string>() + "`");
  if (s.contains("experiment_file") && s["experiment_file"].is_string())
    m.push_back("experiment file `" + s["experiment_file"].get<std::string>() + "`");
  if (r.tests > 0 && design.contains("scenarios") && !design.contains("generate")) {
    std::vector<std::string> names;
    for (const auto& sc : design["scenarios"]) names.push_back(sc.get<std::string>());
    m.push_back("extrinsic scenarios: " + joined(names));
  }
  if (varied) {
    std::vector<std::string> axes;
    for (const auto& [key, values] : design["vary"].items()) {
      std::vector<std::string> vs;
      for (const auto& v : values) vs.push_back(v.is_string() ? v.get<std::string>() : v.dump());
      axes.push_back("`" + key + "` = " + joined(vs));
    }
    std::size_t count = 0;
    for (const auto& [sys, js] : s["systems"].items())
      if (js.contains("extrinsic") && js["extrinsic"].contains("conditions"))
        count = std::max(count, js["extrinsic"]["conditions"].size());
    m.push_back("planner conditions: " + joined(axes, "; ") + (count ? " (" + std::to_string(count) + " conditions)" : ""));
  }
  if (s.contains("random_tables")) {
    const json& rt = s["random_tables"];
    std::vector<std::string> conditions;
    for (const auto& c : rt.value("condition_order", json::array())) {
      const std::string name = c.get<std::string>();
      std::vector<std::string> sets;
      if (rt.contains("conditions") && rt["conditions"].contains(name))
        for (const auto& v : rt["conditions"][name]) sets.push_back("`" + v.get<std::string>() + "`");
      conditions.push_back(name + " (" + (sets.empty() ? std::string("no settings") : joined(sets)) + ")");
    }
    m.push_back(rt.value("count", json(0)).dump() + " random tables from seed " + rt.value("seed", json(0)).dump() +
                "; conditions: " + joined(conditions, ", "));
  }
  if (!one_network) m.push_back("over " + s.value("network", std::string("?")));
  if (s.contains("interrupted")) {
    const json& i = s["interrupted"];
    std::ostringstream t;
    t << "**incomplete**: interrupted by " << i.value("signal", std::string("a signal")) << " in the "
      << i.value("phase", std::string("?")) << " phase, " << i.value("finished", json(0)).dump() << " of "
      << i.value("planned", json(0)).dump() << (i.value("phase", std::string()) == "extrinsic" ? " tests" : " runs")
      << " finished";
    if (i.value("extrinsic_tests_to_come", false)) t << ", the extrinsic tests not begun";
    m.push_back(t.str());
  } else if (!f.state.is_null() && f.state.value("state", std::string("finished")) != "finished") {
    m.push_back("**incomplete**: its experiment.json says \"" + f.state.value("state", std::string()) +
                "\" (still running, or stopped without a summary of it)");
  }
  return r;
}

std::string pValue(const json& p) {
  if (p.is_null()) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g", p.get<double>());
  return buf;
}

// The paper's claim for a shipped experiment (reference.yaml: <experiment>_claims).
std::string claim(const Reference& ref, const json& s) {
  if (s.contains("experiment_file")) return "";
  const std::string key = s["experiment"].get<std::string>();
  const YAML::Node c = ref.entry(key + "_claims");
  if (!c || !c["claim"]) return "";
  std::string source = ref.text(c["source"], key + "_claims.source");
  if (source.rfind("paper ", 0) == 0) source = source.substr(6);
  return "\nThe paper (" + source + "): " + ref.text(c["claim"], key + "_claims.claim") + ".\n";
}

// " (label)" after a heading named by the paper, when the label is not the experiment's name.
std::string labelled(const Folder& f) {
  return f.label == f.summary["experiment"].get<std::string>() ? "" : " (" + f.label + ")";
}

// Links to the project's documentation, relative to the report's folder.
struct Docs {
  fs::path dir;       // the project's docs/; empty: not linked
  fs::path from;      // the report's folder
  // "[name](path#anchor)", or `name` alone when the file is not there.
  std::string link(const std::string& name, const std::string& anchor = "") const {
    if (dir.empty() || !fs::exists(dir / name)) return "`docs/" + name + "`";
    return "[" + name + "](" + linkPath(relativeTo(dir / name, from)) + (anchor.empty() ? "" : "#" + anchor) + ")";
  }
  bool has(const std::string& name) const { return !dir.empty() && fs::exists(dir / name); }
};

// Section 3.2 of the paper: stochastic affordances (Figure 11) and the planner tests (Figures 12-14).
std::string stochasticSections(const std::vector<Folder>& folders, const Reference& ref) {
  const double turn_blue = ref.required("thresholds.stochastic_checks.turn_blue");
  const double move_red = ref.required("thresholds.stochastic_checks.move_red");
  std::ostringstream md;
  for (const auto& f : folders) {
    const json& s = f.summary;
    const std::string exp = s["experiment"];
    if (exp == "stochastic") {
      md << "\n## Stochastic affordances (paper 3.2.1, Table 7, Figure 11)" << labelled(f) << "\n" << claim(ref, s)
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
      md << "\n## Goal-based vs utility-based planner (paper 3.2.2, Table 8, Figure 12)" << labelled(f) << "\n"
         << claim(ref, s) << "\nMean utility gained per test (" << u["system"].get<std::string>() << " agents, scenario "
         << u["scenario"].get<std::string>() << "), with Welch's two-sided t-test:\n\n"
         << "| action budget | goal-based | utility-based | p |\n|---|---|---|---|\n";
      for (std::size_t k = 0; k < u["budgets"].size(); ++k)
        md << "| " << u["budgets"][k].get<int>() << " | " << num(u["goal_mean"][k].get<double>(), 3) << " | "
           << num(u["utility_mean"][k].get<double>(), 3) << " | " << pValue(u["p_values"][k]) << " |\n";
    }
    if (s.contains("forward_models")) {
      const json& fm = s["forward_models"];
      md << "\n## Forward models after " << s.value("after_actions", 0) << " actions (paper 3.2.3, Figure 13)"
         << labelled(f) << "\n" << claim(ref, s)
         << "\nMean utility of the utility planner, by action budget, and Welch's t-test p values:\n\n| system |";
      for (const auto& b : fm["budgets"]) md << " budget " << b.get<int>() << " |";
      md << "\n|---|";
      for (std::size_t k = 0; k < fm["budgets"].size(); ++k) md << "---|";
      md << "\n";
      for (const auto& [sys, js] : s["systems"].items()) {
        if (!js.contains("utility_mean")) continue;
        md << "| " << sys << " |";
        for (const auto& m : js["utility_mean"]) md << " " << num(m.get<double>(), 3) << " |";
        md << "\n";
      }
      for (const auto& [pair, ps] : fm["p_values"].items()) {
        md << "| p " << pair << " |";
        for (const auto& p : ps) md << " " << pValue(p) << " |";
        md << "\n";
      }
    }
    if (s.contains("search")) {
      const json& r = s["search"];
      md << "\n## Affordance-restricted search (paper 3.2.4, Figure 14)" << labelled(f) << "\n" << claim(ref, s)
         << "\nMean actions checked per sub-goal (" << r["system"].get<std::string>() << " agents): with restriction "
         << num(r["restricted_mean"].get<double>(), 3) << ", without " << num(r["unrestricted_mean"].get<double>(), 3)
         << "; Welch's t-test p = " << pValue(r["p_value"]) << ".\n";
    }
  }
  return md.str();
}

// Beyond the paper (issue 11): random tables, and the late-object tests with the memory options beside the paper's
// agent and the paper's tables.
std::string memorySections(const std::vector<Folder>& folders, const Docs& docs) {
  std::ostringstream md;
  const auto find = [&](const std::string& exp) -> const Folder* {
    for (const auto& f : folders)
      if (f.summary["experiment"] == exp) return &f;
    return nullptr;
  };
  bool header = false;
  const auto heading = [&] {
    if (!header)
      md << "\n## Beyond the paper: experience replay and revisits (issue 11)\n\nThe memory options of "
         << docs.link("model.md", "memory") << ": `predictors.replay.enabled` and `motivation.revisit.enabled`, with the "
         << "shipped values of their other keys.\n";
    header = true;
  };
  for (const auto& f : folders) {
    const json& s = f.summary;
    if (!s.contains("random_tables")) continue;
    heading();
    const json& rt = s["random_tables"];
    md << "\n### Random affordance tables (" << f.label << ")\n\n" << rt["count"].get<int>()
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
    const Folder* paper_agent = find("late" + n);
    for (const auto& mf : folders) {
      if (mf.summary["experiment"] != "late" + n + "-memory") continue;
      const json& memory = mf.summary;
      heading();
      const std::string ours = paper_agent ? paper_agent->label : "late" + n;
      md << "\n### late" << n << " with the memory options" << labelled(mf) << "\n\nTable metric per scenario: the paper's, "
         << "ours with the paper's agent (" << ours << "), ours with replay and revisits (" << mf.label << "); then the mean "
         << "absolute error of the learned affordances.\n\n| system | agent | scenario1 | scenario2 | scenario3 | "
         << "scenario4 | scenario5 | affordance error |\n|---|---|---|---|---|---|---|---|\n";
      for (const std::string sys : {"FIX", "IGN", "IMP"}) {
        if (!memory["systems"].contains(sys)) continue;
        const json& mj = memory["systems"][sys];
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
          md << " "
             << (reference || !js.contains("affordance_mae") ? std::string("-") : num(js["affordance_mae"].get<double>(), 3))
             << " |\n";
        };
        row("paper", mj, true);
        if (paper_agent && paper_agent->summary["systems"].contains(sys))
          row("ours", paper_agent->summary["systems"][sys], false);
        row("ours, memory", mj, false);
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
    const json& s = f.summary;
    if (!s.contains("extrinsic_design") || !s["extrinsic_design"].contains("generate")) continue;
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
    const std::string exp = s["experiment"];
    const json& gen = s["extrinsic_design"]["generate"];
    md << "\n### " << f.label << "\n\n" << s.value("description", std::string("")) << ". " << gen["per_point"].get<int>()
       << " scenarios per point (seed " << gen["seed"].get<std::int64_t>() << "), " << s["repetitions"]
       << " trained agent(s) per system, one test of each scenario per agent and condition.\n";
    if (!s.contains("experiment_file") && ref && ref[exp] && ref[exp]["floors"])
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

// A figure to copy: from the experiment's folder into the report's figures.
struct Copy {
  fs::path from, to;
};

struct Rendered {
  std::string markdown;
  std::vector<Copy> copies;
};

struct Where {
  fs::path out_dir;  // the report's folder
  fs::path figures;  // the figures folder
  Docs docs;
  double wall_seconds = 0;
  std::string note;
};

const std::vector<std::string> kSystems{"FIX", "IGN", "IMP"};

// What was run, read from the folders: a row per folder, and what was set.
void whatWasRun(std::ostringstream& md, const std::vector<Folder>& folders, const Where& where) {
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  std::set<std::string> networks;
  bool paper = false;
  for (const auto& f : folders) {
    networks.insert(f.summary.value("network", std::string("?")));
    paper |= hasPaperNumbers(f.summary);
  }
  md << "# Results\n\nWritten by `afford report` on " << date << " from " << folders.size()
     << " experiment folder(s) (paths relative to this file)";
  if (networks.size() == 1) md << ", over " << *networks.begin();
  md << ".";
  if (where.wall_seconds > 0) md << " Wall time given by the caller: " << num(where.wall_seconds / 60.0, 1) << " min.";
  md << " Per folder: its systems, repetitions (runs per system; for random tables, per table, system and condition), "
        "the intrinsic runs in its summary, their seeds, steps per run, the extrinsic tests, and the afford version that "
        "ran it; below, what was set.\n\n"
     << "| experiment | folder | systems | repetitions | runs | seeds | steps | extrinsic tests | afford | wall time |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  std::size_t runs = 0, failed = 0, tests = 0;
  double total = 0;
  std::ostringstream remarks;
  for (const auto& f : folders) {
    const Ran r = whatRan(f, networks.size() == 1);
    md << r.row;
    runs += r.runs, failed += r.failed, tests += r.tests, total += r.wall;
    remarks << "- **" << f.label << "**: " << joined(r.remarks, "; ") << ".\n";
  }
  md << "| all | | | | " << runs << (failed ? " (" + std::to_string(failed) + " failed)" : std::string()) << " | | | "
     << tests << " | | " << num(total / 60.0, 1) << " min |\n\n"
     << remarks.str();
  if (!where.note.empty()) md << "\n" << where.note << "\n";
  if (paper) {
    if (where.docs.has("results-discussion.md"))
      md << "\nWhere our numbers differ from the paper's, what we measured about why is in "
         << where.docs.link("results-discussion.md") << ".\n";
    md << "\nNumbers in brackets are the paper's (or, where marked, the authors' code's).\n";
  }
}

// The intrinsic phase: the mean absolute errors (paper Table 1), and base's mean table (Figure 5).
void intrinsicSection(std::ostringstream& md, const std::vector<Folder>& folders) {
  const std::vector<std::string>& systems = kSystems;
  md << "\n## Intrinsic phase: learned affordances (paper Table 1, Figure 5)\n\n"
     << "Mean absolute error of the final affordance predictions against the experiment's table, mean over runs:\n\n"
     << "| experiment | steps |";
  for (const auto& s : systems) md << " " << s << " |";
  md << "\n|---|---|---|---|---|\n";
  for (const auto& f : folders) {
    const json& s = f.summary;
    if (s.contains("random_tables")) continue;  // no one table: see the random-tables section
    md << "| " << f.label << " | " << s["steps"] << " |";
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
  for (const auto& f : folders) {
    const json& s = f.summary;
    if (s["experiment"] != "base" || s["systems"].empty()) continue;
    const json& target = s["systems"].begin().value()["target"];  // the experiment's table: the same for every system
    md << "\nBase test" << labelled(f)
       << ", mean final prediction per object and action (FIX / IGN / IMP; the paper's table in brackets):\n\n"
       << "| object | move | turn green | turn red | turn blue |\n|---|---|---|---|---|\n";
    const auto objects = s["objects"].get<std::vector<std::string>>();
    for (std::size_t i = 0; i < objects.size(); ++i) {
      md << "| " << objects[i] << " |";
      for (int a = 0; a < 4; ++a) {
        std::string cell;
        for (const auto& sys : systems)
          if (s["systems"].contains(sys))
            cell += (cell.empty() ? "" : " / ") + num(s["systems"][sys]["affordance"][i][a].get<double>());
        md << " " << cell << " (" << num(target[i][a].get<double>(), 0) << ") |";
      }
      md << "\n";
    }
  }
}

// The extrinsic phase: the table metric and the share of tests solved (paper Tables 2, 4, 5, 6).
void extrinsicSection(std::ostringstream& md, const std::vector<Folder>& folders) {
  const std::vector<std::string>& systems = kSystems;
  md << "\n## Extrinsic phase: goal-based planner (paper Tables 2, 4, 5, 6)\n\n"
     << "Table metric: the share of trained agents that solved more than 90% of their tests of the scenario. "
        "Below it, the share of all tests solved.\n";
  for (const auto& f : folders) {
    const json& s = f.summary;
    const auto measured = [&](const std::string& sys) {
      return s["systems"].contains(sys) && s["systems"][sys].contains("extrinsic") &&
             s["systems"][sys]["extrinsic"].contains("table_metric");
    };
    bool any = false;
    for (const auto& sys : systems) any |= measured(sys);
    if (!any) continue;
    md << "\n### " << f.label;
    if (s.contains("reference_extrinsic_source")) md << " (" << s["reference_extrinsic_source"].get<std::string>() << ")";
    md << "\n\n| system |";
    for (const auto& sys : systems)
      if (measured(sys)) {
        for (const auto& sc : s["systems"][sys]["extrinsic"]["scenarios"]) md << " " << sc.get<std::string>() << " |";
        md << "\n|---|";
        for (std::size_t k = 0; k < s["systems"][sys]["extrinsic"]["scenarios"].size(); ++k) md << "---|";
        md << "\n";
        break;
      }
    for (const auto& sys : systems) {
      if (!measured(sys)) continue;
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
}

// Completion steps by number of sub-goals and their fit (paper Figure 6).
void completionSection(std::ostringstream& md, const std::vector<Folder>& folders) {
  const std::vector<std::string>& systems = kSystems;
  md << "\n## Completion steps (paper Figure 6)\n\nMedian iterations of the solved tests, by number of sub-goals, "
        "and the least-squares fit of a x^2 + b x";
  for (const auto& f : folders)
    if (f.summary.contains("reference_completion_fit")) {
      const json& fit = f.summary["reference_completion_fit"];
      md << " (paper, IMP, base: " << num(fit["a"].get<double>(), 3) << " x^2 " << num(fit["b"].get<double>(), 3) << " x)";
      break;
    }
  md << ":\n\n| experiment | system | 1 | 2 | 3 | 4 | 5 | fit |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& f : folders)
    for (const auto& sys : systems) {
      const json& s = f.summary;
      if (!s["systems"].contains(sys) || !s["systems"][sys].contains("extrinsic") ||
          !s["systems"][sys]["extrinsic"].contains("completion_steps"))
        continue;
      const json& ex = s["systems"][sys]["extrinsic"];
      md << "| " << f.label << " | " << sys << " |";
      for (const auto& sc : ex["scenarios"]) {
        const json& c = ex["completion_steps"][sc.get<std::string>()];
        md << " " << (c["n"].get<int>() ? num(c["median"].get<double>(), 1) : std::string("-")) << " |";
      }
      const json& cs = ex["completion_steps"];
      md << " " << (cs.contains("fit") ? num(cs["fit"]["a"].get<double>(), 3) + " x^2 " + num(cs["fit"]["b"].get<double>(), 3) + " x" : "-")
         << " |\n";
    }
}

// The figures, each folder's into its own <figures>/<label>/ (and a sweep's comparisons, once).
void figuresSection(std::ostringstream& md, const std::vector<Folder>& folders, const Where& where, Rendered& out) {
  md << "\n## Figures\n";
  std::set<std::string> sweeps_shown;
  for (const auto& f : folders) {
    if (!f.sweep.empty() && sweeps_shown.insert(f.sweep).second) {  // the conditions side by side, once per sweep
      const std::string label = f.summary["experiment"].get<std::string>() + "-sweep-" + folderName(f.sweep);
      bool heading = false;
      for (const char* name : {"fig_sweep_mae", "fig_sweep_success"}) {
        const fs::path png = fs::path(f.sweep) / (std::string(name) + ".png");
        if (!fs::exists(png)) continue;
        if (!heading) md << "\n### " << label << ": the sweep's conditions compared\n\n";
        heading = true;
        const fs::path target = where.figures / sanitize(label);
        out.copies.push_back({png, target / png.filename()});
        const fs::path csv = fs::path(f.sweep) / (std::string(name) + ".csv");
        if (fs::exists(csv)) out.copies.push_back({csv, target / csv.filename()});
        md << "![" << label << " " << png.filename().string() << "](" << linkPath(relativeTo(target / png.filename(), where.out_dir)) << ")\n";
      }
    }
    std::vector<std::string> pngs;
    for (const auto& e : fs::directory_iterator(f.dir))
      if (e.path().extension() == ".png" && e.path().filename().string().rfind("fig_", 0) == 0)
        pngs.push_back(e.path().filename().string());
    std::sort(pngs.begin(), pngs.end());
    if (pngs.empty()) continue;
    md << "\n### " << f.label << "\n\n";
    const fs::path target = where.figures / f.label;
    for (const auto& p : pngs) {
      out.copies.push_back({fs::path(f.dir) / p, target / p});
      const fs::path csv = fs::path(f.dir) / (fs::path(p).stem().string() + ".csv");
      if (fs::exists(csv)) out.copies.push_back({csv, target / csv.filename()});
      md << "![" << f.label << " " << p << "](" << linkPath(relativeTo(target / p, where.out_dir)) << ")\n";
    }
  }
}

// The whole report of `folders`; reads the folders, writes nothing.
Rendered render(const std::vector<Folder>& folders, const Reference& reference, const Where& where) {
  Rendered out;
  std::ostringstream md;
  whatWasRun(md, folders, where);
  intrinsicSection(md, folders);
  extrinsicSection(md, folders);
  completionSection(md, folders);
  md << stochasticSections(folders, reference);
  md << memorySections(folders, where.docs);
  md << generatedSections(folders, reference, where.docs);
  figuresSection(md, folders, where, out);
  out.markdown = md.str();
  return out;
}

}  // namespace

std::string defaultFiguresDir(const std::string& out) {
  fs::path p(out);
  fs::path figures = p.parent_path() / p.stem();
  if (figures == p) figures += "-figures";  // `--out report`: not the file itself
  return figures.string();
}

std::vector<std::string> folderLabels(const std::vector<std::string>& experiments, const std::vector<std::string>& dirs) {
  std::map<std::string, int> shared;
  for (const auto& e : experiments) ++shared[sanitize(e)];
  std::vector<std::string> labels;
  std::set<std::string> taken;
  for (std::size_t i = 0; i < experiments.size(); ++i) {
    std::string label = sanitize(experiments[i]);
    if (label.empty()) label = "experiment";
    if (shared[sanitize(experiments[i])] > 1) {
      const std::string name = sanitize(folderName(dirs[i]));
      if (!name.empty() && name != label) label += "-" + name;
    }
    std::string unique = label;
    for (int k = 2; taken.count(unique); ++k) unique = label + "-" + std::to_string(k);
    taken.insert(unique);
    labels.push_back(unique);
  }
  return labels;
}

ReportWritten writeReport(const ReportRequest& request) {
  if (request.dirs.empty()) throw std::runtime_error("report: no experiment folder given");
  const Reference reference(request.config_dir);  // before anything is written: a broken file fails the report
  std::vector<Folder> folders;
  std::vector<std::string> dirs;  // per folder (a sweep's conditions one by one)
  for (const auto& d : request.dirs) {
    const json top = fs::exists(fs::path(d) / "summary.json") ? readJson(fs::path(d) / "summary.json", d) : json();
    if (!top.is_object() || !top.contains("sweep")) {
      folders.push_back({d, loadSummary(d), loadState(d), "", "", ""});
      dirs.push_back(d);
      continue;
    }
    // A sweep: each condition's folder is an experiment folder of its own, its settings those of the
    // sweep's command with the condition's.
    const json state = loadState(d);
    if (!top["sweep"].contains("conditions") || !top["sweep"]["conditions"].is_array())
      throw std::runtime_error("report: " + (fs::path(d) / "summary.json").string() + " (folder " + d +
                               ") has a sweep without conditions (docs/results-schema.md)");
    for (const auto& c : top["sweep"]["conditions"]) {
      const std::string dir = (fs::path(d) / c.at("folder").get<std::string>()).string();
      json cs = state;
      if (cs.is_object() && cs.contains("options")) {
        json sets = top.value("settings", json::array());
        for (const auto& v : c.at("settings")) sets.push_back(v);
        cs["options"]["settings"] = sets;
      }
      folders.push_back({dir, loadSummary(dir), cs, "", "", d});
      dirs.push_back(dir);
    }
  }

  const fs::path out = fs::absolute(request.out).lexically_normal();
  if (out.filename().empty()) throw std::runtime_error("report: --out " + request.out + " names a folder, not a file");
  Where where;
  where.out_dir = out.parent_path();
  where.figures =
      fs::absolute(request.figures.empty() ? defaultFiguresDir(request.out) : request.figures).lexically_normal();
  where.docs = {request.docs_dir.empty() ? fs::path() : fs::absolute(request.docs_dir), where.out_dir};
  where.wall_seconds = request.wall_seconds;
  where.note = request.note;

  std::vector<std::string> experiments;
  for (const auto& f : folders) experiments.push_back(f.summary["experiment"].get<std::string>());
  const auto labels = folderLabels(experiments, dirs);
  for (std::size_t i = 0; i < folders.size(); ++i) {
    folders[i].label = labels[i];
    folders[i].shown = relativeTo(fs::absolute(folders[i].dir).lexically_normal(), where.out_dir);
  }
  // Each folder alone first, so that a summary of another shape is an error naming its folder.
  for (const auto& f : folders) {
    try {
      render({f}, reference, where);
    } catch (const json::exception& e) {
      throw std::runtime_error("report: " + (fs::path(f.dir) / "summary.json").string() + " (folder " + f.dir +
                               ") does not have the shape of docs/results-schema.md: " + e.what());
    }
  }
  Rendered rendered;
  try {
    rendered = render(folders, reference, where);
  } catch (const json::exception& e) {
    throw std::runtime_error(std::string("report: the summaries do not fit together: ") + e.what());
  }

  // Everything is read: now write.
  fs::create_directories(where.out_dir);
  for (const auto& c : rendered.copies) {
    fs::create_directories(c.to.parent_path());
    fs::copy_file(c.from, c.to, fs::copy_options::overwrite_existing);
  }
  writeWhole(out, rendered.markdown);  // beside it, then renamed over it
  return {out.string(), where.figures.string(), labels};
}

}  // namespace afford

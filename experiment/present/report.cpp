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
#include "experiment/present/present.hpp"
#include "experiment/run/outcome.hpp"
#include "experiment/schema/summary.hpp"

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
  Summary summary;    // summary.json
  json state;         // experiment.json; null when the folder has none
  std::string label;  // unique among the report's folders: headings and figure subfolder
  std::string shown;  // the folder's path relative to the report's folder
  std::string sweep;  // a sweep's condition: the sweep's folder (its comparison figures), else ""
};

// experiment.json: a regular file no larger than a summary may be (opening a FIFO would wait for a writer).
json readJson(const fs::path& file, const std::string& dir) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec) || fs::file_size(file, ec) > kMaxSummaryBytes || ec)
    throw std::runtime_error("report: " + file.string() + " (folder " + dir + ") is not a regular file of at most " +
                             std::to_string(kMaxSummaryBytes) + " bytes");
  std::ifstream in(file);
  if (!in) throw std::runtime_error("report: cannot read " + file.string() + " (folder " + dir + ")");
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw std::runtime_error("report: " + file.string() + " (folder " + dir + ") is not valid JSON: " + e.what());
  }
}

// The folder's summary.json, read through its structure: one of another shape is an error naming the folder.
Summary loadSummary(const std::string& dir) {
  if (!fs::is_directory(dir)) throw std::runtime_error("report: no folder " + dir);
  try {
    return readSummary(dir);
  } catch (const SummaryError& e) {
    throw std::runtime_error(std::string("report: ") + e.what() + " (docs/results-schema.md)");
  }
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
bool hasPaperNumbers(const Summary& s) {
  if (s.experiment_file) return false;
  if (s.reference_extrinsic_source || s.reference_completion_fit) return true;
  for (const auto& [sys, js] : s.systems)
    if (js.reference_affordance_mae || js.reference_table_metric) return true;
  return false;
}

std::string joined(const std::vector<std::string>& items, const std::string& sep = ", ") {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : sep) + i;
  return out;
}

// The seeds of a folder's runs (finished and failed), first-last when they are consecutive.
std::string seedsOf(const Summary& s) {
  std::set<std::int64_t> seeds;
  for (const auto& [sys, js] : s.systems) {
    for (const RunEntry& r : js.runs) seeds.insert(r.seed);
    for (const FailedRun& r : js.failed_runs.value_or(std::vector<FailedRun>{})) seeds.insert(r.seed);
  }
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
  const Summary& s = f.summary;
  Ran r;
  std::vector<std::string> systems;
  std::optional<std::int64_t> tests_per_scenario;
  for (const auto& [sys, js] : s.systems) {
    systems.push_back(sys);
    r.runs += js.runs.size();
    r.failed += js.failed_runs ? js.failed_runs->size() : 0;
    if (js.extrinsic) tests_per_scenario = js.extrinsic->tests_per_scenario;
  }
  r.tests = static_cast<std::size_t>(s.extrinsic_tests);
  r.wall = s.wall_seconds;
  const DesignSummary design = s.extrinsic_design.value_or(DesignSummary{});
  const bool varied = !design.vary.empty();
  std::string tests = std::to_string(r.tests);
  if (s.extrinsic_design && design.generate)
    tests += " (" + std::to_string(design.tests) + " of each generated scenario per agent" + (varied ? " and condition)" : ")");
  else if (varied)
    tests += " (" + std::to_string(design.tests) + " per scenario, condition and agent)";
  else if (tests_per_scenario)
    tests += " (" + std::to_string(*tests_per_scenario) + " per scenario and agent)";
  std::ostringstream row;
  row << "| " << f.label << " | `" << f.shown << "` | " << joined(systems) << " | " << s.repetitions << " | " << r.runs
      << (r.failed ? " (" + std::to_string(r.failed) + " failed)" : std::string()) << " | " << seedsOf(s) << " | "
      << s.steps << " | " << (r.tests || s.extrinsic_design ? tests : std::string("none")) << " | " << s.afford_version
      << " | " << (r.wall > 0 ? num(r.wall / 60.0, 1) + " min" : std::string("-")) << " |\n";
  r.row = row.str();

  // --set, the experiment file, the conditions, the network, an interruption.
  std::vector<std::string>& m = r.remarks;
  if (!s.description.empty()) m.push_back(s.description);
  if (f.state.is_null() || !f.state.contains("options") || !f.state["options"].contains("settings")) {
    m.push_back("its `--set` settings are not recorded (no experiment.json)");
  } else {
    std::vector<std::string> sets;
    for (const auto& v : f.state["options"]["settings"])
      if (v.is_string()) sets.push_back("`--set " + v.get<std::string>() + "`");
    m.push_back(sets.empty() ? "no `--set`" : joined(sets));
  }
  if (s.sweep_condition) m.push_back("sweep condition `" + *s.sweep_condition + "`");
  if (s.experiment_file) m.push_back("experiment file `" + *s.experiment_file + "`");
  if (r.tests > 0 && s.extrinsic_design && !design.generate) m.push_back("extrinsic scenarios: " + joined(design.scenarios));
  if (varied) {
    std::vector<std::string> axes;
    for (const auto& [key, values] : design.vary) axes.push_back("`" + key + "` = " + joined(values));
    std::size_t count = 0;
    for (const auto& [sys, js] : s.systems)
      if (js.extrinsic && js.extrinsic->conditions) count = std::max(count, js.extrinsic->conditions->size());
    m.push_back("planner conditions: " + joined(axes, "; ") + (count ? " (" + std::to_string(count) + " conditions)" : ""));
  }
  if (s.random_tables) {
    const RandomTables& rt = *s.random_tables;
    std::vector<std::string> conditions;
    for (const auto& name : rt.condition_order) {
      std::vector<std::string> sets;
      if (const auto c = rt.conditions.find(name); c != rt.conditions.end())
        for (const auto& v : c->second) sets.push_back("`" + v + "`");
      conditions.push_back(name + " (" + (sets.empty() ? std::string("no settings") : joined(sets)) + ")");
    }
    m.push_back(std::to_string(rt.count) + " random tables from seed " + std::to_string(rt.seed) +
                "; conditions: " + joined(conditions, ", "));
  }
  if (!one_network) m.push_back("over " + s.network);
  if (s.interrupted) {
    const Interruption& i = *s.interrupted;
    std::ostringstream t;
    t << "**incomplete**: interrupted by " << i.signal << " in the " << i.phase << " phase, " << i.finished << " of "
      << i.planned << (i.phase == "extrinsic" ? " tests" : " runs") << " finished";
    if (i.extrinsic_tests_to_come) t << ", the extrinsic tests not begun";
    m.push_back(t.str());
  } else if (!f.state.is_null() && f.state.value("state", std::string("finished")) != "finished") {
    m.push_back("**incomplete**: its experiment.json says \"" + f.state.value("state", std::string()) +
                "\" (still running, or stopped without a summary of it)");
  }
  return r;
}

std::string pValue(const Nullable<double>& p) {
  if (!p) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g", *p);
  return buf;
}

// The paper's claim for a shipped experiment (reference.yaml: <experiment>_claims).
std::string claim(const Reference& ref, const Summary& s) {
  if (s.experiment_file) return "";
  const std::string& key = s.experiment;
  const YAML::Node c = ref.entry(key + "_claims");
  if (!c || !c["claim"]) return "";
  std::string source = ref.text(c["source"], key + "_claims.source");
  if (source.rfind("paper ", 0) == 0) source = source.substr(6);
  return "\nThe paper (" + source + "): " + ref.text(c["claim"], key + "_claims.claim") + ".\n";
}

// " (label)" after a heading named by the paper, when the label is not the experiment's name.
std::string labelled(const Folder& f) {
  return f.label == f.summary.experiment ? "" : " (" + f.label + ")";
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

// An experiment with the authors' eye (issue 28): NAME-true-centre, shown
// beside NAME in its own section (authorsEyeSections).
const std::string kAuthorsEyeSuffix = "-true-centre";
bool withTheAuthorsEye(const std::string& experiment) {
  return experiment.size() > kAuthorsEyeSuffix.size() &&
         experiment.compare(experiment.size() - kAuthorsEyeSuffix.size(), kAuthorsEyeSuffix.size(), kAuthorsEyeSuffix) == 0;
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
    networks.insert(f.summary.network);
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
     // Experiments run side by side (one queue) overlap: then the caller's wall time is the whole's.
     << tests << " | | " << num((where.wall_seconds > 0 ? where.wall_seconds : total) / 60.0, 1) << " min |\n\n"
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
    const Summary& s = f.summary;
    if (s.random_tables) continue;  // no one table: see the random-tables section
    md << "| " << f.label << " | " << s.steps << " |";
    for (const auto& sys : systems) {
      const auto js = s.systems.find(sys);
      if (js == s.systems.end()) {
        md << " |";
        continue;
      }
      md << " " << num(js->second.affordance_mae.value_or(0.0), 3);
      if (js->second.reference_affordance_mae)
        md << " (" << num(*js->second.reference_affordance_mae, 3) << " authors' code)";
      md << " |";
    }
    md << "\n";
  }
  for (const auto& f : folders) {
    const Summary& s = f.summary;
    if (s.experiment != "base" || s.systems.empty() || !s.systems.begin()->second.target) continue;
    const SummaryTable& target = *s.systems.begin()->second.target;  // the experiment's table: the same for every system
    md << "\nBase test" << labelled(f)
       << ", mean final prediction per object and action (FIX / IGN / IMP; the paper's table in brackets):\n\n"
       << "| object | move | turn green | turn red | turn blue |\n|---|---|---|---|---|\n";
    for (std::size_t i = 0; i < s.objects.size() && i < target.size(); ++i) {
      md << "| " << s.objects[i] << " |";
      for (std::size_t a = 0; a < 4 && a < target[i].size(); ++a) {
        std::string cell;
        for (const auto& sys : systems)
          if (const auto js = s.systems.find(sys); js != s.systems.end() && js->second.affordance)
            cell += (cell.empty() ? "" : " / ") + num(js->second.affordance->at(i).at(a));
        md << " " << cell << " (" << num(target[i][a], 0) << ") |";
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
    const Summary& s = f.summary;
    const auto measured = [&](const std::string& sys) -> const SystemExtrinsic* {
      const auto js = s.systems.find(sys);
      if (js == s.systems.end() || !js->second.extrinsic || !js->second.extrinsic->table_metric ||
          !js->second.extrinsic->success_rate)
        return nullptr;
      return &*js->second.extrinsic;
    };
    bool any = false;
    for (const auto& sys : systems) any |= measured(sys) != nullptr;
    if (!any) continue;
    md << "\n### " << f.label;
    if (s.reference_extrinsic_source) md << " (" << *s.reference_extrinsic_source << ")";
    md << "\n\n| system |";
    for (const auto& sys : systems)
      if (const SystemExtrinsic* ex = measured(sys)) {
        for (const auto& sc : ex->scenarios) md << " " << sc << " |";
        md << "\n|---|";
        for (std::size_t k = 0; k < ex->scenarios.size(); ++k) md << "---|";
        md << "\n";
        break;
      }
    const auto cell = [](const std::map<std::string, double>& m, const std::string& k) {
      const auto it = m.find(k);
      return it == m.end() ? std::string("-") : num(it->second);
    };
    for (const auto& sys : systems) {
      const SystemExtrinsic* ex = measured(sys);
      if (!ex) continue;
      const SystemSummary& js = s.systems.at(sys);
      md << "| " << sys << " |";
      for (const auto& name : ex->scenarios) {
        md << " " << cell(*ex->table_metric, name);
        if (js.reference_table_metric && js.reference_table_metric->count(name))
          md << " (" << num(js.reference_table_metric->at(name), 1) << ")";
        md << " |";
      }
      md << "\n| " << sys << " tests solved |";
      for (const auto& name : ex->scenarios) md << " " << cell(*ex->success_rate, name) << " |";
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

// The figures, each folder's into its own <figures>/<label>/ (and a sweep's comparisons, once).
void figuresSection(std::ostringstream& md, const std::vector<Folder>& folders, const Where& where, Rendered& out) {
  md << "\n## Figures\n";
  std::set<std::string> sweeps_shown;
  for (const auto& f : folders) {
    if (!f.sweep.empty() && sweeps_shown.insert(f.sweep).second) {  // the conditions side by side, once per sweep
      const std::string label = f.summary.experiment + "-sweep-" + folderName(f.sweep);
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
  md << authorsEyeSections(folders, where.docs);
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
    const fs::path file = fs::path(d) / "summary.json";
    json top;
    try {
      if (fs::exists(file)) top = readSummaryJson(d);
    } catch (const SummaryError& e) {
      throw std::runtime_error(std::string("report: ") + e.what() + " (folder " + d + ")");
    }
    if (!isSweepSummary(top)) {
      folders.push_back({d, loadSummary(d), loadState(d), "", "", ""});
      dirs.push_back(d);
      continue;
    }
    // A sweep: each condition's folder is an experiment folder of its own, its settings those of the
    // sweep's command with the condition's.
    SweepSummary sweep;
    try {
      sweep = sweepSummaryFromJson(top, file.string());
    } catch (const SummaryError& e) {
      throw std::runtime_error(std::string("report: ") + e.what() + " (docs/results-schema.md)");
    }
    const json state = loadState(d);
    for (const SweepEntry& c : sweep.sweep.conditions) {
      const std::string dir = (fs::path(d) / c.folder).string();
      json cs = state;
      if (cs.is_object() && cs.contains("options")) {
        std::vector<std::string> sets = sweep.settings;
        sets.insert(sets.end(), c.settings.begin(), c.settings.end());
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
  for (const auto& f : folders) experiments.push_back(f.summary.experiment);
  const auto labels = folderLabels(experiments, dirs);
  for (std::size_t i = 0; i < folders.size(); ++i) {
    folders[i].label = labels[i];
    folders[i].shown = relativeTo(fs::absolute(folders[i].dir).lexically_normal(), where.out_dir);
  }
  // Each folder alone first, so that a summary that does not fit is an error naming its folder.
  for (const auto& f : folders) {
    try {
      render({f}, reference, where);
    } catch (const std::out_of_range& e) {
      throw std::runtime_error("report: " + (fs::path(f.dir) / "summary.json").string() + " (folder " + f.dir +
                               ") does not fit together (a table or condition missing where another names it): " +
                               e.what());
    } catch (const json::exception& e) {
      throw std::runtime_error("report: " + (fs::path(f.dir) / "experiment.json").string() + " (folder " + f.dir +
                               ") does not have the shape `afford experiment` writes: " + e.what());
    }
  }
  const Rendered rendered = render(folders, reference, where);

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

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
#include "experiment/present/report_parts.hpp"
#include "experiment/run/outcome.hpp"
#include "experiment/schema/summary.hpp"
#include "experiment/stored/state_file.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace report {

std::string num(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
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

// experiment.json, if the folder has one (read strictly, as --resume reads it).
std::optional<ExperimentState> loadState(const std::string& dir) {
  std::error_code ec;
  if (!fs::exists(statePath(dir), ec)) return std::nullopt;
  try {
    return readState(dir);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("report: ") + e.what() + " (folder " + dir + ")");
  }
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
  if (!f.state) {
    m.push_back("its `--set` settings are not recorded (no experiment.json)");
  } else {
    std::vector<std::string> sets;
    for (const std::string& v : f.state->options.plan.settings) sets.push_back("`--set " + v + "`");
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
  } else if (f.state && f.state->state != "finished") {
    m.push_back("**incomplete**: its experiment.json says \"" + f.state->state +
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



}  // namespace report

using namespace report;

namespace {
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

// The systems a folder ran: the paper's in their order, then any other (GOALS, novelty) by name.
std::vector<std::string> systemsOf(const Summary& s) {
  std::vector<std::string> out;
  for (const auto& sys : kPaperSystems)
    if (s.systems.count(sys)) out.push_back(sys);
  for (const auto& [sys, js] : s.systems)
    if (std::find(kPaperSystems.begin(), kPaperSystems.end(), sys) == kPaperSystems.end()) out.push_back(sys);
  return out;
}

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
  const std::vector<std::string> systems = systemsOf(folders);
  md << "\n## Intrinsic phase: learned affordances (paper Table 1, Figure 5)\n\n"
     << "Mean absolute error of the final affordance predictions against the experiment's table, mean over runs:\n\n"
     << "| experiment | steps |";
  for (const auto& s : systems) md << " " << s << " |";
  md << "\n|---|---|";
  for (std::size_t i = 0; i < systems.size(); ++i) md << "---|";
  md << "\n";
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
       << ", mean final prediction per object and action (" << [&] {
            std::string names;
            for (const auto& sys : systemsOf(s)) names += (names.empty() ? "" : " / ") + sys;
            return names;
          }() << "; the paper's table in brackets):\n\n"
       << "| object |" << [&] {
            std::string head;
            for (const std::string& a : s.actions) head += " " + a + " |";
            return head;
          }() << "\n|---|---|---|---|---|\n";
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
  md << "\n## Extrinsic phase: goal-based planner (paper Tables 2, 4, 5, 6)\n\n"
     << "Table metric: the share of trained agents that solved more than 90% of their tests of the scenario. "
        "Below it, the share of all tests solved.\n";
  for (const auto& f : folders) {
    const Summary& s = f.summary;
    const std::vector<std::string> systems = systemsOf(s);
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
  md << goalsSections(folders, where.docs);
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
    const std::optional<ExperimentState> state = loadState(d);
    for (const SweepEntry& c : sweep.sweep.conditions) {
      const std::string dir = (fs::path(d) / c.folder).string();
      std::optional<ExperimentState> cs = state;
      if (cs) {
        std::vector<std::string> sets = sweep.settings;
        sets.insert(sets.end(), c.settings.begin(), c.settings.end());
        cs->options.plan.settings = sets;
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

// afford report (experiment/present/report.cpp): a report of any set of
// experiment folders, here two folders of the base test written by hand
// (summary.json and experiment.json as docs/results-schema.md describes them,
// a figure and its CSV each), reported into a nested folder.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "experiment/present/present.hpp"
#include "experiment/present/report.hpp"
#include "experiment/stored/state_file.hpp"
#include "experiment/schema/summary.hpp"
#include "experiment/present/plots_parts.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kConfigDir = std::string(AFFORD_SOURCE_DIR) + "/config";
const std::string kDocsDir = std::string(AFFORD_SOURCE_DIR) + "/docs";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void spit(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

// What one hand-made experiment folder ran.
struct Made {
  std::string version;
  std::vector<std::string> systems;
  int reps = 2;
  std::int64_t first_seed = 1;
  std::int64_t steps = 300;
  int tests_per_scenario = 1;  // of scenario1, per trained agent
  std::vector<std::string> settings;
  std::string experiment_file;  // --config FILE: no reference numbers
  bool interrupted = false;
  std::string experiment = "base";
  double table_metric = 1.0;  // of scenario1, every system
};

Made made(const std::string& version, std::vector<std::string> systems, int reps, std::int64_t first_seed,
          std::int64_t steps, int tests_per_scenario, std::vector<std::string> settings = {}) {
  Made m;
  m.version = version;
  m.systems = std::move(systems);
  m.reps = reps;
  m.first_seed = first_seed;
  m.steps = steps;
  m.tests_per_scenario = tests_per_scenario;
  m.settings = std::move(settings);
  return m;
}

// summary.json of an `afford experiment base` with those counts, as afford writes it (experiment/schema/summary.hpp).
json summaryOf(const Made& m) {
  const SummaryTable table = {{1, 1, 0, 1}, {1, 0, 1, 1}, {1, 1, 1, 0}, {1, 1, 0, 1}, {1, 0, 1, 1},
                              {1, 1, 1, 0}, {1, 1, 0, 1}, {1, 0, 1, 1}, {1, 1, 1, 0}};
  Summary s;
  s.experiment = m.experiment;
  s.description = "base test, deterministic affordances (paper Table 1)";
  s.steps = m.steps;
  s.repetitions = m.reps;
  s.seed = m.first_seed;
  s.transport = "memq";
  s.network = "in-process memq://";
  s.afford_version = m.version;
  s.objects = {"red square",   "green square",  "blue square",     "red circle",    "green circle",
               "blue circle",  "red rectangle", "green rectangle", "blue rectangle"};
  s.actions = {"move", "turn green", "turn red", "turn blue"};
  s.wall_seconds = 90.0;
  s.extrinsic_tests = m.reps * m.tests_per_scenario * static_cast<int>(m.systems.size());
  DesignSummary& design = s.extrinsic_design.emplace();
  design.scenarios = {"scenario1"};
  design.tests = m.tests_per_scenario;
  if (m.experiment_file.empty()) {
    s.reference_source = "authors' code";
    s.reference_extrinsic_source = "paper Table 2 (base test)";
    s.reference_completion_fit = Fit{1.364, -0.808};
  } else {
    s.experiment_file = m.experiment_file;
  }
  for (const auto& sys : m.systems) {
    SystemSummary& js = s.systems[sys];
    js.target = js.affordance = table;
    js.affordance_mae = 0.04;
    if (m.experiment_file.empty()) {
      js.reference_affordance_mae = 0.026;
      js.reference_table_metric = std::map<std::string, double>{{"scenario1", 1.0}};
    }
    for (int r = 0; r < m.reps; ++r) {
      RunEntry run;
      run.seed = m.first_seed + r;
      run.run_id = "t-base-" + sys + "-s" + std::to_string(run.seed);
      run.log_dir = Nullable<std::string>();
      run.affordance = table;
      run.affordance_mae = 0.04;
      run.weights_checksum = "0123456789abcdef";
      js.runs.push_back(run);
    }
    SystemExtrinsic& ex = js.extrinsic.emplace();
    ex.scenarios = {"scenario1"};
    ex.tests_per_scenario = m.tests_per_scenario;
    ex.table_metric = std::map<std::string, double>{{"scenario1", m.table_metric}};
    ex.table_metric_solved_share = 0.9;
    ex.success_rate = std::map<std::string, double>{{"scenario1", 1.0}};
    ex.completion_steps.emplace().scenarios["scenario1"] = ScenarioSteps{2, 1, 1, 1, 1, 1, 1, 1.0};
    ex.actions_checked_per_sub_goal = std::map<std::string, double>{{"scenario1", 2.0}};
  }
  if (m.interrupted)
    s.interrupted = Interruption{"SIGINT", "intrinsic", m.reps - 1, m.reps, {}, {}, true,
                                 "afford experiment --resume --out x", "/"};
  return toJson(s);
}

// An experiment folder: summary.json, experiment.json (its options), a figure and its CSV, whose bytes name the folder.
std::string makeFolder(const fs::path& dir, const Made& m) {
  spit(dir / "summary.json", summaryOf(m).dump(2));
  ExperimentState state;  // as the experiment writes it
  state.experiment = m.experiment;
  state.cwd = "/";
  state.state = "finished";
  state.options.plan.experiment = m.experiment;
  state.options.plan.systems = m.systems;
  state.options.plan.reps = m.reps;
  state.options.plan.seed = m.first_seed;
  state.options.plan.settings = m.settings;
  state.options.plan.extrinsic_reps = m.tests_per_scenario;
  writeState(dir, state);
  spit(dir / "fig_affordances.png", "PNG of " + dir.string());
  spit(dir / "fig_affordances.csv", "csv of " + dir.string());
  return dir.string();
}

// Two folders of the base test, with different counts, seeds, versions and --set.
struct TwoBaseFolders : ::testing::Test {
  fs::path root = test::tempDir("report");
  std::string a = makeFolder(root / "runs" / "a", made("0.1.0+aaaaaaa", {"IMP"}, 2, 1, 300, 1));
  std::string b = makeFolder(root / "runs" / "b", made("0.1.0+bbbbbbb", {"FIX", "IMP"}, 3, 5, 400, 2, {"motivation.leak=0.2"}));
  fs::path out = root / "reports" / "deep" / "mine.md";

  ReportWritten report() const {
    ReportRequest r;
    r.dirs = {a, b};
    r.out = out.string();
    r.config_dir = kConfigDir;
    r.docs_dir = kDocsDir;
    return writeReport(r);
  }
};

// The table row of the folder labelled `label`.
std::string rowOf(const std::string& md, const std::string& label) {
  const auto at = md.find("\n| " + label + " |");
  if (at == std::string::npos) return "";
  return md.substr(at + 1, md.find('\n', at + 1) - at - 1);
}

TEST_F(TwoBaseFolders, TheHeaderSaysWhatEachFolderRan) {
  const ReportWritten w = report();
  const std::string md = slurp(out);
  const std::string ra = rowOf(md, w.labels[0]), rb = rowOf(md, w.labels[1]);
  // experiment | folder | systems | repetitions | runs | seeds | steps | extrinsic tests | afford | wall time
  EXPECT_EQ(ra, "| base-a | `../../runs/a` | IMP | 2 | 2 | 1-2 | 300 | 2 (1 per scenario and agent) | 0.1.0+aaaaaaa | 1.5 min |");
  EXPECT_EQ(rb, "| base-b | `../../runs/b` | FIX, IMP | 3 | 6 | 5-7 | 400 | 12 (2 per scenario and agent) | 0.1.0+bbbbbbb | 1.5 min |");
  EXPECT_NE(md.find("| all | | | | 8 | | | 14 | | 3.0 min |"), std::string::npos) << md;
  EXPECT_NE(md.find("- **base-a**: base test, deterministic affordances (paper Table 1); no `--set`; extrinsic scenarios: scenario1.\n"),
            std::string::npos) << md;
  EXPECT_NE(md.find("- **base-b**: base test, deterministic affordances (paper Table 1); `--set motivation.leak=0.2`;"),
            std::string::npos) << md;
  // Nothing said that these folders do not say.
  EXPECT_EQ(md.find("reproduce.sh"), std::string::npos) << md;
  EXPECT_EQ(md.find("the paper's counts"), std::string::npos) << md;
  EXPECT_EQ(md.find("incomplete"), std::string::npos) << md;
}

TEST_F(TwoBaseFolders, FoldersOfOneExperimentHaveTheirOwnHeadingsAndFigureFolders) {
  const ReportWritten w = report();
  ASSERT_EQ(w.labels, (std::vector<std::string>{"base-a", "base-b"}));
  const std::string md = slurp(out);
  for (const auto& label : w.labels) {
    EXPECT_NE(md.find("\n### " + label + " ("), std::string::npos) << label << "\n" << md;  // the extrinsic table
    EXPECT_NE(md.find("\n### " + label + "\n"), std::string::npos) << label << "\n" << md;  // its figures
  }
  EXPECT_EQ(fs::path(w.figures), out.parent_path() / "mine");  // beside the report, named after it
  for (const auto& [label, dir] : {std::pair{w.labels[0], a}, std::pair{w.labels[1], b}}) {
    const fs::path figs = fs::path(w.figures) / label;
    EXPECT_EQ(slurp(figs / "fig_affordances.png"), "PNG of " + dir) << label;
    EXPECT_EQ(slurp(figs / "fig_affordances.csv"), "csv of " + dir) << label;
  }
}

TEST_F(TwoBaseFolders, EveryLinkIsRelativeAndResolvesFromTheReportsFolder) {
  report();
  const std::string md = slurp(out);
  const std::regex link(R"(\]\(([^)\s]+)\))");
  int links = 0, figures = 0;
  bool discussion = false;
  for (auto it = std::sregex_iterator(md.begin(), md.end(), link); it != std::sregex_iterator(); ++it) {
    std::string target = (*it)[1].str();
    target = target.substr(0, target.find('#'));
    ++links;
    EXPECT_FALSE(fs::path(target).is_absolute()) << target;
    EXPECT_TRUE(fs::is_regular_file(out.parent_path() / target)) << target;
    figures += fs::path(target).extension() == ".png";
    discussion |= fs::path(target).filename() == "results-discussion.md";
  }
  EXPECT_EQ(figures, 2);
  EXPECT_TRUE(discussion) << md;  // the paper's numbers are beside ours
  EXPECT_GE(links, 3);
}

TEST_F(TwoBaseFolders, AFolderWithoutSummaryIsAnErrorNamingItAndNothingIsWritten) {
  const fs::path missing = root / "runs" / "not-an-experiment";
  fs::create_directories(missing);
  ReportRequest r;
  r.dirs = {a, missing.string(), b};
  r.out = out.string();
  r.config_dir = kConfigDir;
  try {
    writeReport(r);
    FAIL() << "a folder without summary.json was reported";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("summary.json"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(root / "reports"));  // neither the report, nor its folder, nor a figure
}

TEST_F(TwoBaseFolders, ABrokenSummaryIsAnErrorNamingItsFolderAndTheJsonError) {
  spit(fs::path(b) / "summary.json", "{\"experiment\": \"base\",");
  ReportRequest r;
  r.dirs = {a, b};
  r.out = out.string();
  r.config_dir = kConfigDir;
  try {
    writeReport(r);
    FAIL() << "a broken summary.json was reported";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("folder " + b), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("parse error"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(root / "reports"));
}

// An experiment with the authors' eye (issue 28) is shown beside the same
// experiment with ours and the paper's table, in its own section.
TEST(Report, TheAuthorsEyeIsShownBesideOursAndThePapers) {
  const fs::path root = test::tempDir("report-eye");
  Made ours = made("0.1.0+aaaaaaa", {"FIX", "IMP"}, 2, 1, 300, 1);
  Made authors = ours;
  authors.experiment = "base-true-centre";
  authors.table_metric = 0.5;
  ReportRequest r;
  r.dirs = {makeFolder(root / "base", ours), makeFolder(root / "base-true-centre", authors)};
  r.out = (root / "report.md").string();
  r.config_dir = kConfigDir;
  r.docs_dir = kDocsDir;
  writeReport(r);
  const std::string md = slurp(root / "report.md");
  const auto section = md.find("### base with the authors' eye");
  ASSERT_NE(section, std::string::npos) << md;
  const std::string rows = md.substr(section);
  for (const std::string sys : {"FIX", "IMP"}) {
    EXPECT_NE(rows.find("| " + sys + " | paper | 1.0 |"), std::string::npos) << rows;
    EXPECT_NE(rows.find("| " + sys + " | ours | 1.00 |"), std::string::npos) << rows;
    EXPECT_NE(rows.find("| " + sys + " | authors' eye | 0.50 |"), std::string::npos) << rows;
  }
  EXPECT_NE(md.find("results-discussion.md#authors-eye"), std::string::npos);
}

// Systems beyond the paper's (GOALS, novelty) have their extrinsic rows too, after the paper's.
// The report of one hand-made folder FOLDER under ROOT.
std::string reportOf(const fs::path& root, const std::string& folder, const Made& m) {
  ReportRequest r;
  r.dirs = {makeFolder(root / folder, m)};
  r.out = (root / "r.md").string();
  r.config_dir = kConfigDir;
  writeReport(r);
  return slurp(root / "r.md");
}

TEST(Report, EverySystemAFolderRanHasItsExtrinsicRows) {
  Made m = made("0.1.0+aaaaaaa", {"IMP", "GOALS"}, 2, 1, 300, 1);
  m.experiment = "goals";
  m.table_metric = 0.5;
  const std::string md = reportOf(test::tempDir("report-systems"), "goals", m);
  const auto section = md.find("## Extrinsic phase");
  ASSERT_NE(section, std::string::npos) << md;
  const std::string rows = md.substr(section, md.find("\n## ", section + 1) - section);
  const auto imp = rows.find("| IMP | 0.50"), goals = rows.find("| GOALS | 0.50");
  ASSERT_NE(imp, std::string::npos) << rows;
  ASSERT_NE(goals, std::string::npos) << rows;
  EXPECT_LT(imp, goals);  // the paper's systems first
  EXPECT_NE(rows.find("| GOALS tests solved | 1.00 |"), std::string::npos) << rows;
}

TEST(Report, EverySystemAFolderRanHasItsColumnOfErrorsAndItsCompletionRows) {
  // GOALS beside IMP: the intrinsic table has a column for each system any folder ran, and the completion steps a
  // row for each (they listed FIX, IGN and IMP alone).
  const std::string md =
      reportOf(test::tempDir("report-goals-columns"), "base", made("0.1.0+aaaaaaa", {"IMP", "GOALS"}, 2, 1, 300, 1));
  EXPECT_NE(md.find("| experiment | steps | IMP | GOALS |\n|---|---|---|---|\n"), std::string::npos) << md;
  EXPECT_NE(md.find("| base | 300 | 0.040 (0.026 authors' code) | 0.040 (0.026 authors' code) |"), std::string::npos)
      << md;
  EXPECT_NE(md.find("(IMP / GOALS; the paper's table in brackets)"), std::string::npos) << md;
  const auto completion = md.find("## Completion steps");
  ASSERT_NE(completion, std::string::npos) << md;
  const std::string rows = md.substr(completion, md.find("\n## ", completion + 1) - completion);
  EXPECT_NE(rows.find("| base | IMP |"), std::string::npos) << rows;
  EXPECT_NE(rows.find("| base | GOALS |"), std::string::npos) << rows;
}

TEST(Report, AnInterruptedFolderIsMarkedIncomplete) {
  const fs::path root = test::tempDir("report-interrupted");
  Made m = made("0.1.0+ccccccc", {"IMP"}, 3, 1, 300, 1);
  m.interrupted = true;
  ReportRequest r;
  r.dirs = {makeFolder(root / "base", m)};
  r.out = (root / "r.md").string();
  r.config_dir = kConfigDir;
  writeReport(r);
  const std::string md = slurp(root / "r.md");
  EXPECT_NE(md.find("**incomplete**: interrupted by SIGINT in the intrinsic phase, 2 of 3 runs finished, the extrinsic "
                    "tests not begun"),
            std::string::npos)
      << md;
}

TEST(Report, AnExperimentFileOfOursHasNoLinkToThePapersDiscussion) {
  const fs::path root = test::tempDir("report-own");
  Made m = made("0.1.0+ddddddd", {"IMP"}, 2, 1, 300, 1);
  m.experiment_file = "/home/me/slow-leak.yaml";
  ReportRequest r;
  r.dirs = {makeFolder(root / "mine", m)};
  r.out = (root / "r.md").string();
  r.config_dir = kConfigDir;
  r.docs_dir = kDocsDir;
  writeReport(r);
  const std::string md = slurp(root / "r.md");
  EXPECT_EQ(md.find("results-discussion.md"), std::string::npos) << md;
  EXPECT_EQ(md.find("Numbers in brackets are the paper's"), std::string::npos) << md;
  EXPECT_NE(md.find("experiment file `/home/me/slow-leak.yaml`"), std::string::npos) << md;
}

TEST(Report, LabelsAreTheExperimentUnlessFoldersShareIt) {
  EXPECT_EQ(folderLabels({"base", "late1"}, {"out/x", "out/y"}), (std::vector<std::string>{"base", "late1"}));
  EXPECT_EQ(folderLabels({"base", "base", "late1"}, {"out/a", "out/b/", "out/c"}),
            (std::vector<std::string>{"base-a", "base-b", "late1"}));
  // The same folder name twice, or the experiment's own: numbered in the order given.
  EXPECT_EQ(folderLabels({"base", "base", "base"}, {"x/base", "y/base", "z/base"}),
            (std::vector<std::string>{"base", "base-2", "base-3"}));
  // Never a path: what is not a letter, digit, '.', '-' or '_' becomes '-', and no label starts with '.'.
  EXPECT_EQ(folderLabels({"base", "base"}, {"out/my run", "out/..hidden"}),
            (std::vector<std::string>{"base-my-run", "base-hidden"}));
}

TEST(Report, FiguresGoBesideTheReportNamedAfterIt) {
  EXPECT_EQ(defaultFiguresDir("report.md"), "report");
  EXPECT_EQ(defaultFiguresDir("docs/results.md"), "docs/results");
  EXPECT_EQ(defaultFiguresDir("out/summary"), "out/summary-figures");  // never the report itself
}


TEST(Console, AGoalsAgentsModulesShowTheirGoalsAndCompetence) {
  // The console summary showed GOALS's learned table alone: each of its modules now has its goals reached of
  // those pursued, its competence early and late, and its share chosen (explore: its random actions).
  const std::string folder = std::string(AFFORD_SOURCE_DIR) + "/tests/data/compat/0.2.0/experiment";
  const Summary summary = readSummary(folder);
  Plan plan;
  plan.systems = {"IMP", "GOALS"};
  const std::string text = tablesText(summary, plan, folder);
  const auto goals = text.find("goals per module");
  ASSERT_NE(goals, std::string::npos) << text;
  EXPECT_GT(goals, text.find("\nGOALS ")) << text;  // under GOALS's table, not IMP's
  EXPECT_EQ(text.find("goals per module", goals + 1), std::string::npos) << text;
  const GoalsSummary& g = *summary.systems.at("GOALS").goals;
  for (const auto& [name, m] : g.modules) {
    const std::string cells =
        name == "explore" ? std::to_string(m.set) + " random actions"
                          : std::to_string(m.reached - m.found) + " of " + std::to_string(m.set - m.found);
    EXPECT_NE(text.find("    " + name + std::string(14 - name.size(), ' ') + cells, goals), std::string::npos)
        << name << "\n" << text;
  }
  EXPECT_NE(text.find(fixed(*g.modules.at("colour").first_tenth, 2) + " / -", goals), std::string::npos) << text;
}


// A name or title with a single quote (an object "bob's cube", "the world's table") is one gnuplot string: gnuplot
// reads it back whole (an apostrophe ended the string, and the plot failed).
TEST(Plots, AStringWithAQuoteIsOneGnuplotString) {
  const std::string dir = test::tempDir("gnuplot-quote");
  const std::string script = dir + "/print.gp";
  std::ofstream(script) << "print " << plots::quoted("bob's cube, the world's table") << "\n";
  const test::CommandResult r = test::runCommand("gnuplot " + script);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("bob's cube, the world's table"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

TEST(Console, TestsUnderPlannerConditionsShowEachConditionsShareSolved) {
  // An experiment that varies a planner setting (extrinsic.vary) printed no extrinsic table at all: its tests
  // ran and the console said nothing of them. Each condition now has its row.
  Summary summary;
  SystemExtrinsic ex;
  ex.scenarios = {"table1", "table2"};
  ex.tests_per_scenario = 1;
  std::vector<PlannerCondition> conditions(2);
  conditions[0].label = "eye.attention=bottom_up";
  conditions[1].label = "eye.attention=top_down";
  const double solved[2][2] = {{1.0, 0.0}, {1.0, 0.75}};
  for (int c = 0; c < 2; ++c)
    for (int k = 0; k < 2; ++k) {
      ConditionScenario s;
      s.tests = s.tests_completed = 4;
      s.success_rate = solved[c][k];
      s.utility.mean = 1.0 + k * c;
      conditions[static_cast<std::size_t>(c)].scenarios[ex.scenarios[static_cast<std::size_t>(k)]] = s;
    }
  ex.conditions = conditions;
  summary.systems["IMP"].extrinsic = ex;
  Plan plan;
  plan.systems = {"IMP"};
  const std::string text = tablesText(summary, plan, "");
  const auto at = text.find("Extrinsic tests by condition");
  ASSERT_NE(at, std::string::npos) << text;
  const auto row = [&](const std::string& label) {
    const auto from = text.find(label, at);
    return from == std::string::npos ? std::string() : text.substr(from, text.find('\n', from) - from);
  };
  const std::string bottom = row("eye.attention=bottom_up"), top = row("eye.attention=top_down");
  EXPECT_NE(bottom.find("1.00 (1.0)"), std::string::npos) << text;
  EXPECT_NE(bottom.find("0.00 (1.0)"), std::string::npos) << text;
  EXPECT_NE(top.find("0.75 (2.0)"), std::string::npos) << text;
  EXPECT_LT(bottom.find("1.00"), bottom.find("0.00")) << "table1's column before table2's\n" << text;
  // A design without conditions has one, unnamed: the table of scenarios is it, and nothing more is printed.
  summary.systems["IMP"].extrinsic->conditions->resize(1);
  summary.systems["IMP"].extrinsic->conditions->front().label.clear();
  const std::string one = tablesText(summary, plan, "");
  EXPECT_EQ(one.find("Extrinsic tests by condition"), std::string::npos) << one;
}

}  // namespace
}  // namespace afford

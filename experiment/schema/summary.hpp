// summary.json as a structure (docs/results-schema.md): every key it may
// hold, each declared once with its type in a visit() below, from which come
// the one conversion to JSON and the one from it (experiment/schema/codec.hpp). Reading is strict: a key of
// the wrong type, a missing one or an unknown one throws SummaryError naming
// its path (systems.IMP.runs[2].seed), so a reader never meets a summary it
// does not know.
//
// std::optional<T>: the key is absent when empty; Nullable<T>: the key is
// always there, null when empty.
#pragma once
#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiment/schema/codec.hpp"
#include "experiment/schema/goals.hpp"

namespace afford {

using SummaryTable = std::vector<std::vector<double>>;  // objects x actions
// The mean absolute difference of two tables; NaN if their shapes differ.
double meanAbsError(const SummaryTable& a, const SummaryTable& b);
using Settings = std::map<std::string, std::string>;     // key path -> value

struct Fit {  // y = a x^2 + b x
  double a = 0, b = 0;
  template <class V>
  void visit(V& v) {
    v("a", a);
    v("b", b);
  }
};

// A sample's description (extrinsic designs).
struct Stats {
  std::int64_t n = 0;
  double mean = 0, sd = 0, median = 0, q1 = 0, q3 = 0, min = 0, max = 0;
  template <class V>
  void visit(V& v) {
    v("n", n);
    v("mean", mean);
    v("sd", sd);
    v("median", median);
    v("q1", q1);
    v("q3", q3);
    v("min", min);
    v("max", max);
  }
};

// One intrinsic run that finished. Hosted runs say where their log and
// checkpoint are and what they cost; a random table's run names its table.
struct RunEntry {
  std::string run_id;
  std::int64_t seed = 0;
  SummaryTable affordance;
  double affordance_mae = 0;
  std::string weights_checksum;
  std::vector<std::int64_t> actions_executed, successes;
  std::int64_t looks = 0, replayed = 0, replayed_effects = 0, revisits = 0;
  Nullable<std::string> reused_from;
  double wall_seconds = 0, steps_per_second = 0;
  std::optional<std::int64_t> table;  // random tables
  std::optional<std::string> condition;
  std::optional<SummaryTable> target;
  std::optional<Nullable<std::string>> log_dir;  // hosted runs
  std::optional<Nullable<std::string>> checkpoint;
  std::optional<std::map<std::string, std::int64_t>> peak_rss_kb;
  std::optional<std::int64_t> log_bytes;
  std::optional<double> log_bytes_per_step;
  std::optional<std::string> sweep_condition;
  template <class V>
  void visit(V& v) {
    v("run_id", run_id);
    v("seed", seed);
    v("affordance", affordance);
    v("affordance_mae", affordance_mae);
    v("weights_checksum", weights_checksum);
    v("actions_executed", actions_executed);
    v("successes", successes);
    v("looks", looks);
    v("replayed", replayed);
    v("replayed_effects", replayed_effects);
    v("revisits", revisits);
    v("reused_from", reused_from);
    v("wall_seconds", wall_seconds);
    v("steps_per_second", steps_per_second);
    v("table", table);
    v("condition", condition);
    v("target", target);
    v("log_dir", log_dir);
    v("checkpoint", checkpoint);
    v("peak_rss_kb", peak_rss_kb);
    v("log_bytes", log_bytes);
    v("log_bytes_per_step", log_bytes_per_step);
    v("sweep_condition", sweep_condition);
  }
};

struct FailedRun {
  std::string run_id;
  std::int64_t seed = 0;
  std::string error;
  template <class V>
  void visit(V& v) {
    v("run_id", run_id);
    v("seed", seed);
    v("error", error);
  }
};

struct CurveGap {  // a run whose tables did not all arrive
  std::string run_id;
  std::int64_t snapshots = 0;
  template <class V>
  void visit(V& v) {
    v("run_id", run_id);
    v("snapshots", snapshots);
  }
};

struct Curves {  // the mean table at each reported step (Figures 7-9)
  std::vector<std::int64_t> steps;
  std::vector<SummaryTable> mean;
  template <class V>
  void visit(V& v) {
    v("steps", steps);
    v("mean", mean);
  }
};

// The solved tests' completion steps of one scenario (paper Table 2 designs).
struct ScenarioSteps {
  std::int64_t n = 0, sub_goals = 0;
  double median = 0, q1 = 0, q3 = 0, min = 0, max = 0, mean = 0;
  template <class V>
  void visit(V& v) {
    v("n", n);
    v("sub_goals", sub_goals);
    v("median", median);
    v("q1", q1);
    v("q3", q3);
    v("min", min);
    v("max", max);
    v("mean", mean);
  }
};

// Per scenario, and the fit over all of them under the key "fit" (Figure 6).
struct CompletionSteps {
  std::map<std::string, ScenarioSteps> scenarios;
  std::optional<Fit> fit;
};

// One scenario's tests under one planner condition (extrinsic designs).
struct ConditionScenario {
  std::int64_t tests = 0, tests_completed = 0;
  double success_rate = 0;
  Stats utility;
  std::vector<double> utility_agent_means;
  Stats actions_checked_per_sub_goal;
  std::vector<double> actions_checked_agent_means;
  std::int64_t sub_goals = 0, objects = 0, multi_step = 0;
  Stats completion_steps;
  template <class V>
  void visit(V& v) {
    v("tests", tests);
    v("tests_completed", tests_completed);
    v("success_rate", success_rate);
    v("utility", utility);
    v("utility_agent_means", utility_agent_means);
    v("actions_checked_per_sub_goal", actions_checked_per_sub_goal);
    v("actions_checked_agent_means", actions_checked_agent_means);
    v("sub_goals", sub_goals);
    v("objects", objects);
    v("multi_step", multi_step);
    v("completion_steps", completion_steps);
  }
};

// One (sub-goals, objects, multi-step) point of generated scenarios.
struct DesignPoint {
  std::int64_t sub_goals = 0, objects = 0, multi_step = 0, tests = 0, tests_completed = 0;
  double success_rate = 0;
  Stats completion_steps, steps_per_sub_goal;
  template <class V>
  void visit(V& v) {
    v("sub_goals", sub_goals);
    v("objects", objects);
    v("multi_step", multi_step);
    v("tests", tests);
    v("tests_completed", tests_completed);
    v("success_rate", success_rate);
    v("completion_steps", completion_steps);
    v("steps_per_sub_goal", steps_per_sub_goal);
  }
};

struct PlannerCondition {
  std::string label;
  Settings settings;
  std::map<std::string, ConditionScenario> scenarios;
  std::vector<DesignPoint> points;
  std::optional<Fit> completion_fit;
  template <class V>
  void visit(V& v) {
    v("label", label);
    v("settings", settings);
    v("scenarios", scenarios);
    v("points", points);
    v("completion_fit", completion_fit);
  }
};

// A system's extrinsic tests: per scenario (one condition) or per condition.
struct SystemExtrinsic {
  std::vector<std::string> scenarios;
  std::int64_t tests_per_scenario = 0;
  double table_metric_solved_share = 0;
  std::optional<std::map<std::string, double>> table_metric, success_rate, actions_checked_per_sub_goal;
  std::optional<CompletionSteps> completion_steps;
  std::optional<std::vector<PlannerCondition>> conditions;
  std::optional<std::vector<FailedRun>> failed_tests;  // tests that failed to run (not counted above), and why
  template <class V>
  void visit(V& v) {
    v("scenarios", scenarios);
    v("tests_per_scenario", tests_per_scenario);
    v("table_metric_solved_share", table_metric_solved_share);
    v("table_metric", table_metric);
    v("success_rate", success_rate);
    v("completion_steps", completion_steps);
    v("actions_checked_per_sub_goal", actions_checked_per_sub_goal);
    v("conditions", conditions);
    v("failed_tests", failed_tests);
  }
};

struct SystemSummary {
  std::optional<SummaryTable> target;  // absent on random tables
  std::vector<RunEntry> runs;
  std::optional<std::vector<FailedRun>> failed_runs;
  std::optional<std::vector<CurveGap>> curve_gaps;
  std::optional<SummaryTable> affordance, affordance_min, affordance_max;
  std::optional<double> affordance_mae, affordance_mae_of_mean, reference_affordance_mae;
  std::optional<Curves> curves;
  std::optional<std::map<std::string, double>> reference_table_metric;
  std::optional<SystemExtrinsic> extrinsic;
  std::optional<std::vector<double>> utility_mean, utility_sd;  // analysis forward-models, per budget
  std::optional<GoalsSummary> goals;                             // GOALS: its goals
  template <class V>
  void visit(V& v) {
    v("target", target);
    v("runs", runs);
    v("failed_runs", failed_runs);
    v("curve_gaps", curve_gaps);
    v("affordance", affordance);
    v("affordance_min", affordance_min);
    v("affordance_max", affordance_max);
    v("affordance_mae", affordance_mae);
    v("affordance_mae_of_mean", affordance_mae_of_mean);
    v("reference_affordance_mae", reference_affordance_mae);
    v("curves", curves);
    v("reference_table_metric", reference_table_metric);
    v("extrinsic", extrinsic);
    v("utility_mean", utility_mean);
    v("utility_sd", utility_sd);
    v("goals", goals);
  }
};

struct TableErrors {  // one condition and system on random tables
  std::vector<Nullable<double>> per_table;
  std::int64_t tables = 0;
  Nullable<double> mean;
  double median = 0, q1 = 0, q3 = 0;
  Nullable<double> min, worst;
  std::int64_t worst_table = -1;
  template <class V>
  void visit(V& v) {
    v("per_table", per_table);
    v("tables", tables);
    v("mean", mean);
    v("median", median);
    v("q1", q1);
    v("q3", q3);
    v("min", min);
    v("worst", worst);
    v("worst_table", worst_table);
  }
};

struct Floors {
  double mean = 0, worst = 0;
  std::string source;
  template <class V>
  void visit(V& v) {
    v("mean", mean);
    v("worst", worst);
    v("source", source);
  }
};

struct RandomTables {
  std::int64_t seed = 0, count = 0;
  std::vector<SummaryTable> tables;
  std::map<std::string, std::vector<std::string>> conditions;  // condition -> its settings
  std::map<std::string, std::map<std::string, TableErrors>> mae;  // condition -> system ->
  std::vector<std::vector<std::string>> one_way_looks;
  std::vector<std::string> condition_order, system_order;
  std::optional<Floors> floors;
  template <class V>
  void visit(V& v) {
    v("seed", seed);
    v("count", count);
    v("tables", tables);
    v("conditions", conditions);
    v("mae", mae);
    v("one_way_looks", one_way_looks);
    v("condition_order", condition_order);
    v("system_order", system_order);
    v("floors", floors);
  }
};

struct MultiStep {  // a number, or "all" (m = k)
  bool all = false;
  std::int64_t count = 0;
};

struct GenerateSummary {
  std::vector<std::int64_t> sub_goals, objects;
  std::int64_t per_point = 0, seed = 0;
  MultiStep multi_step;
  template <class V>
  void visit(V& v) {
    v("sub_goals", sub_goals);
    v("objects", objects);
    v("per_point", per_point);
    v("seed", seed);
    v("multi_step", multi_step);
  }
};

struct DesignSummary {
  std::vector<std::string> scenarios;
  std::int64_t tests = 0, after_actions = 0;
  std::map<std::string, std::vector<std::string>> vary;
  std::string analysis;
  std::optional<GenerateSummary> generate;
  template <class V>
  void visit(V& v) {
    v("scenarios", scenarios);
    v("tests", tests);
    v("vary", vary);
    v("analysis", analysis);
    v("after_actions", after_actions);
    v("generate", generate);
  }
};

using PValues = std::vector<Nullable<double>>;  // null: a sample of fewer than two tests

struct UtilityAnalysis {  // Figure 12
  std::string system, scenario;
  std::vector<std::int64_t> budgets;
  std::vector<double> goal_mean, utility_mean, goal_sd, utility_sd;
  PValues p_values, t;
  std::vector<std::vector<std::int64_t>> n;
  template <class V>
  void visit(V& v) {
    v("system", system);
    v("scenario", scenario);
    v("budgets", budgets);
    v("goal_mean", goal_mean);
    v("utility_mean", utility_mean);
    v("goal_sd", goal_sd);
    v("utility_sd", utility_sd);
    v("p_values", p_values);
    v("t", t);
    v("n", n);
  }
};

struct ForwardModelsAnalysis {  // Figure 13
  std::string scenario;
  std::vector<std::int64_t> budgets;
  std::map<std::string, PValues> p_values, t;  // "IMP-FIX" ->
  template <class V>
  void visit(V& v) {
    v("scenario", scenario);
    v("budgets", budgets);
    v("p_values", p_values);
    v("t", t);
  }
};

struct SearchAnalysis {  // Figure 14
  std::string system, scenario;
  double restricted_mean = 0, unrestricted_mean = 0, restricted_sd = 0, unrestricted_sd = 0;
  std::vector<std::int64_t> n;
  Nullable<double> p_value, t, df;
  template <class V>
  void visit(V& v) {
    v("system", system);
    v("scenario", scenario);
    v("restricted_mean", restricted_mean);
    v("unrestricted_mean", unrestricted_mean);
    v("restricted_sd", restricted_sd);
    v("unrestricted_sd", unrestricted_sd);
    v("n", n);
    v("p_value", p_value);
    v("t", t);
    v("df", df);
  }
};

struct CutRun {
  std::string run_id, where;
  Nullable<std::string> log_dir;
  template <class V>
  void visit(V& v) {
    v("run_id", run_id);
    v("where", where);
    v("log_dir", log_dir);
  }
};

struct Interruption {
  std::string signal, phase;
  std::int64_t finished = 0, planned = 0;
  std::vector<CutRun> cut;
  std::vector<std::string> not_started;
  bool extrinsic_tests_to_come = false;
  std::string resume, resume_in;
  template <class V>
  void visit(V& v) {
    v("signal", signal);
    v("phase", phase);
    v("finished", finished);
    v("planned", planned);
    v("cut", cut);
    v("not_started", not_started);
    v("extrinsic_tests_to_come", extrinsic_tests_to_come);
    v("resume", resume);
    v("resume_in", resume_in);
  }
};

struct ShardSummary {
  std::int64_t index = 0, count = 0;
  template <class V>
  void visit(V& v) {
    v("index", index);
    v("count", count);
  }
};

// What an experiment's summary and a sweep's both begin with.
struct ExperimentHeader {
  std::string experiment, description;
  std::int64_t steps = 0, repetitions = 0, seed = 0;
  std::string transport, network, afford_version;
  template <class V>
  void visit(V& v) {
    v("experiment", experiment);
    v("description", description);
    v("steps", steps);
    v("repetitions", repetitions);
    v("seed", seed);
    v("transport", transport);
    v("network", network);
    v("afford_version", afford_version);
  }
};

// One experiment's summary.json (a sweep condition's too).
struct Summary : ExperimentHeader {
  std::optional<std::string> experiment_file;           // --config FILE
  std::optional<std::map<std::string, std::string>> processes;  // --process
  std::vector<std::string> objects, actions;  // the rows and columns of every table
  std::optional<std::string> reference_source, reference_extrinsic_source;
  std::optional<Fit> reference_completion_fit;
  std::map<std::string, SystemSummary> systems;
  std::optional<RandomTables> random_tables;
  std::optional<DesignSummary> extrinsic_design;
  std::optional<std::int64_t> after_actions;
  std::optional<std::vector<std::string>> untested_agents;
  std::optional<UtilityAnalysis> utility;
  std::optional<ForwardModelsAnalysis> forward_models;
  std::optional<SearchAnalysis> search;
  std::optional<Interruption> interrupted;
  std::optional<ShardSummary> shard;
  std::optional<std::vector<std::string>> merged_from;
  std::optional<std::string> sweep_condition;
  std::optional<std::vector<std::string>> sweep_settings;
  std::int64_t extrinsic_tests = 0;
  double wall_seconds = 0;
  template <class V>
  void visit(V& v) {
    ExperimentHeader::visit(v);
    v("experiment_file", experiment_file);
    v("processes", processes);
    v("objects", objects);
    v("actions", actions);
    v("reference_source", reference_source);
    v("reference_extrinsic_source", reference_extrinsic_source);
    v("reference_completion_fit", reference_completion_fit);
    v("systems", systems);
    v("random_tables", random_tables);
    v("extrinsic_design", extrinsic_design);
    v("after_actions", after_actions);
    v("untested_agents", untested_agents);
    v("utility", utility);
    v("forward_models", forward_models);
    v("search", search);
    v("interrupted", interrupted);
    v("shard", shard);
    v("merged_from", merged_from);
    v("sweep_condition", sweep_condition);
    v("sweep_settings", sweep_settings);
    v("extrinsic_tests", extrinsic_tests);
    v("wall_seconds", wall_seconds);
  }
};

struct SweepEntry {
  std::string name;
  std::vector<std::string> settings;
  std::string folder;  // relative to the sweep's folder
  template <class V>
  void visit(V& v) {
    v("name", name);
    v("settings", settings);
    v("folder", folder);
  }
};

struct SweepKeys {
  std::map<std::string, std::vector<std::string>> keys;  // each swept key's values
  std::vector<SweepEntry> conditions;
  template <class V>
  void visit(V& v) {
    v("keys", keys);
    v("conditions", conditions);
  }
};

// A sweep's own summary.json: every condition's summary under its name.
struct SweepSummary : ExperimentHeader {
  std::vector<std::string> settings;  // the --set keys with one value
  SweepKeys sweep;
  std::map<std::string, Summary> conditions;
  std::optional<Interruption> interrupted;
  double wall_seconds = 0;
  template <class V>
  void visit(V& v) {
    ExperimentHeader::visit(v);
    v("settings", settings);
    v("sweep", sweep);
    v("conditions", conditions);
    v("interrupted", interrupted);
    v("wall_seconds", wall_seconds);
  }
};

nlohmann::json toJson(const Summary& s);
nlohmann::json toJson(const SweepSummary& s);
nlohmann::json toJson(const Interruption& i);  // as in summary.json (experiment.json keeps its cut runs too)
// Throw SummaryError naming the key (its path from the top) that is missing,
// unknown or of the wrong type; `what` begins the message (a file's name).
Summary summaryFromJson(const nlohmann::json& j, const std::string& what = "summary.json");
SweepSummary sweepSummaryFromJson(const nlohmann::json& j, const std::string& what = "summary.json");
// A sweep's summary has "sweep"; any other is one experiment's.
bool isSweepSummary(const nlohmann::json& j);

// An experiment folder's summary.json, read and parsed: throws SummaryError
// naming the file for one missing, unreadable, larger than max_bytes (a
// summary of thousands of runs is a few MB), not JSON, or not a summary.
constexpr std::uintmax_t kMaxSummaryBytes = std::uintmax_t{256} << 20;
nlohmann::json readSummaryJson(const std::string& dir, std::uintmax_t max_bytes = kMaxSummaryBytes);
Summary readSummary(const std::string& dir);

}  // namespace afford

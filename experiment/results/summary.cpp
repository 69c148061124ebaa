#include "experiment/results/summary.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>

#include "afford/version.hpp"
#include "afford/actions.hpp"
#include "experiment/design/reference.hpp"
#include "experiment/run/outcome.hpp"
#include "experiment/design/tables.hpp"
#include "experiment/results/goals.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using Table = SummaryTable;

Table asTable(const AffordanceTable& t) {
  Table out;
  for (const auto& row : t) out.emplace_back(row.begin(), row.end());
  return out;
}

// Random tables (issue 11): per condition and system, each table's mean
// absolute error (mean over its runs), their mean, quartiles and the worst
// table; and random_tables.csv, random_tables_entries.csv.
RandomTables summariseTables(const Plan& plan, const PhaseRuns& phase, const std::string& out_dir) {
  const auto label = [](const std::string& c) { return c.empty() ? std::string("default") : c; };
  std::vector<std::string> names;
  for (const auto& ob : plan.configs.begin()->second.world.objects) names.push_back(ob.name);
  const auto names_of = [&](std::size_t i) { return names[i]; };
  RandomTables rt;
  rt.seed = plan.tables->seed;
  rt.count = plan.tables->count;
  for (const auto& table : plan.table_list) rt.tables.push_back(asTable(table));
  for (const auto& table : plan.table_list) {  // per table: the objects whose look cannot come back once left
    std::vector<std::string> one_way;
    for (std::size_t i : oneWayLooks(table, plan.configs.begin()->second.world.objects)) one_way.push_back(names_of(i));
    rt.one_way_looks.push_back(one_way);
  }
  rt.system_order = plan.systems;
  for (const auto& [c, settings] : plan.conditions_run) {
    rt.conditions[label(c)] = settings;
    rt.condition_order.push_back(label(c));
  }
  std::ostringstream csv, entries;
  csv << "table,condition,system,seed,run_id,mae\n";
  entries << "table,object,action,afforded\n";
  for (std::size_t k = 0; k < plan.table_list.size(); ++k)
    for (std::size_t i = 0; i < plan.table_list[k].size(); ++i)
      for (int a = 0; a < kNumActions; ++a)
        entries << k << ",\"" << names[i] << "\"," << kActionNames[a] << "," << plan.table_list[k][i][a] << "\n";
  for (const auto& [c, settings] : plan.conditions_run)
    for (const auto& sys : plan.systems) {
      std::vector<double> sum(plan.table_list.size(), 0.0);
      std::vector<int> n(plan.table_list.size(), 0);
      for (const auto& p : plan.runs) {
        if (p.intrinsic_condition != c || p.system != sys || !phase.finished[p.index]) continue;
        const RunOutcome& r = phase.outcomes[p.index];
        if (!r.ok || r.curve.empty()) continue;
        const double mae = meanAbsError(r.curve.back().affordance, p.target);
        sum[static_cast<std::size_t>(p.table)] += mae;
        ++n[static_cast<std::size_t>(p.table)];
        csv << p.table << "," << label(c) << "," << sys << "," << p.spec.seed << "," << p.spec.run_id << "," << mae << "\n";
      }
      TableErrors& e = rt.mae[label(c)][sys];
      std::vector<double> values;
      for (std::size_t k = 0; k < sum.size(); ++k) {
        e.per_table.emplace_back();
        if (!n[k]) continue;
        e.per_table.back() = sum[k] / n[k];
        values.push_back(sum[k] / n[k]);
        if (e.worst_table < 0 || sum[k] / n[k] > *e.per_table[static_cast<std::size_t>(e.worst_table)])
          e.worst_table = static_cast<std::int64_t>(k);
      }
      std::vector<double> sorted = values;
      std::sort(sorted.begin(), sorted.end());
      double mean = 0;
      for (double v : values) mean += v / values.size();
      e.tables = static_cast<std::int64_t>(values.size());
      if (!values.empty()) e.mean = mean;
      e.median = quantile(sorted, 0.5);
      e.q1 = quantile(sorted, 0.25);
      e.q3 = quantile(sorted, 0.75);
      if (!sorted.empty()) {
        e.min = sorted.front();
        e.worst = sorted.back();
      }
    }
  writeWhole(fs::path(out_dir) / "random_tables.csv", csv.str());
  writeWhole(fs::path(out_dir) / "random_tables_entries.csv", entries.str());
  return rt;
}

}  // namespace

void summariseExtrinsic(Summary& summary, const Plan& plan, const std::vector<PlannedRun>& tests, const PhaseRuns& phase,
                        const std::string& out_dir) {
  const double solved_share = plan.reference->required("thresholds.table_metric.solved_share");
  const auto& outcomes = phase.outcomes;
  for (const auto& sys : plan.systems) {
    std::ostringstream csv;
    csv << "system,intrinsic_run_id,seed,scenario,condition,rep,success,completion,attempts,utility,sub_goals,"
           "active_sub_goals,actions_checked,wall_seconds\n";
    std::vector<FailedRun> failed;  // failed to run (a process, a checkpoint): no result, not counted
    for (const auto& t : tests) {
      if (t.system != sys || !phase.finished[t.index]) continue;
      const RunOutcome& r = outcomes[t.index];
      if (!r.ok) {
        failed.push_back({t.spec.run_id, t.spec.seed, r.error});
        continue;
      }
      int checks = 0, active = 0;
      for (const auto& g : r.extrinsic.sub_goals) checks += g.actions_checked, active += g.iterations > 0;
      csv << sys << "," << plan.runs[t.intrinsic].spec.run_id << "," << t.spec.seed << "," << t.scenario << ",\""
          << plan.conditions[t.condition].label << "\"," << t.rep << "," << (r.ok && r.extrinsic.success) << ","
          << r.extrinsic.completion << "," << r.extrinsic.attempts << "," << r.extrinsic.utility << ","
          << r.extrinsic.sub_goals.size() << "," << active << "," << checks << "," << r.wall_seconds << "\n";
    }
    writeWhole(fs::path(out_dir) / ("extrinsic_" + sys + ".csv"), csv.str());
    SystemExtrinsic& ex = summary.systems[sys].extrinsic.emplace();
    ex.scenarios = plan.scenarios;
    ex.tests_per_scenario = plan.tests;
    ex.table_metric_solved_share = solved_share;
    if (!failed.empty()) ex.failed_tests = failed;
    if (plan.conditions.size() > 1) continue;  // the design's summary compares the conditions
    auto& table_metric = ex.table_metric.emplace();
    auto& success_rate = ex.success_rate.emplace();
    auto& completion = ex.completion_steps.emplace();
    auto& checked_per_sub_goal = ex.actions_checked_per_sub_goal.emplace();
    std::vector<std::pair<double, double>> solved;  // (sub-goals, completion) of every solved test
    for (const auto& scenario : plan.scenarios) {
      std::map<std::size_t, std::pair<int, int>> per_run;  // intrinsic run -> (successes, tests)
      std::vector<double> steps;
      double checked = 0;
      int sub_goal_count = 0, successes = 0, total = 0;
      for (const auto& t : tests) {
        if (t.system != sys || t.scenario != scenario || !phase.finished[t.index] || !outcomes[t.index].ok) continue;
        const RunOutcome& r = outcomes[t.index];
        const bool ok = r.extrinsic.success;
        auto& [s, n] = per_run[t.intrinsic];
        s += ok;
        ++n;
        successes += ok;
        ++total;
        int checks = 0;
        for (const auto& g : r.extrinsic.sub_goals) checks += g.actions_checked;
        checked += checks;
        sub_goal_count += static_cast<int>(r.extrinsic.sub_goals.size());
        if (ok) {
          steps.push_back(r.extrinsic.completion);
          solved.emplace_back(plan.sub_goals.at(scenario), r.extrinsic.completion);
        }
      }
      int good_runs = 0;
      for (const auto& [run, sn] : per_run) good_runs += sn.first > solved_share * sn.second;
      std::sort(steps.begin(), steps.end());
      double mean = 0;
      for (double v : steps) mean += v / steps.size();
      if (per_run.empty()) continue;  // no test of it ran: no share to state (the table shows "-")
      table_metric[scenario] = static_cast<double>(good_runs) / per_run.size();
      success_rate[scenario] = static_cast<double>(successes) / total;
      completion.scenarios[scenario] = {static_cast<std::int64_t>(steps.size()),
                                        plan.sub_goals.at(scenario),
                                        quantile(steps, 0.5),
                                        quantile(steps, 0.25),
                                        quantile(steps, 0.75),
                                        steps.empty() ? 0.0 : steps.front(),
                                        steps.empty() ? 0.0 : steps.back(),
                                        mean};
      checked_per_sub_goal[scenario] = sub_goal_count ? checked / sub_goal_count : 0.0;
    }
    if (const auto fit = fitCompletion(solved)) completion.fit = Fit{fit->a, fit->b};
  }
}

namespace {

// A finished intrinsic run's entry in its system's "runs".
RunEntry runEntry(const Plan& plan, const PlannedRun& p, const RunOutcome& r, double mae) {
  RunEntry entry;
  entry.run_id = p.spec.run_id;
  entry.seed = p.spec.seed;
  entry.affordance = r.curve.back().affordance;
  entry.affordance_mae = mae;
  entry.weights_checksum = r.weights_checksum;
  entry.actions_executed.assign(r.executed.begin(), r.executed.end());
  entry.successes.assign(r.successes.begin(), r.successes.end());
  entry.looks = r.looks;
  entry.replayed = r.replayed;
  entry.replayed_effects = r.replayed_effects;
  entry.revisits = r.revisits;
  if (!r.reused_from.empty()) entry.reused_from = r.reused_from;
  entry.wall_seconds = r.wall_seconds;
  entry.steps_per_second = r.run_seconds > 0 ? p.spec.steps / r.run_seconds : 0.0;
  if (plan.tables) {  // random tables: each run against its own table; no mean table or curve across them
    entry.table = p.table;
    entry.condition = p.intrinsic_condition.empty() ? std::string("default") : p.intrinsic_condition;
    entry.target = p.target;
    return entry;
  }
  entry.log_dir = r.log_dir.empty() ? Nullable<std::string>() : Nullable<std::string>(r.log_dir);
  entry.checkpoint = Nullable<std::string>(r.checkpoint);
  entry.peak_rss_kb = std::map<std::string, std::int64_t>(r.peak_rss_kb.begin(), r.peak_rss_kb.end());
  entry.log_bytes = r.log_bytes;
  entry.log_bytes_per_step = static_cast<double>(r.log_bytes) / p.spec.steps;
  return entry;
}

// A system's final tables: their mean, least and greatest entries, and how far each is from the target;
// and affordance_<system>.csv.
void summariseFinals(SystemSummary& js, const std::string& sys, const Table& target, const std::vector<Table>& finals,
                     const std::vector<double>& maes, const std::vector<std::string>& object_names,
                     const std::string& out_dir, WorldKind kind) {
  Table mean = target, mn = target, mx = target;
  for (std::size_t i = 0; i < target.size(); ++i)
    for (int a = 0; a < kNumActions; ++a) {
      double s = 0, lo = 1e9, hi = -1e9;
      for (const auto& f : finals) {
        s += f[i][a];
        lo = std::min(lo, f[i][a]);
        hi = std::max(hi, f[i][a]);
      }
      mean[i][a] = s / finals.size();
      mn[i][a] = lo;
      mx[i][a] = hi;
    }
  double mae_sum = 0;
  for (double m : maes) mae_sum += m;
  js.affordance = mean;
  js.affordance_min = mn;
  js.affordance_max = mx;
  js.affordance_mae = mae_sum / maes.size();
  js.affordance_mae_of_mean = meanAbsError(mean, target);
  std::ostringstream csv;
  csv << "system,object,action,target,mean,min,max\n";
  for (std::size_t i = 0; i < target.size(); ++i)
    for (int a = 0; a < kNumActions; ++a)
      csv << sys << ",\"" << object_names[i] << "\"," << actionName(kind, a) << "," << target[i][a] << "," << mean[i][a]
          << "," << mn[i][a] << "," << mx[i][a] << "\n";
  writeWhole(fs::path(out_dir) / ("affordance_" + sys + ".csv"), csv.str());
}

// One system's summary of its finished intrinsic runs; and curves_<system>.csv.
SystemSummary summariseSystem(const Plan& plan, const std::string& sys, const PhaseRuns& phase,
                     const std::vector<std::string>& object_names, const std::string& out_dir) {
  const RunConfig& cfg = plan.configs.at(sys);
  Table target;
  for (const auto& ob : cfg.world.objects) target.emplace_back(ob.affordance.begin(), ob.affordance.end());
  SystemSummary js;
  if (!plan.tables) js.target = target;
  std::vector<Table> finals;
  std::vector<double> maes;
  // A long run's curve is tens of megabytes of rows: written as they are made.
  std::optional<WholeFile> curves_file;
  if (!plan.tables) curves_file.emplace(fs::path(out_dir) / ("curves_" + sys + ".csv"));
  std::ostream* curves_csv = curves_file ? &curves_file->out() : nullptr;
  if (curves_csv) *curves_csv << "system,run_id,seed,step,object,action,prediction\n";
  std::map<std::int64_t, std::pair<Table, int>> curve_sum;
  for (const auto& p : plan.runs) {
    if (p.system != sys || !phase.finished[p.index]) continue;
    const RunOutcome& r = phase.outcomes[p.index];
    if (!r.ok || r.curve.empty()) {
      if (!js.failed_runs) js.failed_runs.emplace();
      js.failed_runs->push_back({p.spec.run_id, p.spec.seed, r.error});
      continue;
    }
    // Every run reports its table at the same steps (run.curve_interval): a snapshot lost on the
    // way would bias the mean curve at that step, so say so.
    if (r.curve.size() != static_cast<std::size_t>(cfg.steps / cfg.curve_interval + 1) + (cfg.steps % cfg.curve_interval != 0))
      (js.curve_gaps ? *js.curve_gaps : js.curve_gaps.emplace())
          .push_back({p.spec.run_id, static_cast<std::int64_t>(r.curve.size())});
    finals.push_back(r.curve.back().affordance);
    maes.push_back(meanAbsError(finals.back(), p.target));
    js.runs.push_back(runEntry(plan, p, r, maes.back()));
    if (plan.tables) continue;
    for (const auto& snap : r.curve) {
      auto& [sum, n] = curve_sum[snap.step];
      if (sum.empty()) sum = Table(snap.affordance.size(), std::vector<double>(kNumActions, 0.0));
      for (std::size_t i = 0; i < snap.affordance.size(); ++i)
        for (int a = 0; a < kNumActions; ++a) {
          sum[i][a] += snap.affordance[i][a];
          *curves_csv << sys << "," << p.spec.run_id << "," << p.spec.seed << "," << snap.step << ",\""
                      << object_names[i] << "\"," << actionName(cfg.world.kind, a) << "," << snap.affordance[i][a] << "\n";
        }
      ++n;
    }
  }
  if (!finals.empty() && !plan.tables) {
    summariseFinals(js, sys, target, finals, maes, object_names, out_dir, cfg.world.kind);
    Curves& curves = js.curves.emplace();
    for (auto& [step, sn] : curve_sum) {
      auto& [sum, n] = sn;
      for (auto& row : sum)
        for (auto& v : row) v /= n;
      curves.steps.push_back(step);
      curves.mean.push_back(sum);
    }
  }
  if (curves_file) curves_file->commit();
  if (cfg.phase == Phase::Goals) {
    std::vector<std::pair<std::string, const RunOutcome*>> goal_runs;
    for (const auto& p : plan.runs)
      if (p.system == sys && phase.finished[p.index] && phase.outcomes[p.index].ok)
        goal_runs.emplace_back(p.spec.run_id, &phase.outcomes[p.index]);
    js.goals = summariseGoals(sys, goal_runs, cfg.steps, cfg.curve_interval, out_dir);
  }
  return js;
}

// The paper's numbers for the same experiment (config/reference.yaml), beside ours: its mean absolute
// errors, the floors of random tables, its extrinsic tables and completion fit.
void addReference(Summary& summary, const Plan& plan) {
  const auto& exp = plan.exp;
  if (!exp.file.empty()) return;  // an experiment from a file elsewhere has none beside it
  const Reference& ref = *plan.reference;
  const YAML::Node reference = ref.entry(exp.name);
  const std::string key = exp.name + ".";
  // The errors after the steps they were measured at: not beside runs of another length (--steps).
  const bool same_steps = !reference || !reference["steps"] ||
                          static_cast<std::int64_t>(ref.number(reference["steps"], key + "steps")) == summary.steps;
  for (const auto& sys : plan.systems)
    if (same_steps && reference && reference["affordance_mae"] && reference["affordance_mae"][sys])
      summary.systems[sys].reference_affordance_mae =
          ref.number(reference["affordance_mae"][sys], key + "affordance_mae." + sys);
  if (reference && reference["source"]) summary.reference_source = ref.text(reference["source"], key + "source");
  if (plan.tables && reference && reference["floors"])  // what issue 11 asks of the memory options, shown beside
    summary.random_tables->floors = Floors{ref.number(reference["floors"]["mean"], key + "floors.mean"),
                                           ref.number(reference["floors"]["worst"], key + "floors.worst"),
                                           ref.text(reference["floors"]["source"], key + "floors.source")};
  const std::string ekey = exp.name + "_extrinsic";
  const YAML::Node ext = ref.entry(ekey);
  if (ext && ext["table_metric"])
    for (const auto& sys : plan.systems)
      if (ext["table_metric"][sys]) {  // the paper's scenarios 1-5
        const auto row = ref.numbers(ext["table_metric"][sys], ekey + ".table_metric." + sys);
        auto& metric = summary.systems[sys].reference_table_metric.emplace();
        for (std::size_t k = 0; k < row.size(); ++k) metric["scenario" + std::to_string(k + 1)] = row[k];
      }
  if (ext && ext["completion_fit"])
    summary.reference_completion_fit = Fit{ref.number(ext["completion_fit"]["a"], ekey + ".completion_fit.a"),
                                           ref.number(ext["completion_fit"]["b"], ekey + ".completion_fit.b")};
  if (ext && ext["source"]) summary.reference_extrinsic_source = ref.text(ext["source"], ekey + ".source");
}

}  // namespace

// summary.json content (docs/results-schema.md) of the finished runs; also writes the CSV files.
Summary summarise(const Plan& plan, const Hosting& hosting, const PhaseRuns& phase, const std::string& out_dir) {
  Summary summary;
  for (const auto& ob : plan.configs.begin()->second.world.objects) summary.objects.push_back(ob.name);
  summary.experiment = plan.exp.name;
  summary.description = plan.exp.description;
  summary.steps = plan.runs.front().spec.steps;
  summary.repetitions = plan.reps;
  summary.seed = plan.seed;
  summary.transport = hosting.transport;
  summary.network = hosting.network;
  summary.afford_version = affordVersion();
  for (int a = 0; a < kNumActions; ++a)
    summary.actions.emplace_back(actionName(plan.configs.begin()->second.world.kind, a));
  if (!plan.exp.file.empty()) summary.experiment_file = plan.exp.file;
  if (!hosting.processes.empty()) summary.processes = hosting.processes;  // --process: the commands run in place of ours
  for (const auto& sys : plan.systems)
    summary.systems[sys] = summariseSystem(plan, sys, phase, summary.objects, out_dir);
  if (plan.tables) summary.random_tables = summariseTables(plan, phase, out_dir);
  addReference(summary, plan);
  return summary;
}

std::vector<TestRecord> testRecords(const Plan& plan, const std::vector<PlannedRun>& tests, const PhaseRuns& phase) {
  std::vector<TestRecord> records;
  for (const auto& t : tests) {
    if (!phase.finished[t.index]) continue;
    const RunOutcome& r = phase.outcomes[t.index];
    TestRecord rec;
    rec.system = t.system;
    rec.agent = t.intrinsic;
    rec.scenario = t.scenario;
    rec.condition = t.condition;
    rec.ok = r.ok;
    rec.success = r.ok && r.extrinsic.success;
    rec.utility = r.extrinsic.utility;
    rec.attempts = r.extrinsic.attempts;
    rec.completion = r.extrinsic.completion;
    rec.sub_goals = plan.sub_goals.at(t.scenario);
    if (const auto spec = plan.specs.find(t.scenario); spec != plan.specs.end()) {
      rec.objects = spec->second.objects;
      rec.multi_step = spec->second.multi_step;
    } else {
      rec.objects = rec.sub_goals;
    }
    for (const auto& g : r.extrinsic.sub_goals) {
      rec.actions_checked += g.actions_checked;
      rec.active_sub_goals += g.iterations > 0;
    }
    records.push_back(rec);
  }
  return records;
}

}  // namespace afford

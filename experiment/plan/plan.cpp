#include "experiment/plan/plan.hpp"

#include "afford/names.hpp"
#include "afford/node.hpp"

#include <algorithm>
#include <ctime>
#include <filesystem>

#include "afford/actions.hpp"
#include "experiment/design/design.hpp"
#include "experiment/design/generate.hpp"
#include "afford/processes.hpp"

namespace afford {
namespace fs = std::filesystem;

void checkPlanRequest(const PlanRequest& o) {
  if (o.keep_logs != "all" && o.keep_logs != "first" && o.keep_logs != "none")
    throw ConfigError("--keep-logs must be all, first or none, not \"" + o.keep_logs + "\"");
  if (o.keep_checkpoints != "all" && o.keep_checkpoints != "first" && o.keep_checkpoints != "none")
    throw ConfigError("--keep-checkpoints must be all, first or none, not \"" + o.keep_checkpoints + "\"");
  if (o.extrinsic_reps < 0) throw ConfigError("--extrinsic-reps must be 0 or more");
  if (o.reps && *o.reps < 1) throw ConfigError("--reps must be at least 1");
}

std::string defaultPrefix() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::localtime(&t));
  return buf;
}

// Everything that can be wrong with the request is found here, before any process starts.
namespace {
// A run id names folders and files, and every process drops messages of one that is not a safe name
// (afford/names.hpp): refuse it here, before anything runs, naming what it is made of.
void checkRunId(const std::string& id, const Plan& plan) {
  if (const std::string why = runIdProblem(id, plan.protocol.limits.run_id_bytes); !why.empty())
    throw ConfigError("run id '" + printable(id) + "' " + why +
                      ": it is made of --run-prefix, the experiment's name, its conditions' and scenarios' names; "
                      "change the one that has it");
}
}  // namespace

Plan planExperiment(const PlanRequest& o) {
  Plan plan;
  plan.config_dir = o.config_dir.empty() ? defaultConfigDir() : o.config_dir;
  plan.exp = loadExperiment(plan.config_dir, o.experiment);
  plan.protocol = loadProtocol(plan.config_dir);
  plan.reference.emplace(plan.config_dir);
  plan.seed = o.seed;
  const int reps = plan.reps = o.reps.value_or(plan.exp.repetitions);
  if (reps < 1) throw ConfigError("--reps must be at least 1");
  checkPlanRequest(o);
  plan.systems = !o.systems.empty() ? o.systems
                 : !plan.exp.default_systems.empty() ? plan.exp.default_systems
                                                     : std::vector<std::string>{"FIX", "IGN", "IMP"};
  if (plan.exp.extrinsic) plan.design = *plan.exp.extrinsic;
  plan.tests = o.extrinsic_reps > 0 ? o.extrinsic_reps : plan.design.tests;
  if ((o.tables || o.table_seed) && !plan.exp.tables)
    throw ConfigError("--tables and --table-seed are for experiments on random tables (a 'tables:' section, e.g. "
                      "random-tables); " + plan.exp.name + " has none");
  if (plan.exp.tables) {
    plan.tables = TablesDesign{o.tables.value_or(plan.exp.tables->count), o.table_seed.value_or(plan.exp.tables->seed)};
    if (plan.tables->count < 1) throw ConfigError("--tables must be at least 1");
    if (plan.tests > 0)
      throw ConfigError("random tables have no extrinsic tests: the scenarios assume the paper's Table 1 "
                        "(leave --extrinsic-reps out)");
    if (!plan.exp.conditions.empty()) plan.conditions_run = plan.exp.conditions;
  }
  if (plan.tests > 0) {
    const RunConfig any = parseRunConfig(effectiveConfig(plan.config_dir, RunRequest{o.experiment, System::IMP, o.seed, o.steps, o.settings}));
    plan.scenarios = !o.scenarios.empty() ? o.scenarios
                     : !plan.design.scenarios.empty() || plan.design.generate ? plan.design.scenarios
                                                                              : listScenarios(plan.config_dir);
    for (const auto& name : plan.scenarios)
      plan.sub_goals[name] = static_cast<int>(loadScenario(plan.config_dir, name, any.world).objects.size());
    if (o.scenarios.empty() && plan.design.generate) {  // drawn here, kept in the plan: nothing is written to config/
      const GenerateDesign& gen = *plan.design.generate;
      for (const ScenarioSpec& spec : designPoints(gen))
        for (int i = 0; i < gen.per_point; ++i) {
          GeneratedScenario g;
          try {
            g = generateScenario(any, spec, gen.seed, i);
          } catch (const std::exception& e) {
            throw ConfigError("extrinsic.generate: " + std::string(e.what()));
          }
          const std::string name = g.scenario.name;
          plan.scenarios.push_back(name);
          plan.sub_goals[name] = spec.sub_goals;
          plan.specs[name] = spec;
          plan.generated[name] = std::move(g.scenario);
        }
    }
    plan.conditions = conditionsOf(plan.design);
    for (const Condition& c : plan.conditions) {  // every combination must make a valid extrinsic config
      std::vector<std::string> settings = o.settings;
      for (const auto& [k, v] : c.settings) settings.push_back(k + "=" + v);
      const RunRequest req{o.experiment, System::IMP, o.seed, o.steps, settings};
      if (plan.generated.count(plan.scenarios.front()))
        extrinsicConfig(plan.config_dir, req, "unchecked", plan.generated.at(plan.scenarios.front()));
      else
        extrinsicConfig(plan.config_dir, req, "unchecked", plan.scenarios.front());
    }
  }
  const std::string prefix = o.run_prefix.empty() ? defaultPrefix() : o.run_prefix;
  auto& runs = plan.runs;
  auto& configs = plan.configs;
  // Random tables: table k of the series replaces the affordances of the world's objects.
  std::vector<ObjectSpec> drawn_for;  // the objects the tables are drawn for
  if (plan.tables) {
    drawn_for = parseRunConfig(effectiveConfig(plan.config_dir, RunRequest{o.experiment, System::IMP, o.seed, o.steps, o.settings}))
                    .world.objects;
    for (int k = 0; k < plan.tables->count; ++k) plan.table_list.push_back(randomTable(plan.tables->seed, k, drawn_for));
  }
  const int n_tables = plan.tables ? plan.tables->count : 1;
  for (int table = 0; table < n_tables; ++table)
  for (const auto& [condition, condition_settings] : plan.conditions_run)
  for (const auto& sys_name : plan.systems) {
    const System sys = parseSystem(sys_name);
    for (int r = 0; r < reps; ++r) {
      std::vector<std::string> settings = o.settings;
      settings.insert(settings.end(), condition_settings.begin(), condition_settings.end());
      RunRequest req{o.experiment, sys, o.seed + r, o.steps, settings};
      YAML::Node node;
      try {
        node = effectiveConfig(plan.config_dir, req);
      } catch (const ConfigError& e) {
        if (condition.empty()) throw;
        throw ConfigError("condition '" + condition + "' of " + plan.exp.name + ": " + e.what());
      }
      std::string run_id = prefix + "-" + plan.exp.name + "-";
      if (plan.tables) {
        const auto objects = parseRunConfig(node).world.objects;
        const auto same = [](const ObjectSpec& a, const ObjectSpec& b) { return a.shape == b.shape && a.colour == b.colour; };
        if (objects.size() != drawn_for.size() || !std::equal(objects.begin(), objects.end(), drawn_for.begin(), same))
          throw ConfigError("condition '" + condition + "' of " + plan.exp.name +
                            " changes world.objects, for which the random tables are drawn (their colours decide which "
                            "entries are 0): a condition may not change the objects' number, shapes or colours");
        char t[16];
        std::snprintf(t, sizeof t, "t%02d-", table);
        run_id += t + condition + (condition.empty() ? "" : "-");
        for (std::size_t i = 0; i < plan.table_list[table].size(); ++i) {
          YAML::Node aff = node["world"]["objects"][i]["affordance"];
          for (int a = 0; a < kNumActions; ++a) aff[a] = plan.table_list[table][i][a];
        }
      }
      run_id += sys_name + "-s" + std::to_string(o.seed + r);
      checkRunId(run_id, plan);
      // ... and the longest of its extrinsic tests' ids (planExtrinsic)
      for (const auto& scenario : plan.scenarios)
        checkRunId(run_id + (plan.conditions.size() > 1 ? "-c" + std::to_string(plan.conditions.size() - 1) : "") + "-" +
                       scenario + "-e" + std::to_string(std::max(0, plan.tests - 1)),
                   plan);
      node["run"]["checkpoint"] = (fs::path(o.log_root) / run_id / "predictors.ckpt").string();
      const bool first = r == 0 && table == 0 && condition == plan.conditions_run.front().first;
      node["run"]["record"] = o.keep_logs == "all" || (o.keep_logs == "first" && first);
      if (plan.design.after_actions > 0) node["run"]["checkpoint_after_actions"] = plan.design.after_actions;
      const RunConfig cfg = parseRunConfig(node);
      if (!configs.count(sys_name)) configs[sys_name] = cfg;
      PlannedRun p;
      p.system = sys_name;
      p.table = plan.tables ? table : -1;
      p.intrinsic_condition = condition;
      for (const auto& ob : cfg.world.objects) p.target.emplace_back(ob.affordance.begin(), ob.affordance.end());
      p.keep_log = o.keep_logs == "all" || (o.keep_logs == "first" && first);
      p.keep_checkpoint = o.keep_checkpoints == "all" || (o.keep_checkpoints == "first" && first);
      p.spec.run_id = run_id;
      p.spec.experiment = plan.exp.name;
      p.spec.system = sys_name;
      p.spec.seed = o.seed + r;
      p.spec.steps = cfg.steps;
      p.spec.config_yaml = emitYaml(node);
      p.spec.processes = runProcesses(/*extrinsic=*/false, p.keep_log);
      p.spec.log_root = o.log_root;
      p.index = runs.size();
      runs.push_back(std::move(p));
    }
  }

  return plan;
}

void refuseUsedLogFolders(const std::vector<PlannedRun>& runs, const std::vector<char>& elsewhere,
                          const std::string& log_root) {
  // The run's folder holds its log and its checkpoint: a run never writes into another's.
  for (const auto& p : runs)
    if ((elsewhere.empty() || !elsewhere[p.index]) && fs::exists(fs::path(log_root) / p.spec.run_id))
      throw ConfigError("the log folder " + (fs::path(log_root) / p.spec.run_id).string() +
                        " exists already: choose another --run-prefix or --log-root");
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& e : v) s += (s.empty() ? "" : " ") + e;
  return s;
}

std::vector<PlannedRun> planExtrinsic(const Plan& plan, const std::vector<RunOutcome>& trained,
                                      const PlanRequest& o, std::vector<std::string>& errors) {
  std::vector<PlannedRun> tests;
  for (const auto& p : plan.runs) {
    const RunOutcome& r = trained[p.index];
    if (!r.ok) continue;  // a failed run is reported as such
    if (r.checkpoint.empty()) {
      errors.push_back("run '" + p.spec.run_id + "' left no checkpoint of its predictors (they could not write it: " +
                       "see their log), so its agent is not tested");
      continue;
    }
    std::string checkpoint = r.checkpoint;
    if (plan.design.after_actions > 0) {
      checkpoint = actionsCheckpoint(r.checkpoint, plan.design.after_actions);
      if (!fs::exists(checkpoint)) {
        errors.push_back("run '" + p.spec.run_id + "' executed fewer than " + std::to_string(plan.design.after_actions) +
                         " actions, so it has no " + checkpoint + " (extrinsic.after_actions): give it more run.steps");
        continue;
      }
    }
    for (std::size_t c = 0; c < plan.conditions.size(); ++c)
      for (std::size_t k = 0; k < plan.scenarios.size(); ++k)
        for (int e = 0; e < plan.tests; ++e) {
          PlannedRun t;
          t.system = p.system;
          t.intrinsic = p.index;
          t.scenario = plan.scenarios[k];
          t.condition = static_cast<int>(c);
          t.rep = e;
          t.keep_log = o.keep_logs == "all" || (o.keep_logs == "first" && p.keep_log && e == 0);
          // Each test its own seed, derived from the intrinsic run's (documented in docs/experiments.md);
          // the conditions share seeds, so they meet the same draws.
          const std::int64_t seed = p.spec.seed * 1'000'000 + static_cast<std::int64_t>(k + 1) * 1000 + e;
          std::vector<std::string> settings = o.settings;
          for (const auto& [key, value] : plan.conditions[c].settings) settings.push_back(key + "=" + value);
          const RunRequest req{o.experiment, parseSystem(p.system), seed, std::nullopt, settings};
          const auto gen = plan.generated.find(t.scenario);
          YAML::Node node = gen != plan.generated.end() ? extrinsicConfig(plan.config_dir, req, checkpoint, gen->second)
                                                        : extrinsicConfig(plan.config_dir, req, checkpoint, t.scenario);
          node["run"]["record"] = t.keep_log;
          t.spec.run_id = p.spec.run_id + (plan.conditions.size() > 1 ? "-c" + std::to_string(c) : "") + "-" +
                          t.scenario + "-e" + std::to_string(e);
          t.spec.experiment = plan.exp.name;
          t.spec.system = p.system;
          t.spec.seed = seed;
          t.spec.steps = node["run"]["steps"].as<std::int64_t>();
          t.spec.config_yaml = emitYaml(node);
          t.spec.extrinsic = true;
          t.spec.processes = runProcesses(/*extrinsic=*/true, t.keep_log);
          t.spec.log_root = o.log_root;
          t.index = tests.size();
          tests.push_back(std::move(t));
        }
  }
  return tests;
}

}  // namespace afford

// afford world truth EXPERIMENT: the physical table's affordances, each (object, action) estimated by trials
// of the hand's primitive on the object alone (processes/environment/table/truth.hpp), with its 95% interval;
// kept per world configuration in --out, so that a second call reads what the first estimated.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "afford/config.hpp"
#include "afford/process_main.hpp"
#include "afford/yaml_reader.hpp"
#include "apps/afford/commands.hpp"
#include "environment/table/truth.hpp"
#include "experiment/design/experiment_file.hpp"
#include "experiment/design/truth_store.hpp"
#include "experiment/run/group.hpp"

namespace afford {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct TruthArgs {
  std::string experiment;
  int trials = 0;
  std::int64_t seed = 1;
  std::vector<std::string> objects, settings;
  std::string out = "logs/truth";
  bool fresh = false;
};

void printTable(const json& rows) {
  std::printf("%-12s", "object");
  for (int a = 0; a < table::kTableActions; ++a) std::printf("  %-20s", table::tableActionName(a));
  std::printf("\n");
  for (const json& row : rows) {
    std::printf("%-12s", row.at("object").get<std::string>().c_str());
    for (int a = 0; a < table::kTableActions; ++a) {
      const json& c = row.at(table::tableActionName(a));
      char cell[64];
      std::snprintf(cell, sizeof cell, "%.2f [%.2f, %.2f]", c.at("rate").get<double>(), c.at("low").get<double>(),
                    c.at("high").get<double>());
      std::printf("  %-20s", cell);
    }
    std::printf("\n");
  }
}

int runTruth(const TruthArgs& a, const FrontDoor& door) {
  const YAML::Node node = effectiveConfig(door.config_dir, RunRequest{a.experiment, System::IMP, 1, std::nullopt, a.settings});
  const RunConfig cfg = parseRunConfig(node);
  if (cfg.world.kind != WorldKind::Table)
    throw ConfigError("experiment '" + a.experiment + "' is of the paper's world (world.kind: grid), whose "
                      "affordances its file gives (world.objects); `afford world truth` estimates a physical "
                      "table's (world.kind: table, e.g. `afford world truth table`)");
  const table::TableWorldConfig& tw = cfg.table;
  std::vector<int> objects;
  for (const std::string& name : a.objects) {
    int found = -1;
    for (std::size_t i = 0; i < tw.spec.objects.size(); ++i)
      if (tw.spec.objects[i].name == name) found = static_cast<int>(i);
    if (found < 0) {
      std::vector<std::string> names;
      std::string known;
      for (const auto& o : tw.spec.objects) {
        names.push_back(o.name);
        known += (known.empty() ? "" : ", ") + o.name;
      }
      const std::string near = closestName(name, names);
      throw ConfigError("--object '" + name + "': experiment '" + a.experiment + "' has no such object" +
                        (near.empty() ? "" : " (did you mean '" + near + "'?)") + "; it has " + known);
    }
    objects.push_back(found);
  }
  if (objects.empty())
    for (std::size_t i = 0; i < tw.spec.objects.size(); ++i) objects.push_back(static_cast<int>(i));

  installStopHandlers();  // Ctrl-C: stop between cells, nothing half-written left
  bool told = false;
  const StoredTruth t = storedTruth(
      node, cfg, TruthRequest{a.experiment, a.seed, a.trials, objects, a.out, a.fresh, codeFingerprint()},
      [&](const std::string& w) { door.log->warn("{}", w); },
      [&](int object, int action) {
        if (!told) {
          std::fprintf(stderr, "estimating %zu object(s) x %d actions, %d trials each (seed %lld)\n", objects.size(),
                       table::kTableActions, a.trials > 0 ? a.trials : tw.truth_trials, static_cast<long long>(a.seed));
          told = true;
        }
        std::fprintf(stderr, "  %s, %s\n", tw.spec.objects[static_cast<std::size_t>(object)].name.c_str(),
                     table::tableActionName(action));
        if (stopRequested()) throw std::runtime_error("interrupted: nothing written");
      });
  printTable(t.rows);
  if (t.estimated)
    std::printf("wrote %s\n", t.file.c_str());
  else
    std::printf("read from %s (estimated before: --fresh estimates again)\n", t.file.c_str());
  return 0;
}

}  // namespace

Command worldCommand(CLI::App& app, const FrontDoor& door) {
  auto a = std::make_shared<TruthArgs>();
  auto* world = app.add_subcommand("world", "what an experiment's world is: `afford world truth` (a physical table)");
  world->require_subcommand(1);
  auto* truth = world->add_subcommand(
      "truth", "a physical table's affordances: each (object, action) estimated by trials of the hand's primitive "
               "on the object alone, from drawn poses, with its 95% interval; kept per world configuration");
  truth->add_option("experiment", a->experiment, "a table experiment (world.kind: table), e.g. table")->required();
  truth->add_option("--trials", a->trials, "trials of each (object, action) (default: table.truth.trials)")
      ->check(CLI::PositiveNumber);
  truth->add_option("--seed", a->seed, "the trials' seed")->capture_default_str();
  truth->add_option("--object", a->objects, "only this object (repeatable; default: every one)");
  truth->add_option("--set", a->settings, "override a config value (repeatable)");
  truth->add_option("--out", a->out, "the folder of the tables (each named by its experiment and configuration)")
      ->capture_default_str();
  truth->add_flag("--fresh", a->fresh, "estimate again though --out has the table");
  return {world, [a, &door] { return runTruth(*a, door); }};
}

}  // namespace afford

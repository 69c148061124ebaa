// Experiment files and what they make (docs/experiments.md): the effective
// configuration of one run is config/defaults.yaml, overlaid by the
// experiment file's keys (along its `extends` chain), by its systems.<S>
// block, and by the command line's settings; an error about a key names the
// file and block that gave it. Also the scenario files of config/scenarios.
// The runs' configuration itself (RunConfig) is common's (afford/config.hpp):
// every process parses it; this is the experiment engine's alone.
#pragma once
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "afford/config.hpp"

namespace afford {

// The systems `given` names, each a system, `all`, or a comma-separated list of them (FIX,IMP), in the
// order given, each once; throws ConfigError naming `option` and the unknown name.
std::vector<std::string> parseSystems(const std::vector<std::string>& given, const std::string& option);

// config/scenarios/<name>.yaml, parsed and validated.
Scenario loadScenario(const std::string& config_dir, const std::string& name, const RunConfig& run);
// The scenarios of config/scenarios of one world (a file's `world:`, the grid if it says none).
std::vector<std::string> listScenarios(const std::string& config_dir, WorldKind world = WorldKind::Grid);

// Experiment files (config/experiments/<name>.yaml): the effective config of one
// run is defaults.yaml, overlaid by the experiment's keys, overlaid by
// systems.<S>, overlaid by command-line settings.
// The extrinsic tests an experiment file declares (`extrinsic:`): which
// scenarios, how many tests per trained agent, and the planner settings to
// compare (`vary`: every combination is a condition, tested from every agent).
// Generated scenarios (`extrinsic.generate`, issue 12): per_point scenarios for
// every point (k sub-goals on n objects, m of them two-action), drawn from seed.
struct GenerateDesign {
  std::vector<int> sub_goals;   // k of each point
  std::vector<int> objects;     // n of each point; empty: n = k (every object has a sub-goal)
  int multi_step = 0;           // m of each point (at most k)
  bool all_multi_step = false;  // m = k
  int per_point = 1;
  std::int64_t seed = 1;
};

struct ExtrinsicDesign {
  std::vector<std::string> scenarios;
  std::optional<GenerateDesign> generate;   // scenarios drawn for the tests, beside `scenarios`
  int tests = 0;                            // per trained agent, condition and scenario
  std::int64_t after_actions = 0;           // test the weights saved after this many actions (0: the final ones)
  std::vector<std::pair<std::string, std::vector<std::string>>> vary;  // config key -> values (YAML text)
  std::string analysis;                     // "", utility, forward-models, search-reduction
};

// Random affordance tables (an experiment file's `tables:`, issue 11): the
// experiment is run on `count` tables drawn from `seed` (afford/tables.hpp),
// each replacing the affordances of the world's objects.
struct TablesDesign {
  int count = 0;
  std::int64_t seed = 0;
};

struct ExperimentFile {
  std::string name;
  std::string file;                        // an experiment file outside the config folder (--config FILE), else ""
  std::string description;
  int repetitions = 1;
  std::vector<std::string> default_systems;  // systems run when none is named (empty: all three)
  YAML::Node overlay;                      // keys merged over the defaults
  YAML::Node systems;                      // map System -> overlay
  std::optional<ExtrinsicDesign> extrinsic;
  std::optional<TablesDesign> tables;
  // Intrinsic conditions compared (`conditions:`, with `tables:`): name -> settings ("key.path=value"), in file order.
  std::vector<std::pair<std::string, std::vector<std::string>>> conditions;
  // The `extrinsic:` and `tables:` sections as written, merged along `extends` (the designs are parsed from them).
  YAML::Node extrinsic_node, tables_node;
  // Where each config key it sets was set (dotted key -> "experiment file F" or "... F, block systems.IMP"):
  // an error about a key names the file and block that gave it.
  std::map<std::string, std::string> sources;
  std::map<std::string, std::map<std::string, std::string>> system_sources;  // system -> key -> where
};

std::vector<std::string> listExperiments(const std::string& config_dir);
// `name`: an experiment of <config_dir>/experiments, or the path of an
// experiment file anywhere (it has a '/' or ends in .yaml; its name is the
// file's stem). `extends:` names an experiment of the config folder, or a
// path relative to the extending file's folder; the file then starts from
// the whole of that experiment and changes what it states: maps (the config
// keys, `systems`, `extrinsic`, `tables`) are merged to any depth, lists
// replaced; `extrinsic` stating one source of tests (`scenarios` or
// `generate`) drops the extended design's other; `conditions` are replaced
// as a whole;
// `extrinsic: none` and `tables: none` drop the extended experiment's.
ExperimentFile loadExperiment(const std::string& config_dir, const std::string& name);
bool isExperimentPath(const std::string& name);

// A YAML file a user names on the command line (`what`: how errors name it, e.g. "--plan"), read only if it
// is a regular file of at most max_bytes: a FIFO would wait for a writer, a huge file hold the memory.
YAML::Node loadGivenYaml(const std::string& file, const std::string& what, std::uintmax_t max_bytes = 1u << 20);

struct RunRequest {
  std::string experiment;
  System system = System::IMP;
  std::int64_t seed = 0;
  std::optional<std::int64_t> steps;
  std::vector<std::string> settings;       // "key.path=value"
};

// The merged YAML tree of one run (validated with parseRunConfig before returning).
YAML::Node effectiveConfig(const std::string& config_dir, const RunRequest& request);

// The effective configuration of one extrinsic test: the experiment's
// configuration for `request` (system, seed, settings), in the extrinsic phase,
// with the trained predictors of `checkpoint` and config/scenarios/<scenario>.yaml.
// run.steps is the planner's budget. Validated before returning.
YAML::Node extrinsicConfig(const std::string& config_dir, const RunRequest& request, const std::string& checkpoint,
                           const std::string& scenario);

// The same with a scenario given whole (a generated one), inlined as it is.
YAML::Node extrinsicConfig(const std::string& config_dir, const RunRequest& request, const std::string& checkpoint,
                           const Scenario& scenario);
// A scenario as its file would say it (parseScenario reads it back equal).
YAML::Node scenarioNode(const Scenario& scenario);

// Overlay `over` onto `base` (maps merged recursively, everything else replaced).
void mergeInto(YAML::Node base, const YAML::Node& over);

}  // namespace afford

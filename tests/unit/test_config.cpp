#include <gtest/gtest.h>

#include <filesystem>
#include <cstdlib>
#include <functional>
#include <regex>
#include <set>
#include <fstream>
#include <iterator>
#include <sstream>

#include "afford/config.hpp"
#include "afford/migrations.hpp"
#include "afford/yaml_reader.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

const std::string kConfigDir = std::string(AFFORD_SOURCE_DIR) + "/config";

// The message of the ConfigError thrown by parsing `root`, or "" if none.
std::string errorOf(const YAML::Node& root) {
  try {
    parseRunConfig(root);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

YAML::Node baseTree() { return effectiveConfig(kConfigDir, RunRequest{"base", System::IMP, 1, std::nullopt, {}}); }

// The error of loading an experiment file "trial" with this text from a copy
// of the config folder at `dir` ("" if it loads).
std::string experimentFileError(const std::string& dir, const std::string& text) {
  std::ofstream(dir + "/experiments/trial.yaml") << text;
  try {
    loadExperiment(dir, "trial");
  } catch (const ConfigError& e) {
    return std::string(e.what());
  }
  return std::string();
}

TEST(Config, EveryShippedExperimentParsesForEverySystem) {
  for (const auto& name : listExperiments(kConfigDir))
    for (System s : {System::FIX, System::IGN, System::IMP}) {
      const RunConfig c = test::shippedConfig(name, s);
      if (c.world.kind == WorldKind::Table) {  // a physical table's objects are its own, named in the world's
        EXPECT_GE(c.table.spec.objects.size(), 5u) << name;
        ASSERT_EQ(c.world.objects.size(), c.table.spec.objects.size()) << name;
        for (std::size_t i = 0; i < c.world.objects.size(); ++i)
          EXPECT_EQ(c.world.objects[i].name, c.table.spec.objects[i].name) << name;
        EXPECT_EQ(c.world.size_px, c.table.spec.camera.width) << name;
        EXPECT_EQ(c.world.rows(), c.table.spec.camera.height) << name;
        continue;
      }
      const bool large = name == "large-world" || name == "world-size";
      EXPECT_EQ(c.world.objects.size(), large ? 20u : 9u) << name;  // the paper's nine, or twenty
      EXPECT_EQ(c.system, s);
    }
}

TEST(Config, PaperValuesReachTheRunConfig) {
  const RunConfig fix = test::shippedConfig("base", System::FIX);
  const RunConfig ign = test::shippedConfig("base", System::IGN);
  const RunConfig imp = test::shippedConfig("base", System::IMP);
  EXPECT_DOUBLE_EQ(fix.predictors.affordance_learning_rate, 0.002);
  EXPECT_DOUBLE_EQ(ign.predictors.affordance_learning_rate, 0.01);
  EXPECT_DOUBLE_EQ(ign.motivation.leak, 0.3);
  EXPECT_DOUBLE_EQ(imp.motivation.leak, 0.1);
  EXPECT_EQ(imp.steps, 6000);
  EXPECT_EQ(test::shippedConfig("late1").steps, 10000);
  EXPECT_DOUBLE_EQ(test::shippedConfig("stochastic").predictors.affordance_learning_rate, 0.001);
  EXPECT_EQ(test::shippedConfig("late1").world.objects[6].appears_at, 2000);
}

TEST(Config, MissingKeyIsNamed) {
  YAML::Node root = baseTree();
  root["eye"].remove("saliency_noise");
  const std::string e = errorOf(root);
  EXPECT_NE(e.find("'eye.saliency_noise'"), std::string::npos) << e;
  EXPECT_NE(e.find("missing"), std::string::npos) << e;
}

TEST(Config, WrongTypeIsNamed) {
  YAML::Node root = baseTree();
  root["predictors"]["affordance"]["learning_rate"] = "fast";
  const std::string e = errorOf(root);
  EXPECT_NE(e.find("'predictors.affordance.learning_rate'"), std::string::npos) << e;
  EXPECT_NE(e.find("expected a number"), std::string::npos) << e;
}

TEST(Config, OutOfRangeValueIsNamed) {
  YAML::Node root = baseTree();
  root["eye"]["image_change_threshold"] = 5.0;
  const std::string e = errorOf(root);
  EXPECT_NE(e.find("'eye.image_change_threshold'"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
}

// The table's range is [min, max]: a reversed or empty one is named, before any object is checked against it.
TEST(Config, AReversedTableRangeIsNamed) {
  for (const auto& [lo, hi] : {std::pair{0.9, 0.1}, std::pair{0.5, 0.5}}) {
    YAML::Node root = baseTree();
    root["world"]["table"][0] = lo;
    root["world"]["table"][1] = hi;
    const std::string e = errorOf(root);
    EXPECT_NE(e.find("'world.table'"), std::string::npos) << e;
    EXPECT_NE(e.find("min < max"), std::string::npos) << e;
  }
}

TEST(Config, ObjectOutsideTheTableIsNamedWithItsIndex) {
  YAML::Node root = baseTree();
  root["world"]["objects"][3]["position"][0] = 0.95;
  const std::string e = errorOf(root);
  EXPECT_NE(e.find("'world.objects[3].position[0]'"), std::string::npos) << e;
}

// Objects present together may not overlap or touch: the eye would see one blob.
TEST(Config, ObjectsThatTouchAreNamedWithBoth) {
  YAML::Node root = baseTree();
  ASSERT_EQ(errorOf(root), "");
  const double x = root["world"]["objects"][0]["position"][0].as<double>();
  const double y = root["world"]["objects"][0]["position"][1].as<double>();
  root["world"]["objects"][4]["position"][0] = x + 0.05;  // 7.5 px: the 15-px shapes overlap
  root["world"]["objects"][4]["position"][1] = y;
  std::string e = errorOf(root);
  EXPECT_NE(e.find("'world.objects[4].position'"), std::string::npos) << e;
  EXPECT_NE(e.find("world.objects[0]"), std::string::npos) << e;
  root["world"]["objects"][4]["position"][0] = x + 0.13;  // 19.5 px between centres: apart
  e = errorOf(root);
  EXPECT_EQ(e, "");
  root["world"]["objects"][4]["appears_at"] = 100;  // a late object is placed where it is free when it comes
  root["world"]["objects"][4]["position"][0] = x;
  EXPECT_EQ(errorOf(root), "");
}

// The environment acts by look, so two objects of one look need one affordance row.
TEST(Config, OneLookWithTwoAffordanceRowsIsNamed) {
  YAML::Node root = baseTree();
  YAML::Node copy = YAML::Clone(root["world"]["objects"][0]);
  copy["name"] = "second red square";
  copy["position"][0] = 0.2;
  copy["position"][1] = 0.8;
  copy["appears_at"] = 50;
  root["world"]["objects"].push_back(copy);
  ASSERT_EQ(errorOf(root), "");
  root["world"]["objects"][9]["affordance"][0] = 1.0 - root["world"]["objects"][0]["affordance"][0].as<double>();
  const std::string e = errorOf(root);
  EXPECT_NE(e.find("'world.objects[9].affordance'"), std::string::npos) << e;
  EXPECT_NE(e.find("world.objects[0]"), std::string::npos) << e;
}

TEST(Config, UnknownKeyIsRejected) {
  YAML::Node root = baseTree();
  root["motivation"]["leek"] = 0.2;
  const std::string e = errorOf(root);
  EXPECT_NE(e.find("'motivation.leek'"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key"), std::string::npos) << e;
}

TEST(Config, UnknownChoiceListsTheOptions) {
  YAML::Node root = baseTree();
  root["motivation"]["imp_threshold_input"] = "guess";
  const std::string e = errorOf(root);
  EXPECT_NE(e.find("signal, observed_change"), std::string::npos) << e;
}

TEST(Config, UnknownExperimentIsRejectedWithTheKnownOnes) {
  try {
    loadExperiment(kConfigDir, "nosuch");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown experiment \"nosuch\""), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("base"), std::string::npos);
  }
}

TEST(Config, SettingsOverrideAndAreValidated) {
  EXPECT_DOUBLE_EQ(test::shippedConfig("base", System::IMP, 1, {"motivation.leak=0.25"}).motivation.leak, 0.25);
  try {
    test::shippedConfig("base", System::IMP, 1, {"motivation.nope=1"});
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'motivation.nope'"), std::string::npos) << e.what();
  }
  try {
    test::shippedConfig("base", System::IMP, 1, {"eye.focus_side=20"});
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'eye.focus_side'"), std::string::npos) << e.what();
  }
}

TEST(Config, EmittedYamlParsesToTheSameConfig) {
  const YAML::Node root = baseTree();
  const RunConfig a = parseRunConfig(root);
  const RunConfig b = parseRunConfigText(emitYaml(root));
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_DOUBLE_EQ(a.predictors.what_effect_learning_rate, b.predictors.what_effect_learning_rate);
  EXPECT_EQ(a.world.objects[8].name, b.world.objects[8].name);
}

// Experiment files on random tables (issue 11): `conditions:` compares settings on them, and nothing else.
TEST(Config, ConditionsNeedTablesAndNamesFitForRunIds) {
  const std::string dir = test::tempDir("config-conditions");
  std::filesystem::copy(kConfigDir, dir, std::filesystem::copy_options::recursive);
  const auto errorOfFile = [&](const std::string& text) { return experimentFileError(dir, text); };
  EXPECT_NE(errorOfFile("extends: base\nconditions: {a: [motivation.leak=0.2]}\n").find("config key 'conditions': compares "
                                                                                             "conditions on random tables"),
            std::string::npos);
  EXPECT_NE(errorOfFile("extends: base\ntables: {count: 2, seed: 1}\nconditions: {\"a b\": []}\n").find("config key 'conditions.a b'"),
            std::string::npos);
  EXPECT_NE(errorOfFile("extends: base\ntables: {count: 2, seed: 1}\nconditions: {a: [motivation]}\n").find("key.path=value"),
            std::string::npos);
  EXPECT_NE(errorOfFile("extends: base\ntables: {count: 0, seed: 1}\n").find("config key 'tables.count'"), std::string::npos);
  const ExperimentFile e = loadExperiment(kConfigDir, "random-tables");
  ASSERT_TRUE(e.tables);
  EXPECT_EQ(e.tables->count, 20);
  ASSERT_EQ(e.conditions.size(), 2u);
  EXPECT_EQ(e.conditions[0].first, "paper");
  EXPECT_EQ(e.conditions[1].second, test::kMemoryOptions);
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

// Designs of generated scenarios (issue 12): the points, and errors naming the key.
TEST(Config, GeneratedDesignsNameTheirPointsAndTheirErrors) {
  const ExperimentFile attention = loadExperiment(std::string(AFFORD_SOURCE_DIR) + "/config", "attention");
  ASSERT_TRUE(attention.extrinsic && attention.extrinsic->generate);
  EXPECT_TRUE(attention.extrinsic->scenarios.empty());
  EXPECT_EQ(attention.extrinsic->generate->sub_goals.size(), 10u);
  EXPECT_TRUE(attention.extrinsic->generate->objects.empty());
  const std::string dir = test::tempDir("config-generate");
  std::filesystem::copy(std::string(AFFORD_SOURCE_DIR) + "/config", dir, std::filesystem::copy_options::recursive);
  const auto errorOfFile = [&](const std::string& text) { return experimentFileError(dir, text); };
  EXPECT_EQ(errorOfFile("extends: base\nextrinsic: {generate: {sub_goals: [2, 3], multi_step: all}}\n"), "");
  EXPECT_NE(errorOfFile("extends: base\nextrinsic: {generate: {sub_goals: [2, x]}}\n").find("extrinsic.generate.sub_goals[1]"),
            std::string::npos);
  EXPECT_NE(errorOfFile("extends: base\nextrinsic: {generate: {sub_goals: 5, objects: [4]}}\n").find("extrinsic.generate.objects"),
            std::string::npos);
  EXPECT_NE(errorOfFile("extends: base\nextrinsic: {generate: {sub_goals: 2, multi_step: 3}}\n").find("extrinsic.generate.multi_step"),
            std::string::npos);
  EXPECT_NE(errorOfFile("extends: base\nextrinsic: {generate: {sub_goals: 2, typo: 1}}\n").find("extrinsic.generate.typo"),
            std::string::npos);
  EXPECT_EQ(errorOfFile("extends: base\nextrinsic: {tests: 1}\n"), "");  // base's five scenarios, once each
  EXPECT_NE(errorOfFile("extrinsic: {tests: 1}\n").find("extrinsic.scenarios"), std::string::npos);
}

// A scenario written out by scenarioNode reads back as it was.
TEST(Config, AScenarioNodeReadsBackEqual) {
  const RunConfig c = test::shippedConfig();
  Scenario s;
  s.name = "round-trip";
  s.objects.push_back({Shape::Circle, {Colour::Blue, 0.31234567890123, 0.7}, {Colour::Green, 0.55, 0.25}, 1, 2, "", -1});
  const Scenario back = parseScenario(scenarioNode(s), "", c.world);
  ASSERT_EQ(back.objects.size(), 1u);
  EXPECT_EQ(back.name, "round-trip");
  EXPECT_EQ(back.objects[0].initial.x, 0.31234567890123);
  EXPECT_EQ(back.objects[0].goal.colour, Colour::Green);
  EXPECT_EQ(back.objects[0].actions, 2);
}

TEST(Systems, ListsAndAllAreTakenInOrderOnceAndAnUnknownOneIsNamed) {
  EXPECT_EQ(parseSystems({"FIX,IMP"}, "--system"), (std::vector<std::string>{"FIX", "IMP"}));
  EXPECT_EQ(parseSystems({"IMP", "all"}, "--system"), (std::vector<std::string>{"IMP", "FIX", "IGN"}));
  EXPECT_EQ(parseSystems({"IGN,IGN"}, "--system"), (std::vector<std::string>{"IGN"}));
  try {
    parseSystems({"FIX,IMPP"}, "--system");
    ADD_FAILURE() << "IMPP was taken";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--system: unknown system \"IMPP\" in \"FIX,IMPP\""), std::string::npos) << e.what();
  }
  EXPECT_THROW(parseSystems({""}, "--system"), ConfigError);
}

// Every shipped experiment as loaded (extends resolved): its design, written out. The record
// (tests/data/experiments.txt) is what the reproduction runs; a change to it must be meant.
// AFFORD_UPDATE_RECORD=1 writes it anew.
std::string describeExperiment(const ExperimentFile& e) {
  std::ostringstream o;
  const auto list = [](const std::vector<std::string>& xs) {
    std::string s;
    for (const auto& x : xs) s += (s.empty() ? "" : ", ") + x;
    return "[" + s + "]";
  };
  o << "== " << e.name << "\ndescription: " << e.description << "\nrepetitions: " << e.repetitions
    << "\ndefault_systems: " << list(e.default_systems) << "\noverlay:\n" << emitYaml(e.overlay)
    << "\nsystems:\n" << (e.systems.IsDefined() && !e.systems.IsNull() ? emitYaml(e.systems) : "~") << "\n";
  if (e.extrinsic) {
    const ExtrinsicDesign& d = *e.extrinsic;
    o << "extrinsic: scenarios " << list(d.scenarios) << ", tests " << d.tests << ", after_actions " << d.after_actions
      << ", analysis '" << d.analysis << "'\n";
    if (d.generate) {
      std::vector<std::string> k, n;
      for (int x : d.generate->sub_goals) k.push_back(std::to_string(x));
      for (int x : d.generate->objects) n.push_back(std::to_string(x));
      o << "  generate: sub_goals " << list(k) << ", objects " << list(n) << ", multi_step " << d.generate->multi_step
        << (d.generate->all_multi_step ? " (all)" : "") << ", per_point " << d.generate->per_point << ", seed "
        << d.generate->seed << "\n";
    }
    for (const auto& [key, values] : d.vary) o << "  vary " << key << ": " << list(values) << "\n";
  } else {
    o << "extrinsic: none\n";
  }
  if (e.tables) o << "tables: " << e.tables->count << " from seed " << e.tables->seed << "\n";
  for (const auto& [name, settings] : e.conditions) o << "condition " << name << ": " << list(settings) << "\n";
  return o.str();
}

TEST(Experiments, EveryShippedExperimentLoadsAsRecorded) {
  const std::string dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  std::string all;
  for (const std::string& name : listExperiments(dir)) all += describeExperiment(loadExperiment(dir, name));
  const std::string record = std::string(AFFORD_SOURCE_DIR) + "/tests/data/experiments.txt";
  if (const char* update = std::getenv("AFFORD_UPDATE_RECORD"); update && std::string(update) == "1") {
    std::ofstream(record) << all;
    GTEST_SKIP() << "wrote " << record;
  }
  std::ifstream in(record);
  const std::string recorded((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(all, recorded) << "an experiment loads otherwise than " << record
                           << " records (AFFORD_UPDATE_RECORD=1 writes it anew, if that is meant)";
}

TEST(Experiments, ExtendsTakesTheWholeExperimentAndAFileChangesOnlyWhatItStates) {
  const std::string config = std::string(AFFORD_SOURCE_DIR) + "/config";
  const std::string dir = test::tempDir("extends");
  const auto load = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + "/" + name + ".yaml") << text;
    return loadExperiment(config, dir + "/" + name + ".yaml");
  };
  const ExperimentFile attention = loadExperiment(config, "attention");
  // A new seed for the generated scenarios: the rest of attention's design and its systems stay.
  const ExperimentFile seeded = load("seeded", "extends: attention\nextrinsic: {generate: {seed: 7}}\n");
  ASSERT_TRUE(seeded.extrinsic && seeded.extrinsic->generate);
  EXPECT_EQ(seeded.extrinsic->generate->seed, 7);
  EXPECT_EQ(seeded.extrinsic->generate->sub_goals, attention.extrinsic->generate->sub_goals);
  EXPECT_EQ(seeded.extrinsic->generate->per_point, attention.extrinsic->generate->per_point);
  EXPECT_EQ(seeded.extrinsic->tests, attention.extrinsic->tests);
  EXPECT_EQ(seeded.extrinsic->vary, attention.extrinsic->vary);
  EXPECT_EQ(seeded.default_systems, attention.default_systems);
  EXPECT_EQ(emitYaml(seeded.overlay), emitYaml(attention.overlay));
  // ... to any depth: a file extending that file, changing a world key, keeps the seed.
  const ExperimentFile deeper = load("deeper", "extends: seeded.yaml\nplanner: {budget: 99}\n");
  EXPECT_EQ(deeper.extrinsic->generate->seed, 7);
  EXPECT_EQ(deeper.overlay["planner"]["budget"].as<int>(), 99);
  EXPECT_EQ(deeper.overlay["planner"]["max_attempts"].as<std::string>(),
            attention.overlay["planner"]["max_attempts"].as<std::string>());
  // Stating the tests' source replaces the extended one; `none` drops the design.
  const ExperimentFile listed = load("listed", "extends: attention\nextrinsic: {scenarios: [scenario2]}\n");
  EXPECT_FALSE(listed.extrinsic->generate);
  EXPECT_EQ(listed.extrinsic->scenarios, std::vector<std::string>{"scenario2"});
  EXPECT_EQ(listed.extrinsic->vary, attention.extrinsic->vary);
  EXPECT_FALSE(load("none", "extends: attention\nextrinsic: none\n").extrinsic);
  // Random tables: another series, the same count and conditions.
  const ExperimentFile tables = load("tables", "extends: random-tables\ntables: {seed: 9}\n");
  ASSERT_TRUE(tables.tables);
  EXPECT_EQ(tables.tables->seed, 9);
  EXPECT_EQ(tables.tables->count, loadExperiment(config, "random-tables").tables->count);
  EXPECT_EQ(tables.conditions, loadExperiment(config, "random-tables").conditions);
  try {
    load("bad", "extends: attention\nextrinsic: [scenario1]\n");
    ADD_FAILURE() << "a list for extrinsic was taken";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("extrinsic"), std::string::npos) << e.what();
  }
}

// Each key is declared once (common/src/config_keys.hpp): config/defaults.yaml
// gives exactly the keys declared to come from it, and no key is declared twice.
TEST(Configuration, DefaultsYamlGivesExactlyTheKeysDeclaredToComeFromIt) {
  std::set<std::string> keys;
  std::function<void(const YAML::Node&, const std::string&)> leaves = [&](const YAML::Node& n, const std::string& path) {
    if (!n.IsMap()) {
      keys.insert(path);
      return;
    }
    for (const auto& kv : n) leaves(kv.second, path.empty() ? kv.first.Scalar() : path + "." + kv.first.Scalar());
  };
  leaves(YAML::LoadFile(std::string(AFFORD_SOURCE_DIR) + "/config/defaults.yaml"), "");
  std::set<std::string> declared, from_defaults;
  for (const KeyInfo& k : configKeys()) {
    EXPECT_TRUE(declared.insert(k.key).second) << "config key '" << k.key << "' is declared twice";
    EXPECT_FALSE(k.meaning.empty()) << "config key '" << k.key << "' has no meaning";
    EXPECT_FALSE(k.type.empty()) << "config key '" << k.key << "' has no type";
    if (k.origin == KeyInfo::Origin::Defaults) from_defaults.insert(k.key);
  }
  for (const std::string& k : keys)
    EXPECT_TRUE(from_defaults.count(k)) << "config/defaults.yaml has '" << k << "', which is not declared as a default";
  for (const std::string& k : from_defaults)
    EXPECT_TRUE(keys.count(k)) << "config key '" << k << "' is declared as a default but config/defaults.yaml lacks it";
  EXPECT_GT(keys.size(), 80u);
  EXPECT_GT(declared.size(), keys.size());  // and the runner's and the experiments' keys
}

// The tables of keys in docs/configuration.md are what the declaration and
// defaults.yaml give (`afford config --keys`): every key, its type and range,
// its default and source, its meaning.
TEST(Configuration, TheTablesOfKeysInTheDocsAreThoseTheDeclarationGives) {
  std::ifstream doc(std::string(AFFORD_SOURCE_DIR) + "/docs/configuration.md");
  const std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  const std::string begin = "<!-- the keys: `afford config --keys` -->\n", end = "<!-- end of the keys -->";
  const auto from = text.find(begin), to = text.find(end);
  ASSERT_NE(from, std::string::npos) << "docs/configuration.md has no " << begin;
  ASSERT_NE(to, std::string::npos) << "docs/configuration.md has no " << end;
  const std::string documented = text.substr(from + begin.size(), to - from - begin.size());
  const test::CommandResult keys = test::runAfford("config --keys");
  ASSERT_EQ(keys.exit_code, 0) << keys.output;
  EXPECT_EQ(documented, keys.output + "\n") << "regenerate the tables with scripts/docs-keys.sh";
}

// Every default value has its source: the comment beside it in defaults.yaml begins with it.
TEST(Configuration, EveryDefaultNamesItsSource) {
  const std::string md = test::runAfford("config --keys").output;
  std::istringstream rows(md.substr(0, md.find("\n\n")));
  int checked = 0;
  for (std::string line; std::getline(rows, line);) {
    if (line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;  // key, type, default, source, meaning
    for (std::size_t at = 2, bar; (bar = line.find(" | ", at)) != std::string::npos; at = bar + 3)
      cells.push_back(line.substr(at, bar - at));
    ASSERT_GE(cells.size(), 4u) << line;
    if (cells[2] == "set by the runner" || cells[2] == "per experiment") continue;
    ++checked;
    const std::string& s = cells[3];
    EXPECT_TRUE(s.rfind("paper", 0) == 0 || s.rfind("authors' code", 0) == 0 || s.rfind("ours", 0) == 0)
        << cells[0] << ": its source in defaults.yaml is '" << s
        << "' (begin its comment with paper ..., authors' code or ours)";
  }
  EXPECT_GT(checked, 50);
}

}  // namespace
}  // namespace afford

namespace afford {
namespace {

TEST(Typos, ASwapOfTwoLettersIsOneEditAndTheLongerNameSetsHowManyMayDiffer) {
  EXPECT_EQ(editDistance("stpes", "steps"), 1u);
  EXPECT_EQ(editDistance("sead", "seed"), 1u);
  EXPECT_EQ(editDistance("colr", "colour"), 2u);
  EXPECT_EQ(editDistance("abc", "abc"), 0u);
  EXPECT_EQ(editDistance("", "abc"), 3u);
  EXPECT_EQ(closestName("stpes", {"seed", "steps"}), "steps");
  EXPECT_EQ(closestName("cuont", {"count", "seed"}), "count");
  EXPECT_EQ(closestName("colr", {"colour", "shape"}), "colour");
  EXPECT_EQ(closestName("xyz", {"colour", "shape"}), "");
}

// A configuration as an earlier release wrote it: the table says what it lacks or spells otherwise.
TEST(Migrations, AKeyAddedSinceAReleaseTakesTheValueTheTableGivesInAConfigurationOfBefore) {
  YAML::Node old = baseTree();
  old["goals"].remove("held");  // as before goals.held
  EXPECT_NE(errorOf(old).find("goals.held"), std::string::npos) << "taken with no table entry";
  ConfigMigrations m;
  m.added.push_back({"goals.held", "0.2.0", YAML::Load("64")});
  YAML::Node upgraded = YAML::Clone(old);
  const std::vector<std::string> said = upgradeConfig(upgraded, m);
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0], "goals.held: absent (written before 0.2.0), read as 64");
  EXPECT_EQ(parseRunConfig(upgraded).goals.held, 64);
  // A configuration that has the key keeps its own value.
  YAML::Node now = baseTree();
  EXPECT_TRUE(upgradeConfig(now, m).empty());
  EXPECT_EQ(parseRunConfig(now).goals.held, parseRunConfig(baseTree()).goals.held);
}

TEST(Migrations, AConfigurationOfThisBuildReadsAsTheReleaseBeforeTheKeyWroteIt) {
  // What an experiment planned by that release keeps (its runs' fingerprints) is compared with this.
  YAML::Node then = baseTree();
  then["goals"].remove("held");
  const std::string old_text = emitYaml(then), now_text = emitYaml(baseTree());
  ConfigMigrations m;
  m.added.push_back({"goals.held", "0.3.0", YAML::Clone(baseTree()["goals"]["held"])});
  EXPECT_EQ(configAsWrittenBy(now_text, "0.2.0+abc", m), old_text);
  EXPECT_EQ(configAsWrittenBy(now_text, "0.3.0", m), now_text);
  // Another value than the one it stands for: no configuration of before had it.
  YAML::Node other = baseTree();
  other["goals"]["held"] = 8;
  EXPECT_EQ(configAsWrittenBy(emitYaml(other), "0.2.0", m), emitYaml(other));
  EXPECT_TRUE(releaseBefore("0.9.0", "0.10.0"));
  EXPECT_FALSE(releaseBefore("0.2.0+abc", "0.2.0"));
}

TEST(Migrations, ARenamedKeyIsReadUnderItsNewNameAndSaidSo) {
  YAML::Node old = baseTree();
  const double leak = old["motivation"]["leak"].as<double>();
  old["motivation"]["leak_rate"] = 0.25;  // as if it had been spelt so before
  old["motivation"].remove("leak");
  ConfigMigrations m;
  m.renamed.push_back({"motivation.leak_rate", "motivation.leak", "0.2.0"});
  const std::vector<std::string> said = upgradeConfig(old, m);
  ASSERT_EQ(said.size(), 1u) << leak;
  EXPECT_NE(said[0].find("motivation.leak_rate is spelt motivation.leak since 0.2.0"), std::string::npos);
  EXPECT_DOUBLE_EQ(parseRunConfig(old).motivation.leak, 0.25);
  // Both spelt: the new one counts, and the old one is an unknown key, named.
  YAML::Node both = baseTree();
  both["motivation"]["leak_rate"] = 0.25;
  EXPECT_TRUE(upgradeConfig(both, m).empty());
  EXPECT_THROW(parseRunConfig(both), ConfigError);
}

TEST(Migrations, TheShippedTableNamesKeysOfThisBuildAndAMalformedOneIsRefusedNamingTheEntry) {
  const ConfigMigrations& shipped = loadMigrations(std::string(AFFORD_SOURCE_DIR) + "/config/migrations.yaml");
  std::set<std::string> keys;
  for (const KeyInfo& k : configKeys()) keys.insert(k.key);
  for (const auto& a : shipped.added) EXPECT_TRUE(keys.count(a.key)) << a.key << " is not a key of this build";
  for (const auto& r : shipped.renamed) {
    EXPECT_TRUE(keys.count(r.to)) << r.to << " is not a key of this build";
    EXPECT_FALSE(keys.count(r.from)) << r.from << " is still a key of this build";
  }
  const std::string dir = test::tempDir("migrations");
  std::ofstream(dir + "/bad.yaml") << "added:\n  - {key: goals.held, value: 3}\n";
  try {
    loadMigrations(dir + "/bad.yaml");
    ADD_FAILURE() << "an entry without its release was taken";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml: added[0]: needs release"), std::string::npos) << e.what();
  }
  std::ofstream(dir + "/other.yaml") << "removed: []\n";
  EXPECT_THROW(loadMigrations(dir + "/other.yaml"), ConfigError);
}

}  // namespace
}  // namespace afford

#include "experiment/design/experiment_file.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <mutex>
#include <sstream>

#include "afford/yaml_reader.hpp"

namespace afford {

namespace {

}  // namespace

std::vector<std::string> parseSystems(const std::vector<std::string>& given, const std::string& option) {
  std::vector<std::string> out;
  const auto add = [&](const std::string& name) {
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  };
  for (const std::string& g : given) {
    std::stringstream items(g);
    std::string item;
    bool any = false;
    while (std::getline(items, item, ',')) {
      any = true;
      if (item == "all") {
        for (const char* s : {"FIX", "IGN", "IMP"}) add(s);
        continue;
      }
      try {
        add(toString(parseSystem(item)));
      } catch (const ConfigError&) {
        std::string upper = item;
        for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        const bool cased = upper == "FIX" || upper == "IGN" || upper == "IMP" || upper == "GOALS";
        throw ConfigError(option + ": unknown system \"" + item + "\" in \"" + g + "\"" +
                          (cased ? "; did you mean " + upper + "? (systems are written in capitals)" : "") +
                          " (FIX, IGN, IMP, GOALS, all (the paper's three), or a list: FIX,IMP)");
      }
    }
    if (!any) throw ConfigError(option + ": empty (FIX, IGN, IMP, GOALS, all (the paper's three), or a list: FIX,IMP)");
  }
  return out;
}

std::vector<std::string> listScenarios(const std::string& config_dir, WorldKind world) {
  std::vector<std::string> out;
  for (const std::string& name : yamlNames(config_dir, "scenarios")) {
    WorldKind of = WorldKind::Grid;  // a file that does not read is listed: loading it says what is wrong
    try {
      const YAML::Node n = YAML::LoadFile((std::filesystem::path(config_dir) / "scenarios" / (name + ".yaml")).string());
      if (n.IsMap() && n["world"] && n["world"].IsScalar())
        for (const auto& k : kWorldKindNames)
          if (n["world"].Scalar() == k.name) of = k.value;
    } catch (const YAML::Exception&) {
    }
    if (of == world) out.push_back(name);
  }
  return out;
}


void mergeInto(YAML::Node base, const YAML::Node& over) {
  if (!over.IsMap()) return;
  for (const auto& kv : over) {
    const std::string key = kv.first.Scalar();
    if (kv.second.IsMap() && base[key].IsMap()) {
      mergeInto(base[key], kv.second);
    } else {
      base[key] = YAML::Clone(kv.second);
    }
  }
}

std::vector<std::string> listExperiments(const std::string& config_dir) { return yamlNames(config_dir, "experiments"); }

namespace {
YAML::Node loadFile(const std::filesystem::path& file) {
  // Planning reads the same few files for each of thousands of runs: a file is
  // parsed again only when its size or time of change differs from the last.
  struct Parsed {
    std::uintmax_t size;
    std::filesystem::file_time_type mtime;
    YAML::Node node;
  };
  static std::mutex mutex;
  static std::map<std::string, Parsed> parsed;
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  const auto mtime = ec ? std::filesystem::file_time_type() : std::filesystem::last_write_time(file, ec);
  if (!ec) {
    const std::lock_guard<std::mutex> lock(mutex);
    if (auto it = parsed.find(file.string()); it != parsed.end() && it->second.size == size && it->second.mtime == mtime)
      return YAML::Clone(it->second.node);
  }
  try {
    YAML::Node node = YAML::LoadFile(file.string());
    if (!ec) {
      const std::lock_guard<std::mutex> lock(mutex);
      parsed[file.string()] = Parsed{size, mtime, YAML::Clone(node)};
    }
    return node;
  } catch (const YAML::BadFile&) {
    throw ConfigError("cannot read config file " + file.string());
  } catch (const YAML::Exception& e) {
    throw ConfigError("config file " + file.string() + " is not valid YAML: " + e.what());
  }
}

// config_dir/<folder>/<name>.yaml, or a ConfigError listing the names known there.
std::filesystem::path namedFile(const std::string& config_dir, const char* folder, const char* kind,
                                const std::string& name) {
  const auto known = yamlNames(config_dir, folder);
  if (std::find(known.begin(), known.end(), name) == known.end()) {
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    const std::string near = closestName(name, known);
    throw ConfigError(std::string("unknown ") + kind + " \"" + name + "\"" +
                      (near.empty() ? "" : "; did you mean \"" + near + "\"?") + " (known in " + config_dir + "/" +
                      folder + ": " + list + ")");
  }
  return std::filesystem::path(config_dir) / folder / (name + ".yaml");
}
}  // namespace

Scenario loadScenario(const std::string& config_dir, const std::string& name, const RunConfig& run) {
  const auto file = namedFile(config_dir, "scenarios", "scenario", name);
  Scenario s = parseScenario(loadFile(file), "", run.world);
  validateScenario(s, run);
  return s;
}

namespace {
ExtrinsicDesign parseDesign(const YAML::Node& node, const std::string& file) {
  ConfigReader r(node, "extrinsic");
  r.expect({"scenarios", "generate", "tests", "after_actions", "vary", "analysis"});
  ExtrinsicDesign d;
  if (r.has("generate")) {
    ConfigReader g = r.map("generate");
    g.expect({"sub_goals", "objects", "multi_step", "per_point", "seed"});
    GenerateDesign gen;
    auto counts = [&](const char* key) {
      std::vector<int> out;
      const YAML::Node n = g.raw(key);
      const std::string path = g.keyPath(key);
      if (n.IsScalar())
        out.push_back(static_cast<int>(g.integer(key, 1, 256)));
      else if (n.IsSequence() && n.size() > 0)
        for (std::size_t i = 0; i < n.size(); ++i) {
          int v = 0;
          try {
            v = n[i].as<int>();
          } catch (const YAML::Exception&) {
            failKey(path + "[" + std::to_string(i) + "]", "expected a whole number, got " + describeNode(n[i]));
          }
          if (v < 1 || v > 256) failKey(path + "[" + std::to_string(i) + "]", "expected 1 to 256, got " + std::to_string(v));
          out.push_back(v);
        }
      else
        failKey(path, "expected a number or a non-empty list of numbers, got " + describeNode(n));
      return out;
    };
    gen.sub_goals = counts("sub_goals");
    if (g.has("objects")) gen.objects = counts("objects");
    if (g.has("multi_step")) {
      if (g.raw("multi_step").IsScalar() && g.raw("multi_step").Scalar() == "all")
        gen.all_multi_step = true;
      else
        gen.multi_step = static_cast<int>(g.integer("multi_step", 0, 256));
    }
    gen.per_point = g.has("per_point") ? static_cast<int>(g.integer("per_point", 1, 10000)) : 1;
    gen.seed = g.has("seed") ? g.integer("seed", 0, std::numeric_limits<std::int32_t>::max()) : 1;
    for (int k : gen.sub_goals) {
      for (int n : gen.objects)
        if (n < k)
          failKey(g.keyPath("objects"), "every point needs at least as many objects as sub-goals: " + std::to_string(n) +
                                         " objects for " + std::to_string(k) + " sub-goals");
      if (!gen.all_multi_step && gen.multi_step > k)
        failKey(g.keyPath("multi_step"), std::to_string(gen.multi_step) + " two-action sub-goals is more than the " +
                                          std::to_string(k) + " sub-goals of a point (say 'all' for m = k)");
    }
    g.finish();
    d.generate = gen;
  }
  if (r.has("scenarios") || !d.generate) {
    const YAML::Node sc = r.has("scenarios") ? r.raw("scenarios") : YAML::Node();
    if (!sc.IsSequence() || sc.size() == 0)
      failKey("extrinsic.scenarios", "expected a non-empty list of scenario names (or extrinsic.generate)");
    for (const auto& n : sc) d.scenarios.push_back(n.Scalar());
  }
  d.tests = r.has("tests") ? static_cast<int>(r.integer("tests", 1, 100000)) : 0;  // 0: only with --extrinsic-reps
  d.after_actions = r.has("after_actions") ? r.integer("after_actions", 1, 100'000'000) : 0;
  if (r.has("vary")) {
    const YAML::Node v = r.raw("vary");
    if (!v.IsMap()) failKey("extrinsic.vary", "expected a map of config keys to lists of values");
    for (const auto& kv : v) {
      const std::string key = kv.first.Scalar();
      if (!kv.second.IsSequence() || kv.second.size() == 0)
        failKey("extrinsic.vary." + key, "expected a non-empty list of values");
      std::vector<std::string> values;
      for (const auto& x : kv.second) values.push_back(YAML::Dump(x));
      d.vary.emplace_back(key, values);
    }
  }
  d.analysis = r.has("analysis") ? r.text("analysis") : "";
  if (!d.analysis.empty() && d.analysis != "utility" && d.analysis != "forward-models" && d.analysis != "search-reduction")
    failKey("extrinsic.analysis", "expected utility, forward-models or search-reduction, got \"" + d.analysis + "\" (" + file + ")");
  r.finish();
  return d;
}

}  // namespace

YAML::Node loadGivenYaml(const std::string& file, const std::string& what, std::uintmax_t max_bytes) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw ConfigError(what + " " + file + ": no such file");
  if (!std::filesystem::is_regular_file(file, ec)) throw ConfigError(what + " " + file + ": not a regular file");
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec || size > max_bytes)
    throw ConfigError(what + " " + file + ": " + (ec ? "cannot read its size" : std::to_string(size) + " bytes, more than " +
                                                                                 std::to_string(max_bytes)));
  try {
    return YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    throw ConfigError(what + " " + file + ": " + e.what());
  }
}

namespace {

// `key: none` (or an empty value) in an experiment file: drop what the extended experiment had.
bool isNone(const YAML::Node& n) { return n.IsNull() || (n.IsScalar() && n.Scalar() == "none"); }

// Every key a node sets (maps to any depth; a list is one key), under `path`, as set by `where`.
void recordKeys(const YAML::Node& node, const std::string& path, const std::string& where,
                std::map<std::string, std::string>& out) {
  if (!path.empty()) out[path] = where;
  if (node.IsMap())
    for (const auto& kv : node) recordKeys(kv.second, joinKey(path, kv.first.Scalar()), where, out);
}

// An experiment file's `conditions:`, checked (the map itself is checked by the caller).
std::vector<std::pair<std::string, std::vector<std::string>>> parseConditions(const YAML::Node& node) {
  std::vector<std::pair<std::string, std::vector<std::string>>> out;
  for (const auto& c : node) {
    const std::string cname = c.first.Scalar();
    if (cname.empty() || cname.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") !=
                             std::string::npos)
      failKey("conditions." + cname, "a condition's name is part of run ids: letters, digits and _ only");
    if (!c.second.IsSequence()) failKey("conditions." + cname, "expected a list of settings (key.path=value)");
    std::vector<std::string> settings;
    for (const auto& v : c.second) {
      if (!v.IsScalar() || v.Scalar().find('=') == std::string::npos)
        failKey("conditions." + cname, "expected settings of the form key.path=value, got " + describeNode(v));
      settings.push_back(v.Scalar());
    }
    out.emplace_back(cname, settings);
  }
  return out;
}

// One top-level block of an experiment file, into `e` (the experiment it extends, so far).
void readBlock(ExperimentFile& e, const std::string& key, const YAML::Node& value, const std::filesystem::path& file) {
    if (key == "description") {
      e.description = value.Scalar();
    } else if (key == "repetitions") {
      YAML::Node one(YAML::NodeType::Map);
      one["repetitions"] = value;
      ConfigReader r(one, "");
      e.repetitions = static_cast<int>(r.integer("repetitions", 1, 100000));
    } else if (key == "default_systems") {
      if (!value.IsSequence()) failKey("default_systems", "expected a list of systems (FIX, IGN, IMP, GOALS)");
      e.default_systems.clear();  // a file's list replaces the one of the file it extends
      for (const auto& s : value) e.default_systems.push_back(toString(parseSystem(s.Scalar())));
    } else if (key == "extrinsic") {
      if (isNone(value)) {  // `extrinsic: none`: no design, whatever the extended experiment had
        e.extrinsic.reset();
        e.extrinsic_node = YAML::Node();
        return;
      }
      if (!value.IsMap()) failKey("extrinsic", "expected a map (or none), got " + describeNode(value) + " (" + file.string() + ")");
      YAML::Node merged = e.extrinsic_node.IsMap() ? e.extrinsic_node : YAML::Node(YAML::NodeType::Map);
      // The tests' source: a file stating one (scenarios, or generate) does not keep the extended design's other.
      if (value["scenarios"] && !value["generate"]) merged.remove("generate");
      if (value["generate"] && !value["scenarios"]) merged.remove("scenarios");
      mergeInto(merged, value);
      e.extrinsic_node = merged;
      e.extrinsic = parseDesign(merged, file.string());
    } else if (key == "tables") {
      if (isNone(value)) {
        e.tables.reset();
        e.tables_node = YAML::Node();
        return;
      }
      if (!value.IsMap()) failKey("tables", "expected a map (or none), got " + describeNode(value) + " (" + file.string() + ")");
      YAML::Node merged = e.tables_node.IsMap() ? e.tables_node : YAML::Node(YAML::NodeType::Map);
      mergeInto(merged, value);
      e.tables_node = merged;
      ConfigReader t(merged, "tables");
      t.expect({"count", "seed"});
      e.tables = TablesDesign{static_cast<int>(t.integer("count", 1, 100'000)), t.integer("seed", 0, INT64_MAX)};
      t.finish();
    } else if (key == "conditions") {
      if (!value.IsMap() || value.size() == 0)
        failKey("conditions", "expected a map of condition names to lists of settings (key.path=value), got " +
                               describeNode(value) + " (" + file.string() + ")");
      e.conditions = parseConditions(value);
    } else if (key == "systems") {
      if (!e.systems.IsMap()) e.systems = YAML::Node(YAML::NodeType::Map);
      mergeInto(e.systems, value);
      if (value.IsMap())
        for (const auto& s : value)
          recordKeys(s.second, "", "experiment file " + file.string() + ", block systems." + s.first.Scalar(),
                     e.system_sources[s.first.Scalar()]);
    } else {
      // A section of the run's configuration (run, world, motivation, ...); anything else is a typo.
      std::vector<std::string> blocks = {"extends", "description", "repetitions", "default_systems", "extrinsic",
                                         "tables", "conditions", "systems"};
      for (const KeyInfo& k : configKeys())
        if (const std::string top = k.key.substr(0, k.key.find('.'));
            std::find(blocks.begin(), blocks.end(), top) == blocks.end())
          blocks.push_back(top);
      if (std::find(blocks.begin(), blocks.end(), key) == blocks.end()) {
        const std::string near = closestName(key, blocks);
        throw ConfigError("experiment file " + file.string() + ": unknown block '" + key + "'" +
                              (near.empty() ? "" : "; did you mean '" + near + "'?"),
                          key);
      }
      YAML::Node over(YAML::NodeType::Map);
      over[key] = value;
      mergeInto(e.overlay, over);
      recordKeys(value, key, "experiment file " + file.string() + ", block " + key, e.sources);
    }
}

ExperimentFile loadExperimentChain(const std::string& config_dir, const std::string& name, int depth,
                                   const std::filesystem::path& from = {}) {
  const bool path = isExperimentPath(name);
  std::filesystem::path file;
  if (path) {
    file = (std::filesystem::path(name).is_relative() && !from.empty() ? from.parent_path() / name
                                                                        : std::filesystem::path(name))
               .lexically_normal();
    if (!std::filesystem::is_regular_file(file))
      throw ConfigError("experiment file " + file.string() + " does not exist" +
                        (from.empty() ? std::string() : " (named by 'extends' in " + from.string() + ")"));
  } else {
    file = namedFile(config_dir, "experiments", "experiment", name);
  }
  YAML::Node root = loadFile(file);
  if (!root.IsMap()) throw ConfigError("config file " + file.string() + ": expected a map");
  ExperimentFile e;
  if (root["extends"].IsDefined()) {  // start from the whole of another experiment; this file changes what it states
    if (depth > 8) throw ConfigError("config file " + file.string() + ": 'extends' chain too long (a cycle?)");
    try {
      e = loadExperimentChain(config_dir, root["extends"].Scalar(), depth + 1, file);
    } catch (const ConfigError& err) {
      throw ConfigError(std::string(err.what()) + " (extended by " + file.string() + ")", err.key());
    }
    // What the extended file set, named as such when the run's configuration is read later.
    for (auto& [key, where] : e.sources) where += " (extended by " + file.string() + ")";
    for (auto& [system, sources] : e.system_sources)
      for (auto& [key, where] : sources) where += " (extended by " + file.string() + ")";
    e.overlay = YAML::Clone(e.overlay);
    e.systems = YAML::Clone(e.systems);
    e.extrinsic_node = YAML::Clone(e.extrinsic_node);
    e.tables_node = YAML::Clone(e.tables_node);
  } else {
    e.overlay = YAML::Node(YAML::NodeType::Map);
  }
  e.name = path ? file.stem().string() : name;
  e.file = path ? std::filesystem::absolute(file).lexically_normal().string() : std::string();
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (key == "extends") continue;
    try {
      readBlock(e, key, kv.second, file);
    } catch (const ConfigError& err) {
      const std::string what = err.what();
      if (what.find(file.string()) != std::string::npos) throw;  // (it names the file already)
      throw ConfigError("experiment file " + file.string() + ", block " + key + ": " + what, err.key());
    }
  }
  if (!e.conditions.empty() && !e.tables)
    failKey("conditions", "compares conditions on random tables: it needs a 'tables:' section (" + file.string() + ")");
  return e;
}
}  // namespace

ExperimentFile loadExperiment(const std::string& config_dir, const std::string& name) {
  return loadExperimentChain(config_dir, name, 0);
}

bool isExperimentPath(const std::string& name) {
  return name.find('/') != std::string::npos ||
         (name.size() > 5 && name.compare(name.size() - 5, 5, ".yaml") == 0);
}

YAML::Node effectiveConfig(const std::string& config_dir, const RunRequest& request) {
  YAML::Node root = loadFile(std::filesystem::path(config_dir) / "defaults.yaml");
  const ExperimentFile e = loadExperiment(config_dir, request.experiment);
  mergeInto(root, e.overlay);
  const std::string sys = toString(request.system);
  std::map<std::string, std::string> sources = e.sources;  // config key -> where it was given
  if (e.systems.IsMap() && e.systems[sys].IsDefined()) {
    if (!e.systems[sys].IsMap()) failKey("systems." + sys, "expected a map of overrides");
    mergeInto(root, e.systems[sys]);
    if (const auto it = e.system_sources.find(sys); it != e.system_sources.end())
      for (const auto& [k, where] : it->second) sources[k] = where;
  }
  root["experiment"] = e.name;
  root["system"] = sys;
  if (request.system == System::GOALS) root["phase"] = "goals";  // the agent that sets its own goals learns there
  root["seed"] = request.seed;
  if (request.steps) root["run"]["steps"] = *request.steps;
  for (const auto& setting : request.settings) {
    const auto eq = setting.find('=');
    if (eq == std::string::npos || eq == 0)
      throw ConfigError("setting \"" + setting + "\": expected key.path=value");
    const std::string path = setting.substr(0, eq);
    YAML::Node value;
    try {
      value = YAML::Load(setting.substr(eq + 1));
    } catch (const YAML::Exception& ex) {
      throw ConfigError("config key '" + path + "': value is not valid YAML: " + ex.what());
    }
    std::vector<std::string> parts;
    std::stringstream ss(path);
    for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
    std::vector<YAML::Node> chain{root};
    const auto keysOf = [](const YAML::Node& map) {
      std::vector<std::string> keys;
      for (const auto& kv : map) keys.push_back(kv.first.Scalar());
      return keys;
    };
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      YAML::Node next = chain.back()[parts[i]];
      if (!next.IsDefined() || !next.IsMap()) {
        const std::string near = closestName(parts[i], keysOf(chain.back()));
        failKey(path, "unknown key (no map '" + parts[i] + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?") + ")");
      }
      chain.push_back(next);
    }
    if (!chain.back()[parts.back()].IsDefined())
      failKey(path, unknownKey(path.substr(0, path.size() - parts.back().size() - (parts.size() > 1 ? 1 : 0)),
                               parts.back(), keysOf(chain.back())));
    chain.back()[parts.back()] = value;
    sources[path] = "--set " + setting;
  }
  // The `table` section is a table world's (world.kind: table). A run of the paper's world (grid, the default)
  // carries neither it nor the kind: its configuration is as it was before there was a table world (its logs,
  // plans and stored agents with it), and a table key given to it is refused rather than left unread.
  if (root["world"].IsMap() && (!root["world"]["kind"].IsDefined() || root["world"]["kind"].Scalar() == "grid")) {
    for (const auto& [key, where] : sources)
      if (key == "table" || key.rfind("table.", 0) == 0)
        throw ConfigError(where + ": config key '" + key + "': the table section is the physical table's "
                          "(world.kind: table); experiment '" + e.name + "' is of the paper's world (grid)", key);
    root["world"].remove("kind");
    root.remove("table");
  }
  try {
    parseRunConfig(root);  // validate now, before any process starts
  } catch (const ConfigError& e) {
    // Say where the key was given: the experiment file and its block, or --set.
    std::string where;
    for (std::string k = e.key(); !k.empty() && where.empty();) {
      if (auto it = sources.find(k); it != sources.end()) where = it->second;
      const auto dot = k.rfind('.');
      k = dot == std::string::npos ? std::string() : k.substr(0, dot);
    }
    if (where.empty()) throw;
    throw ConfigError(where + ": " + e.what(), e.key());
  }
  return root;
}

YAML::Node extrinsicConfig(const std::string& config_dir, const RunRequest& request, const std::string& checkpoint,
                           const std::string& scenario) {
  YAML::Node root = effectiveConfig(config_dir, request);
  const RunConfig base = parseRunConfig(root);
  loadScenario(config_dir, scenario, base);  // names the scenario's problem, if any
  root["phase"] = "extrinsic";
  root["run"]["steps"] = base.planner.budget;
  root["extrinsic"]["checkpoint"] = checkpoint;
  root["extrinsic"]["scenario"] = loadFile(std::filesystem::path(config_dir) / "scenarios" / (scenario + ".yaml"));
  parseRunConfig(root);
  return root;
}

YAML::Node scenarioNode(const Scenario& scenario) {
  YAML::Node root(YAML::NodeType::Map);
  root["name"] = scenario.name;
  if (!scenario.description.empty()) root["description"] = scenario.description;
  auto state = [](const ObjectState& s) {
    YAML::Node n(YAML::NodeType::Map);
    n["colour"] = toString(s.colour);
    YAML::Node pos(YAML::NodeType::Sequence);
    pos.push_back(s.x);
    pos.push_back(s.y);
    pos.SetStyle(YAML::EmitterStyle::Flow);
    n["position"] = pos;
    return n;
  };
  for (const ScenarioObject& o : scenario.objects) {
    YAML::Node n(YAML::NodeType::Map);
    n["shape"] = toString(o.shape);
    n["initial"] = state(o.initial);
    n["goal"] = state(o.goal);
    n["value"] = o.value;
    if (o.actions != 1) n["actions"] = o.actions;
    root["objects"].push_back(n);
  }
  return root;
}

YAML::Node extrinsicConfig(const std::string& config_dir, const RunRequest& request, const std::string& checkpoint,
                           const Scenario& scenario) {
  YAML::Node root = effectiveConfig(config_dir, request);
  const RunConfig base = parseRunConfig(root);
  root["phase"] = "extrinsic";
  root["run"]["steps"] = base.planner.budget;
  root["extrinsic"]["checkpoint"] = checkpoint;
  root["extrinsic"]["scenario"] = scenarioNode(scenario);
  parseRunConfig(root);  // validates the scenario in this world
  return root;
}


}  // namespace afford

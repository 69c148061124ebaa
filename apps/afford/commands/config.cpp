// afford config NAME: print the effective configuration of one run; afford config --keys: every key, as
// the tables of docs/configuration.md (written from the declaration and config/defaults.yaml here, the one
// place that writes them).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "afford/config.hpp"
#include "afford/yaml_reader.hpp"
#include "apps/afford/commands.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

// Each key's value and comment as config/defaults.yaml spells them (its
// first line): "steps: 6000  # paper 3.1.1 ..." gives run.steps -> {6000, paper 3.1.1 ...}.
struct DefaultLine {
  std::string value, comment;
};
std::map<std::string, DefaultLine> defaultLines(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ConfigError("cannot read config file " + file.string());
  std::map<std::string, DefaultLine> out;
  std::vector<std::pair<std::size_t, std::string>> open;  // the sections the line is in: indentation, key
  const auto trim = [](std::string t) {
    t.erase(0, t.find_first_not_of(" \t"));
    t.erase(t.find_last_not_of(" \t") + 1);
    return t;
  };
  for (std::string line; std::getline(in, line);) {
    const std::size_t indent = line.find_first_not_of(' ');
    if (indent == std::string::npos || line[indent] == '#') continue;
    const std::size_t colon = line.find(':', indent);
    if (colon == std::string::npos) continue;
    while (!open.empty() && open.back().first >= indent) open.pop_back();
    std::string path;
    for (const auto& [i, k] : open) path += k + ".";
    path += line.substr(indent, colon - indent);
    // The comment begins at the first '#' outside quotes.
    std::size_t hash = std::string::npos;
    bool quoted = false;
    for (std::size_t i = colon + 1; i < line.size() && hash == std::string::npos; ++i) {
      if (line[i] == '"') quoted = !quoted;
      if (line[i] == '#' && !quoted) hash = i;
    }
    const std::string value = trim(line.substr(colon + 1, hash == std::string::npos ? std::string::npos : hash - colon - 1));
    const std::string comment = hash == std::string::npos ? "" : trim(line.substr(hash + 1));
    if (value.empty())
      open.emplace_back(indent, line.substr(indent, colon - indent));
    else
      out[path] = {value, comment};
  }
  return out;
}

std::string cell(const std::string& text) {
  std::string out;
  for (char ch : text) out += ch == '|' ? std::string("\\|") : std::string(1, ch);
  return out;
}

// Every scalar of a tree, by its dotted key ("motivation.leak" -> "0.3");
// lists and the keys in `skip` (and below them) are left out.
void flatten(const YAML::Node& node, const std::string& path, const std::set<std::string>& skip,
             std::map<std::string, std::string>& out) {
  if (skip.count(path)) return;
  if (node.IsScalar()) out[path] = node.Scalar();
  if (!node.IsMap()) return;
  for (const auto& kv : node) flatten(kv.second, joinKey(path, kv.first.Scalar()), skip, out);
}

// The values the experiment files (and their systems' blocks) give in place
// of defaults.yaml's, as a table: key, default, and each other value with
// where it is set ("base: IGN" for one system; an experiment alone for all).
std::string overridesMarkdown(const std::string& config_dir, const std::map<std::string, DefaultLine>& lines) {
  // The runner's keys and the world's objects differ by their nature.
  const std::set<std::string> skip{"experiment", "system", "seed", "phase", "run", "world.objects"};
  std::map<std::string, std::map<std::string, std::map<std::string, std::vector<std::string>>>> by_key;  // key, value, experiment, systems
  for (const std::string& name : listExperiments(config_dir))
    for (const auto& sys : kSystemNames) {
      std::map<std::string, std::string> flat;
      flatten(effectiveConfig(config_dir, RunRequest{name, sys.value, 1, std::nullopt, {}}), "", skip, flat);
      for (const auto& [key, value] : flat) {
        const auto d = lines.find(key);
        if (d != lines.end() && YAML::Load(d->second.value).Scalar() != value) by_key[key][value][name].push_back(sys.name);
      }
    }
  std::ostringstream out;
  out << "| key | default | elsewhere |\n|---|---|---|\n";
  for (const auto& [key, values] : by_key) {
    std::string elsewhere;
    for (const auto& [value, experiments] : values) {
      std::string where;
      for (const auto& [name, systems] : experiments) {
        std::string who = name;
        if (systems.size() < kSystemNames.size()) {
          who += ":";
          for (const auto& s : systems) who += " " + s;
        }
        where += (where.empty() ? "" : ", ") + who;
      }
      elsewhere += (elsewhere.empty() ? "" : "; ") + value + " (" + where + ")";
    }
    out << "| `" << key << "` | " << cell(lines.at(key).value) << " | " << cell(elsewhere) << " |\n";
  }
  return out.str();
}

// The tables of keys of docs/configuration.md: every key with its value and
// source in config_dir's defaults.yaml (the comment beside it, up to its first
// colon) and its meaning; the protocol's keys in a table of their own.
std::string keysMarkdown(const std::string& config_dir) {
  const auto lines = defaultLines(std::filesystem::path(config_dir) / "defaults.yaml");
  std::ostringstream run, protocol;
  run << "| key | type | default | source | meaning |\n|---|---|---|---|---|\n";
  protocol << "| key | type | default | meaning |\n|---|---|---|---|\n";
  for (const KeyInfo& k : configKeys()) {
    std::string value = k.origin == KeyInfo::Origin::Runner ? "set by the runner" : "per experiment";
    std::string source;
    if (k.origin == KeyInfo::Origin::Defaults) {
      const auto line = lines.find(k.key);
      if (line == lines.end()) throw ConfigError("config key '" + k.key + "': missing in " + config_dir + "/defaults.yaml");
      value = line->second.value;
      source = line->second.comment.substr(0, line->second.comment.find(':'));
    }
    if (k.key.rfind("protocol.", 0) == 0)
      protocol << "| `" << k.key << "` | " << cell(k.type) << " | " << cell(value) << " | " << cell(k.meaning) << " |\n";
    else
      run << "| `" << k.key << "` | " << cell(k.type) << " | " << cell(value) << " | " << cell(source) << " | "
          << cell(k.meaning) << " |\n";
  }
  return run.str() + "\n" + protocol.str() +
         "\nThe values the experiment files give in place of the defaults (each "
         "experiment's file names their sources); `name: FIX` is one system's block, "
         "a name alone holds for every system:\n\n" +
         overridesMarkdown(config_dir, lines);
}

}  // namespace

Command configCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::string name, system = "IMP";
    std::vector<std::string> settings;
    bool keys = false;
  };
  auto a = std::make_shared<Args>();
  auto* show = app.add_subcommand("config", "print the effective configuration of one run");
  auto* name = show->add_option("name", a->name, "experiment");
  show->add_flag("--keys", a->keys,
                 "print every key of the configuration instead: its type, its default and source (defaults.yaml) "
                 "and its meaning, as the tables of docs/configuration.md")
      ->excludes(name);
  show->add_option("--system", a->system, "FIX, IGN or IMP")->capture_default_str();
  show->add_option("--set", a->settings, "override a config value (repeatable)");
  return {show, [a, &door] {
            if (a->keys) {
              std::printf("%s", keysMarkdown(door.config_dir).c_str());
              return 0;
            }
            if (a->name.empty()) throw ConfigError("which experiment? `afford config NAME` (or --keys)");
            RunRequest req{a->name, parseSystem(a->system), 1, std::nullopt, a->settings};
            std::printf("%s", emitYaml(effectiveConfig(door.config_dir, req)).c_str());
            return 0;
          }};
}

}  // namespace afford

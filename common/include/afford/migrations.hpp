// What a configuration written by an earlier release means to this build (docs/releases.md): the keys added
// since a release, with the value that keeps what that release did, and the keys renamed since, kept in
// config/migrations.yaml. A configuration an earlier release wrote (a log's RUN_CONFIG, a manifest's
// config_yaml) or a user's experiment file of then lacks the added keys and spells the renamed ones as then:
// upgradeConfig gives it this build's form, and says what it changed.
#pragma once
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace afford {

struct ConfigMigrations {
  struct Added {
    std::string key;      // dotted: "goals.held"
    std::string release;  // the first release that has it
    YAML::Node value;     // what it is in a configuration of an earlier release
  };
  struct Renamed {
    std::string from, to;  // dotted
    std::string release;   // the first release that spells it `to`
  };
  std::vector<Added> added;
  std::vector<Renamed> renamed;
};

// The table of `file` (config/migrations.yaml); ConfigError naming the file and the entry if it is malformed.
ConfigMigrations loadMigrations(const std::string& file);
// This build's (config/migrations.yaml of its config folder), read once; empty if the folder has none.
const ConfigMigrations& configMigrations();

// `root` in this build's form: a renamed key moved to its new name (unless the new one is there too), an added
// key that is absent given its value. Returns a line for each change ("goals.held: absent (written before
// 0.2.0): 4096").
std::vector<std::string> upgradeConfig(YAML::Node& root, const ConfigMigrations& m);

// A configuration text of this build as `release` wrote it ("0.1.0", "0.2.0+abc"): each key added after that
// release that holds the value it stands for in that release's configurations is left out (YAML as
// emitYaml writes it). The text itself if there is none.
std::string configAsWrittenBy(const std::string& text, const std::string& release, const ConfigMigrations& m);
// Is release a earlier than release b (by their numbers: "0.1.0+abc" is 0.1.0)?
bool releaseBefore(const std::string& a, const std::string& b);

}  // namespace afford

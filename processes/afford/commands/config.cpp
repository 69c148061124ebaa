// afford config NAME: print the effective configuration of one run; afford config --keys: every key.
#include <cstdio>
#include <memory>

#include "afford/commands.hpp"
#include "afford/config.hpp"

namespace afford {

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

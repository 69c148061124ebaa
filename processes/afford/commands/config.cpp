// afford config NAME: print the effective configuration of one run.
#include <cstdio>
#include <memory>

#include "afford/commands.hpp"
#include "afford/config.hpp"

namespace afford {

Command configCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::string name, system = "IMP";
    std::vector<std::string> settings;
  };
  auto a = std::make_shared<Args>();
  auto* show = app.add_subcommand("config", "print the effective configuration of one run");
  show->add_option("name", a->name, "experiment")->required();
  show->add_option("--system", a->system, "FIX, IGN or IMP")->capture_default_str();
  show->add_option("--set", a->settings, "override a config value (repeatable)");
  return {show, [a, &door] {
            RunRequest req{a->name, parseSystem(a->system), 1, std::nullopt, a->settings};
            std::printf("%s", emitYaml(effectiveConfig(door.config_dir, req)).c_str());
            return 0;
          }};
}

}  // namespace afford

// afford: the front door. One subcommand per file (commands/): `afford
// experiment NAME ...` runs experiments over real processes (udpm, default) or
// in one process (memq); `afford --help` lists the others.
#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include <vector>

#include "afford/node.hpp"
#include "afford/process_main.hpp"
#include "afford/version.hpp"
#include "apps/afford/commands.hpp"
#include "afford/config.hpp"
#include "afford/logging.hpp"

int main(int argc, char** argv) {
  CLI::App app{"afford: an embodied agent learning affordances (intrinsic phase) and solving extrinsic tasks", "afford"};
  app.require_subcommand(1);
  // The release and the commit it was built from (CHANGELOG.md says what each release changed).
  app.set_version_flag("--version", std::string("afford ") + afford::affordVersion());
  auto log = afford::makeLogger("afford");
  afford::FrontDoor door{afford::defaultConfigDir(), argv[0], std::vector<std::string>(argv + 1, argv + argc), log.get()};
  app.add_option("--config-dir", door.config_dir, "folder with defaults.yaml and experiments/")->capture_default_str();
  const std::vector<afford::Command> commands = {
      afford::experimentCommand(app, door), afford::experimentsCommand(app, door), afford::configCommand(app, door),
      afford::plotCommand(app, door),       afford::reportCommand(app, door),      afford::replayCommand(app, door),
      afford::explainCommand(app, door),    afford::statusCommand(app, door),      afford::scenarioCommand(app, door),
      afford::processesCommand(app, door),  afford::cleanCommand(app, door),      afford::mergeCommand(app, door),
      afford::busKeyCommand(app, door),     afford::renderCommand(app, door),
      afford::exportCommand(app, door),     afford::watchCommand(app, door),      afford::tuneCommand(app, door),
      afford::worldCommand(app, door)};
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(0);  // small images: OpenCV's thread pool only adds wake-ups
  try {
    for (const auto& c : commands)
      if (c.sub->parsed()) return c.run();
    return 2;
  } catch (const afford::ConfigError& e) {
    log->error("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
}

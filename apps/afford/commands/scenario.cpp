// afford scenario NAME | --generate K M N: check or draw a scenario, and picture it.
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <memory>

#include "apps/afford/commands.hpp"
#include "afford/config.hpp"
#include "afford/file_lock.hpp"
#include "experiment/design/generate.hpp"
#include "afford/image.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {

Command scenarioCommand(CLI::App& app, const FrontDoor& door) {
  struct Args {
    std::string name, png, experiment = "base";
    std::vector<int> generate;
    std::int64_t seed = 1, index = 0;
  };
  auto a = std::make_shared<Args>();
  auto* scen = app.add_subcommand("scenario", "check a scenario file and draw its goal and initial scenes");
  scen->add_option("name", a->name, "scenario (config/scenarios/<name>.yaml)");
  scen->add_option("--png", a->png, "write the picture to this PNG file");
  scen->add_option("--generate", a->generate,
                   "draw one instead: SUB_GOALS TWO_ACTION OBJECTS (k m n), printed as a scenario file")
      ->expected(3);
  scen->add_option("--seed", a->seed, "with --generate: the seed of the draw");
  scen->add_option("--index", a->index, "with --generate: which scenario of the seed");
  scen->add_option("--experiment", a->experiment, "the experiment whose world the scenario is for (default: base)");
  return {scen, [a, &door] {
            if (!a->png.empty()) prepareOutput(a->png, "--png", {".png"});
            const RunConfig run =
                parseRunConfig(effectiveConfig(door.config_dir, {a->experiment, System::IMP, 1, std::nullopt, {}}));
            const WorldConfig& world = run.world;
            Scenario s;
            if (!a->generate.empty()) {
              if (!a->name.empty()) throw ConfigError("afford scenario: give a scenario name or --generate, not both");
              const ScenarioSpec spec{a->generate[2], a->generate[0], a->generate[1]};
              s = generateScenario(run, spec, a->seed, a->index).scenario;
              std::printf("%s", emitYaml(scenarioNode(s)).c_str());
            } else {
              if (a->name.empty()) throw ConfigError("afford scenario: name a scenario, or --generate K M N");
              try {
                s = loadScenario(door.config_dir, a->name, run);
              } catch (const ConfigError& e) {
                if (e.key() != "world") throw;
                throw ConfigError(std::string(e.what()) + " (--experiment names an experiment of its world, e.g. " +
                                      (world.kind == WorldKind::Grid ? "table" : "base") + ")",
                                  e.key());
              }
              std::printf("%s: %zu object(s), valid. %s\n", s.name.c_str(), s.objects.size(), s.description.c_str());
            }
            if (!a->png.empty() && world.kind != WorldKind::Grid)
              throw ConfigError("--png draws the paper's world's scenarios; a table scenario's scenes are the camera's, "
                                "drawn by the environment (afford render of a test's log shows its goal image)",
                                "--png");
            if (!a->png.empty() && !cv::imwrite(a->png, scenarioPicture(s, world)))
              throw std::runtime_error("cannot write " + a->png);
            return 0;
          }};
}

}  // namespace afford

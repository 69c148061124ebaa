// afford-table-bench: what a step of the table world costs the environment process (docs/performance.md,
// "The physical table"). The world of an experiment (default `table`) acts N times, each action on an object
// drawn by (seed, step), the gaze on its centre as the eye would put it, each action in turn; the time of
// each part is measured: the motor primitive's physics, the camera's image, the segmentation that names the
// object under the gaze, and the scene set up anew. Prints one JSON object.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <cstdio>
#include <iostream>

#include "afford/rng.hpp"
#include "environment/table_world.hpp"
#include "eye/eye.hpp"
#include "experiment/design/experiment_file.hpp"

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
using afford::kNumActions;
using afford::kTableActionNames;

// Per action: its physics steps (the mean) and how often the scene did not come to rest within the bound.
nlohmann::json perAction(const std::array<std::array<double, 3>, kNumActions>& per_action) {
  nlohmann::json p;
  for (int a = 0; a < kNumActions; ++a) {
    const auto& v = per_action[static_cast<std::size_t>(a)];
    p[std::string(kTableActionNames[static_cast<std::size_t>(a)])] = {{"physics_steps", v[1] ? v[0] / v[1] : 0.0},
                                                                      {"not_at_rest", v[2]}};
  }
  return p;
}

// Per action: the eye's verdicts beside the simulation's (both yes, eye only, physics only, both no) and their
// agreement.
nlohmann::json eyeVerdicts(const std::array<std::array<int, 4>, kNumActions>& verdicts) {
  nlohmann::json p;
  for (int a = 0; a < kNumActions; ++a) {
    const auto& v = verdicts[static_cast<std::size_t>(a)];
    const int n = v[0] + v[1] + v[2] + v[3];
    p[std::string(kTableActionNames[static_cast<std::size_t>(a)])] = {
        {"both_yes", v[0]}, {"eye_only", v[1]}, {"physics_only", v[2]}, {"both_no", v[3]},
        {"agree", n ? static_cast<double>(v[0] + v[3]) / n : 0.0}};
  }
  return p;
}
// Each object's actions in the run's scenes: how often the eye saw the goal reached, and the simulation reached it.
nlohmann::json byObject(const afford::RunConfig& c, const std::vector<std::array<std::array<int, 3>, kNumActions>>& by_object) {
  nlohmann::json objects;
  for (std::size_t o = 0; o < by_object.size(); ++o)
    for (int a = 0; a < kNumActions; ++a) {
      const auto& cell = by_object[o][static_cast<std::size_t>(a)];
      objects[c.table.spec.objects[o].name][std::string(kTableActionNames[static_cast<std::size_t>(a)])] = {
          {"actions", cell[0]}, {"eye", cell[0] ? static_cast<double>(cell[1]) / cell[0] : 0.0},
          {"physics", cell[0] ? static_cast<double>(cell[2]) / cell[0] : 0.0}};
    }
  return objects;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace afford;
  CLI::App app{"the table world's cost a step: physics, camera, segmentation", "afford-table-bench"};
  std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config", experiment = "table";
  std::int64_t steps = 200, seed = 1;
  std::vector<std::string> settings;
  app.add_option("--config-dir", config_dir)->capture_default_str();
  app.add_option("--experiment", experiment, "a table experiment")->capture_default_str();
  app.add_option("--steps", steps, "actions")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--seed", seed)->capture_default_str();
  app.add_option("--set", settings, "key=value, as afford experiment --set");
  CLI11_PARSE(app, argc, argv);
  try {
    const RunConfig c = parseRunConfig(effectiveConfig(config_dir, RunRequest{experiment, System::IMP, seed, steps, settings}));
    if (c.world.kind != WorldKind::Table) throw ConfigError("experiment '" + experiment + "' is not of the table world");
    auto t0 = Clock::now();
    TableWorld world(c);
    const double build_ms = msSince(t0);
    double physics = 0, render = 0, segment = 0, setup = 0;
    long physics_steps = 0;
    std::array<std::array<double, 3>, kNumActions> per_action{};  // physics steps, actions, not settled
    int on_object = 0, succeeded = 0;
    Eye eye(c);
    // The eye's verdict on each action (what the agent learns) against the simulation's (the truth's): per action,
    // both yes, eye only, physics only, both no.
    std::array<std::array<int, 4>, kNumActions> verdicts{};
    // ... and by object: (actions, the eye's yes, the simulation's yes) per object and action.
    std::vector<std::array<std::array<int, 3>, kNumActions>> by_object(c.table.spec.objects.size());
    const auto wall = Clock::now();
    for (std::int64_t s = 0; s < steps; ++s) {
      if (world.objectsAppearAt(s)) {
        t0 = Clock::now();
        world.introduceObjectsAt(s);
        setup += msSince(t0);
      }
      const std::vector<cv::Point2d> at = world.centres();
      const KeyedRng rng(seed, s, Purpose::Component, 58);
      const cv::Point2d gaze = at[static_cast<std::size_t>(rng.bits(0) % at.size())];
      eye.setScene(world.render(), {});
      const Focus f = eye.attend(gaze.x, gaze.y);
      t0 = Clock::now();
      const int object = world.objectAt(f.x, f.y);  // the segmentation, drawn once a state
      segment += msSince(t0);
      const double before = world.physics().time();
      t0 = Clock::now();
      const ActionOutcome out = world.execute(s, static_cast<int>(s % kNumActions), f.x, f.y);
      physics += msSince(t0);
      physics_steps += std::lround((world.physics().time() - before) / c.table.spec.timestep);
      const int a = static_cast<int>(s % kNumActions);
      per_action[a][0] += world.lastPrimitive().physics_steps;
      per_action[a][1] += 1;
      per_action[a][2] += world.lastPrimitive().settled ? 0 : 1;
      on_object += out.on_object;
      succeeded += out.succeeded;
      t0 = Clock::now();
      const cv::Mat after = world.render();
      render += msSince(t0);
      if (out.on_object) {
        const std::optional<cv::Point2d> target =
            out.target_x >= 0 ? std::optional<cv::Point2d>(cv::Point2d(out.target_x, out.target_y)) : std::nullopt;
        const bool seen = eye.scanEffect(s, after, a, {}, target).affordance;
        ++verdicts[static_cast<std::size_t>(a)][seen ? (out.succeeded ? 0 : 1) : (out.succeeded ? 2 : 3)];
        if (object >= 0) {
          auto& cell = by_object[static_cast<std::size_t>(object)][static_cast<std::size_t>(a)];
          ++cell[0], cell[1] += seen, cell[2] += out.succeeded;
        }
      }
    }
    const double wall_s = msSince(wall) / 1000.0;
    nlohmann::json j{{"experiment", experiment},
                     {"steps", steps},
                     {"objects", c.table.spec.objects.size()},
                     {"image", std::to_string(c.world.size_px) + "x" + std::to_string(c.world.rows())},
                     {"build_ms", build_ms},
                     {"steps_per_second", steps / wall_s},
                     {"ms_per_step",
                      {{"physics", physics / steps}, {"render", render / steps}, {"segmentation", segment / steps},
                       {"set_up", setup / steps}}},
                     {"physics_steps_per_action", static_cast<double>(physics_steps) / steps},
                     {"us_per_physics_step", physics_steps ? 1000.0 * physics / physics_steps : 0.0},
                     {"on_object", on_object},
                     {"instabilities", world.physics().instabilities()},
                     {"eye_verdicts", eyeVerdicts(verdicts)},
                     {"by_object", byObject(c, by_object)},
                     {"per_action", perAction(per_action)},
                     {"succeeded", succeeded}};
    std::cout << j.dump(2) << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "afford-table-bench: %s\n", e.what());
    return 1;
  }
}

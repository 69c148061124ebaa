// `afford render LOG --primitive STEP --out FILE`: the motor primitive of one action of a table run
// (world.kind: table) as a person sees it, the hand drawn: the agent's top camera beside a view from the
// table's side, a frame every so many physics steps (real time at the video's frame rate).
//
// A log holds the scenes between actions, not the physics within them: the run's world is built again from
// its RUN_CONFIG and the environment's part of the run is simulated again from the log's DECISIONs (each
// executed as the environment process did, in step order), up to STEP, whose primitive is drawn as it runs.
// The simulation is deterministic for the same build and MuJoCo, so the primitive's end is the scene the run
// published after it: the command checks that it is, byte for byte, and writes nothing when it is not.
#pragma once
#include <spdlog/spdlog.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace afford {

struct PrimitiveVideoOptions {
  std::filesystem::path log;  // a run's log folder or one .lcm file
  std::string run_id;         // the run, in a log that holds several (default: the first)
  std::string bus_key;        // the key of the bus an lcm-logger recording was made on
  std::filesystem::path out;  // .mp4 or .gif
  std::int64_t step = 0;      // the step whose action is drawn (an intrinsic run's step; a test's iteration)
  int fps = 25;               // frames per second; a frame every 1 / (fps x table.timestep) physics steps
  std::string ffmpeg = "ffmpeg";
  std::string config_dir;     // its defaults.yaml gives what the edge accepts
};

struct PrimitiveVideoResult {
  std::string run_id, action, object;  // the action's name and the object's (its table.objects name, or "none")
  bool succeeded = false;              // its goal, as the simulation checked it
  std::int64_t frames = 0, physics_steps = 0, replayed = 0;  // replayed: the run's actions simulated before it
  int width = 0, height = 0;
};

// Throws std::runtime_error saying what was wrong: the log (no such run or step, a run of the grid, a step in
// which the agent did not act: the nearest that did are named), the simulation (not the run's scene), ffmpeg.
PrimitiveVideoResult renderPrimitive(const PrimitiveVideoOptions& options, spdlog::logger& log);

}  // namespace afford

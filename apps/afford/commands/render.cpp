// afford render LOG --out FILE: a run's log as a video or GIF (experiment/present/video.hpp).
#include <cstdio>
#include <memory>

#include "afford/process_main.hpp"
#include "apps/afford/commands.hpp"
#include "experiment/present/primitive_video.hpp"
#include "experiment/present/video.hpp"

namespace afford {

Command renderCommand(CLI::App& app, const FrontDoor& door) {
  auto o = std::make_shared<VideoOptions>();
  auto primitive = std::make_shared<std::int64_t>(-1);
  auto* render = app.add_subcommand("render", "draw a run's log as a video (.mp4) or an animated GIF (.gif): the "
                                              "viewer's frames, encoded by ffmpeg; or, with --primitive, the motor "
                                              "primitive of one action of a table run, the hand drawn");
  render->add_option("log", o->log, "the run's log folder (logs/<run-id>) or one .lcm file")->required();
  render->add_option("--out", o->out, "the file to write, .mp4 or .gif (never overwritten)")->required();
  render->add_option("--every", o->every, "a frame every N steps")->capture_default_str()->check(CLI::PositiveNumber);
  render->add_option("--fps", o->fps, "frames per second of the video")->capture_default_str()->check(CLI::Range(1, 240));
  render->add_option("--max-frames", o->max_frames, "stop after this many frames (0: the whole run)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  render->add_option("--run", o->run_id, "the run to draw, in a log that holds several (default: the first)");
  render->add_option("--bus-key", o->bus_key, "the key of the bus the log was recorded on (an lcm-logger recording)");
  render->add_option("--ffmpeg", o->ffmpeg, "the ffmpeg to run")->capture_default_str();
  auto* prim = render->add_option("--primitive", *primitive,
                                  "a table run's step (a test's iteration): its action's primitive, simulated again "
                                  "from the log (checked against the scene the run published), the hand drawn; a "
                                  "frame every 1/fps s of physics")
                   ->check(CLI::NonNegativeNumber);
  render->get_option("--every")->excludes(prim);
  render->get_option("--max-frames")->excludes(prim);
  return {render, [o, primitive, &door] {
            o->config_dir = door.config_dir;
            installStopHandlers();  // Ctrl-C: nothing half-written left
            if (*primitive >= 0) {
              const PrimitiveVideoOptions p{o->log, o->run_id, o->bus_key, o->out, *primitive, o->fps, o->ffmpeg, o->config_dir};
              const PrimitiveVideoResult r = renderPrimitive(p, *door.log);
              std::printf("run: %s\nwrote %s: %lld frames of %dx%d, %s on %s at step %lld (%lld physics steps; %s), "
                          "%d per second, after simulating the run's %lld earlier actions again\n",
                          r.run_id.c_str(), o->out.string().c_str(), static_cast<long long>(r.frames), r.width, r.height,
                          r.action.c_str(), r.object.c_str(), static_cast<long long>(*primitive),
                          static_cast<long long>(r.physics_steps), r.succeeded ? "its goal reached" : "its goal not reached",
                          o->fps, static_cast<long long>(r.replayed));
              return 0;
            }
            const VideoResult r = renderVideo(*o, *door.log);
            std::printf("run: %s\nwrote %s: %lld frames of %dx%d, steps %lld to %lld every %lld, %d per second\n",
                        r.run_id.c_str(), o->out.string().c_str(), static_cast<long long>(r.frames), r.width, r.height,
                        static_cast<long long>(r.first_step), static_cast<long long>(r.last_step),
                        static_cast<long long>(o->every), o->fps);
            printLogSkips(r.malformed, 0, r.untagged);
            if (r.refused) std::printf("refused: %lld recorded message(s) (see the warnings)\n", static_cast<long long>(r.refused));
            return 0;
          }};
}

}  // namespace afford

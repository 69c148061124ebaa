// `afford render LOG --out FILE`: a run's log as a video (MP4) or an animated
// GIF, the viewer's frames (processes/viewer/viewer.hpp) at a stride of steps,
// encoded by ffmpeg. The run's messages are drawn in step order, whatever the
// log's interleaving of its channels (viewer/step_order.hpp: the log is read
// once for their steps, then as it is drawn, nothing of it held but the
// viewer's state and what came ahead of its step), each decoded and checked as
// the edge would; what the edge refuses is skipped and counted. The file is written beside FILE under a
// temporary name and renamed when ffmpeg has finished: an existing FILE is
// refused and never overwritten, and a failed render leaves nothing.
#pragma once
#include <spdlog/spdlog.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace afford {

struct VideoOptions {
  std::filesystem::path log;  // a run's log folder or one .lcm file
  std::string run_id;         // the run to draw, in a log that holds several (default: the first)
  std::string bus_key;        // the key of the bus an lcm-logger recording was made on
  std::filesystem::path out;  // .mp4 or .gif
  std::int64_t every = 10;    // a frame every this many steps
  int fps = 25;               // frames per second of the video
  std::int64_t max_frames = 0;  // stop after this many (0: the whole run)
  std::string ffmpeg = "ffmpeg";
  std::string config_dir;       // its defaults.yaml gives what the edge accepts
};

struct VideoResult {
  std::string run_id;
  std::int64_t frames = 0, first_step = -1, last_step = -1;
  int width = 0, height = 0;
  std::int64_t events = 0, refused = 0, malformed = 0, untagged = 0;  // events: the run's
};

// The frames' steps: the first step of the run drawn, then each step at least
// `every` after the last one drawn, each drawn once all of its messages are in
// (a frame is a function of the log's messages, not of their order in it).
// Throws std::runtime_error saying what was wrong (the log, the output, ffmpeg).
VideoResult renderVideo(const VideoOptions& options, spdlog::logger& log);

}  // namespace afford

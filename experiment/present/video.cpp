#include "experiment/present/video.hpp"

#include <memory>
#include <stdexcept>
#include <vector>

#include "afford/auth.hpp"
#include "afford/config.hpp"
#include "afford/process_main.hpp"
#include "experiment/present/encoder.hpp"
#include "experiment/replay/replay.hpp"
#include "viewer/feed.hpp"
#include "viewer/step_order.hpp"
#include "viewer/viewer.hpp"

namespace afford {

VideoResult renderVideo(const VideoOptions& o, spdlog::logger& log) {
  if (o.every < 1) throw std::runtime_error("--every must be at least 1");
  VideoFile file(o.out, o.ffmpeg, o.fps, "afford render");
  const std::shared_ptr<const BusKey> key = o.bus_key.empty() ? nullptr : busKeyFrom(o.bus_key);
  const ProtocolConfig protocol = loadProtocol(o.config_dir.empty() ? defaultConfigDir() : o.config_dir);
  // The run's messages in step order: each frame pairs a step's own messages, however the log interleaves them.
  StepOrderedLog<RecordedLogStream, RunSelector> in(
      [&](spdlog::logger& l) { return std::make_unique<RecordedLogStream>(o.log, l, key.get()); },
      [&](spdlog::logger& l) { return std::make_unique<RunSelector>(o.run_id, o.log.string(), l); }, protocol, log);
  Viewer viewer;
  ViewFeed feed(viewer, protocol, o.run_id);
  VideoResult r;
  std::int64_t drawn = -1;  // the step last drawn
  auto draw = [&] {         // the viewer's state, a step complete
    file.write(viewer.render());
    drawn = viewer.step();
    if (r.first_step < 0) r.first_step = drawn;
    r.last_step = drawn;
    ++r.frames;
  };
  auto due = [&] { return viewer.step() >= 0 && (drawn < 0 || viewer.step() - drawn >= o.every); };
  LogEvent e;
  StepKey at;
  while (in.next(e, at) && (o.max_frames <= 0 || r.frames < o.max_frames)) {
    // Ctrl-C (when the command installed the stop handlers): the partial file is removed (VideoFile).
    if (stopRequested()) throw std::runtime_error("interrupted: " + o.out.string() + " not written");
    ++r.events;
    // A message of a later step: the step shown is complete (the messages come in step order).
    if (due() && at.step > viewer.step()) draw();
    std::string why;
    if (!feed.take(e, why) && r.refused++ < 10) log.warn("{}: {}: skipped", e.channel, why);
  }
  if (due() && (o.max_frames <= 0 || r.frames < o.max_frames)) draw();
  if (!file.started()) {
    in.selector().check(in.cut(), in.stream().counts().key);  // no RUN_CONFIG: why (a key that does not fit?)
    throw std::runtime_error(o.log.string() + ": no scene of " +
                             (o.run_id.empty() ? "any run" : "run '" + o.run_id + "'") + " to draw");
  }
  file.finish();
  r.width = file.width(), r.height = file.height();
  r.run_id = feed.shown();
  r.malformed = in.stream().counts().malformed;
  r.untagged = in.stream().counts().untagged;
  return r;
}

}  // namespace afford

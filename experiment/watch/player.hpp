// `afford watch --log LOG`: a finished run played to the page, with its
// controls: play, pause, step, seek and speed. The run's messages are played
// in step order, whatever the log's interleaving of its channels
// (viewer/step_order.hpp): the log is read through once for their steps, then
// as it is played (nothing of it held but the page's state and what came
// ahead of its step); seeking back reads it again from its start, feeding the
// state without pacing up to the step asked for.
#pragma once
#include <spdlog/spdlog.h>

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "afford/auth.hpp"
#include "afford/config.hpp"
#include "afford/logfile.hpp"
#include "experiment/watch/server.hpp"
#include "experiment/watch/state.hpp"
#include "viewer/step_order.hpp"

namespace afford {

class RecordedLogStream;
class RunSelector;
class ViewFeed;

struct PlayerOptions {
  std::filesystem::path log;
  std::string run_id;   // default: the log's first run
  std::string bus_key;  // an lcm-logger recording of a keyed bus
  double speed = 20;    // steps a second
  bool play = true;     // at once, or paused at the first step
};

class LogPlayer : public PlaybackControls {
 public:
  static constexpr double kMostSpeed = 2000;

  // Reads the log through once (its run and last step); throws naming the log if it holds no run.
  LogPlayer(WatchState& state, const ProtocolConfig& protocol, PlayerOptions options, spdlog::logger& log);
  ~LogPlayer() override;

  // Plays until stop() (on this thread).
  void run();
  void stop();

  // "play", "pause", "step", "seek" (value: a step), "speed" (value: steps a second); "" or why not.
  std::string control(const std::string& command, const std::string& value) override;
  // The state of step `step` (from the start again if it is behind), fed on this thread: run()'s, or the
  // caller's while run() is not running.
  void seekTo(std::int64_t step);

  const std::string& runId() const { return run_id_; }
  std::int64_t firstStep() const { return first_; }
  std::int64_t lastStep() const { return last_; }

 private:
  void rewind();
  // Feeds every message up to and including step `target` of the run; false at the end of the log.
  bool feedThrough(std::int64_t target);
  std::optional<std::int64_t> nextStep();  // of the run's next message, read ahead (its configuration taken at once)
  void published();                        // the controls' state to the page

  WatchState& state_;
  const ProtocolConfig& protocol_;
  PlayerOptions options_;
  spdlog::logger& log_;
  std::shared_ptr<const BusKey> key_;
  std::string run_id_;
  std::int64_t first_ = -1, last_ = -1, at_ = -1;  // the log's first and last step of the run, the step shown
  std::unique_ptr<StepOrderedLog<RecordedLogStream, RunSelector>> in_;
  std::unique_ptr<ViewFeed> feed_;
  std::optional<LogEvent> ahead_;
  StepKey ahead_key_;
  bool ended_ = false;

  std::mutex mutex_;
  std::condition_variable cv_;
  bool playing_ = true, stop_ = false;
  double speed_ = 20;
  std::optional<std::int64_t> seek_;
  int steps_asked_ = 0;
};

}  // namespace afford

#include "experiment/watch/player.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "experiment/replay/replay.hpp"
#include "viewer/feed.hpp"

namespace afford {

using Clock = std::chrono::steady_clock;

LogPlayer::LogPlayer(WatchState& state, const ProtocolConfig& protocol, PlayerOptions options, spdlog::logger& log)
    : state_(state), protocol_(protocol), options_(std::move(options)), log_(log) {
  if (!(options_.speed > 0 && options_.speed <= kMostSpeed))
    throw std::runtime_error("--speed must be above 0 and at most " + std::to_string(static_cast<int>(kMostSpeed)));
  key_ = options_.bus_key.empty() ? nullptr : busKeyFrom(options_.bus_key);
  // Read through once for the step of every message of the run (the first run, or --run's): it is played in
  // step order, whatever the log's interleaving of its channels.
  in_ = std::make_unique<StepOrderedLog<RecordedLogStream, RunSelector>>(
      [this](spdlog::logger& l) { return std::make_unique<RecordedLogStream>(options_.log, l, key_.get()); },
      [this](spdlog::logger& l) { return std::make_unique<RunSelector>(options_.run_id, options_.log.string(), l); },
      protocol_, log_);
  first_ = in_->order().firstStep();
  last_ = in_->order().lastStep();
  playing_ = options_.play;
  speed_ = options_.speed;
  rewind();
  nextStep();  // the run's configuration taken: the run shown
  run_id_ = feed_->shown();
  if (run_id_.empty()) in_->selector().check(in_->cut(), in_->stream().counts().key);  // no RUN_CONFIG: why (a key?)
  if (run_id_.empty() || first_ < 0)
    throw std::runtime_error(options_.log.string() + ": no " +
                             (options_.run_id.empty() ? "run" : "message of run '" + options_.run_id + "'") + " in it");
  feedThrough(first_);
  published();
}

LogPlayer::~LogPlayer() = default;

void LogPlayer::rewind() {
  state_.clearRun();
  if (feed_) in_->order().rewind();  // (from the start again: built, it is there)
  feed_ = std::make_unique<ViewFeed>(state_, protocol_, options_.run_id);
  ahead_.reset();
  ended_ = false;
  at_ = -1;
}

std::optional<std::int64_t> LogPlayer::nextStep() {
  while (!ended_) {
    if (!ahead_) {
      LogEvent e;
      if (!in_->next(e, ahead_key_)) {
        ended_ = true;
        break;
      }
      ahead_ = std::move(e);
    }
    if (ahead_key_.step != StepKey::kBefore && ahead_key_.step != StepKey::kAfter) return ahead_key_.step;
    std::string why;  // the run's configuration and START, or STOP: taken at once
    if (!feed_->take(*ahead_, why)) log_.warn("{}: {}: skipped", ahead_->channel, why);
    ahead_.reset();
  }
  return std::nullopt;
}

bool LogPlayer::feedThrough(std::int64_t target) {
  for (;;) {
    const std::optional<std::int64_t> next = nextStep();
    if (!next) return false;
    if (*next > target) return true;
    std::string why;
    if (!feed_->take(*ahead_, why)) log_.warn("{}: {}: skipped", ahead_->channel, why);
    at_ = std::max(at_, *next);
    ahead_.reset();
  }
}

void LogPlayer::seekTo(std::int64_t step) {
  if (step < at_) rewind();
  feedThrough(step);
}

void LogPlayer::published() {
  std::lock_guard<std::mutex> lock(mutex_);
  state_.setPlayback(playing_, speed_, last_);
}

std::string LogPlayer::control(const std::string& command, const std::string& value) {
  double number = 0;
  const bool needs_number = command == "seek" || command == "speed";
  if (needs_number) {
    try {
      std::size_t used = 0;
      number = std::stod(value, &used);
      if (used != value.size() || !std::isfinite(number)) throw std::invalid_argument(value);
    } catch (const std::exception&) {
      return command + ": value '" + value.substr(0, 40) + "' is not a number";
    }
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (command == "play") playing_ = true;
    else if (command == "pause") playing_ = false;
    else if (command == "step") playing_ = false, steps_asked_ = std::min(steps_asked_ + 1, 1000);
    else if (command == "seek") {
      if (number < first_ || number > last_)
        return "seek: step " + value + " is not in the run (" + std::to_string(first_) + " to " + std::to_string(last_) + ")";
      seek_ = static_cast<std::int64_t>(number);
    } else if (command == "speed") {
      if (!(number > 0 && number <= kMostSpeed))
        return "speed: " + value + " steps a second is not within (0, " + std::to_string(static_cast<int>(kMostSpeed)) + "]";
      speed_ = number;
    } else {
      return "command '" + command.substr(0, 40) + "' is none of play, pause, step, seek, speed";
    }
  }
  cv_.notify_all();
  published();
  return "";
}

void LogPlayer::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
}

void LogPlayer::run() {
  auto next_at = Clock::now();
  for (;;) {
    std::optional<std::int64_t> seek;
    bool step = false;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      const bool due = playing_ && !ended_;
      if (due) cv_.wait_until(lock, next_at, [&] { return stop_ || seek_ || steps_asked_ > 0 || !playing_; });
      else cv_.wait(lock, [&] { return stop_ || seek_ || steps_asked_ > 0 || (playing_ && !ended_); });
      if (stop_) return;
      seek.swap(seek_);
      if (steps_asked_ > 0) --steps_asked_, step = true;
      if (!seek && !step && !(playing_ && Clock::now() >= next_at)) {
        if (playing_) continue;
        next_at = Clock::now();
        continue;
      }
    }
    if (seek) {
      seekTo(*seek);
    } else if (const auto next = nextStep()) {
      feedThrough(*next);
    }
    if (ended_ && !ahead_) {
      std::lock_guard<std::mutex> lock(mutex_);
      playing_ = false;
    }
    next_at = std::max(next_at + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / speed_)),
                       Clock::now() - std::chrono::milliseconds(100));
    published();
  }
}

}  // namespace afford

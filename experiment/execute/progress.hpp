// Progress of a phase's runs as they go: a line per job slot (the run, its
// step out of its total, steps per second) and one for the phase (runs done,
// an estimate of the time left). On a terminal the lines are a board redrawn
// in place below everything else printed (terminal.hpp: every line printed
// meanwhile stays above it, and its last drawing stays at the end); otherwise
// they are printed as plain lines at most every few seconds. Drawing is driven
// by events (a run starts, a process reports its step in its STATUS
// heartbeat, a run ends); the clock only paces the drawing and measures
// rates, it decides nothing.
#pragma once
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace afford {

class TerminalRelay;  // terminal.hpp

struct ProgressOptions {
  std::string mode = "auto";  // auto (terminal if stderr is one, else lines), terminal, lines, none
  double every = -1;          // seconds between draws (< 0: 0.25 on a terminal, 30 as lines)
  std::function<void(const std::string&)> write;  // each line drawn, in the place of the FILE (lines only)
};

class Progress {
 public:
  // `phase`: what the runs are ("intrinsic runs", "extrinsic tests"); `steps`:
  // each run still to do, its steps; `done`/`planned`: the phase's runs.
  Progress(const ProgressOptions& options, std::string phase, int slots, std::vector<std::int64_t> steps,
           std::size_t done, std::size_t planned, std::FILE* out = stderr);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // A new phase on the same board: its runs and steps replace the last phase's.
  void restart(std::string phase, std::vector<std::int64_t> steps, std::size_t done, std::size_t planned);
  // More runs for the board (a queue of experiments: each phase of each adds its own).
  void add(const std::vector<std::int64_t>& steps, std::size_t done, std::size_t planned);
  // What the board's first line calls the runs.
  void relabel(std::string phase);
  // Runs counted twice (started ahead of their phase, then counted again as kept by it): once less.
  void uncount(std::size_t finished);

  void started(int slot, const std::string& run_id, std::int64_t steps);
  void step(int slot, std::int64_t step);
  // The slot's run waits for these processes (not heard: RunDriver::onWaiting), "" once it does not: the board
  // says so instead of a time left that would only grow.
  void waiting(int slot, const std::string& processes);
  void ended(int slot, bool finished);
  // Print something (a log line): above the board, which is drawn anew below it.
  void say(const std::function<void()>& print);

 private:
  using Clock = std::chrono::steady_clock;
  struct Slot {
    std::string run_id;
    std::int64_t step = 0, steps = 0;
    Clock::time_point since{};
    std::string waiting;  // processes the run waits for
  };
  void draw(bool force);
  std::vector<std::string> lines() const;

  std::mutex mutex_;
  std::FILE* out_;
  std::function<void(const std::string&)> write_;  // (ProgressOptions::write)
  bool terminal_ = false, enabled_ = true;
  double every_ = 30;
  std::string phase_;
  std::vector<Slot> slots_;
  std::int64_t total_steps_ = 0, done_steps_ = 0;
  std::size_t done_ = 0, planned_ = 0;
  Clock::time_point began_ = Clock::now(), drawn_at_{};
  std::unique_ptr<TerminalRelay> relay_;  // (on a terminal) the terminal's one writer
};

// "1 h 02 min", "4 min 10 s", "12 s".
std::string durationText(double seconds);

}  // namespace afford

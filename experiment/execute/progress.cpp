#include "experiment/execute/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "experiment/execute/terminal.hpp"

namespace afford {

std::string durationText(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[48];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%ld h %02ld min", s / 3600, (s % 3600) / 60);
  else if (s >= 60)
    std::snprintf(buf, sizeof buf, "%ld min %02ld s", s / 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld s", s);
  return buf;
}

Progress::Progress(const ProgressOptions& options, std::string phase, int slots, std::vector<std::int64_t> steps,
                   std::size_t done, std::size_t planned, std::FILE* out)
    : out_(out), write_(options.write), phase_(std::move(phase)), slots_(static_cast<std::size_t>(std::max(slots, 0))), done_(done),
      planned_(planned) {
  if (options.mode == "none") enabled_ = false;
  else if (options.mode == "terminal") terminal_ = true;
  else if (options.mode == "auto") terminal_ = !write_ && isatty(fileno(out)) == 1;
  else if (options.mode != "lines")
    throw std::invalid_argument("--progress must be auto, terminal, lines or none, not \"" + options.mode + "\"");
  if (write_) terminal_ = false;  // lines to a function: no board to redraw
  if (terminal_ && enabled_) {
    relay_ = std::make_unique<TerminalRelay>(out_);
    if (!relay_->started()) {  // (no process could be started) plain lines, which never erase anything
      relay_.reset();
      terminal_ = false;
    }
  }
  every_ = options.every >= 0 ? options.every : terminal_ ? 0.25 : 30;
  total_steps_ = std::accumulate(steps.begin(), steps.end(), std::int64_t{0});
  drawn_at_ = began_;
}

// The board's last drawing stays as it is (a fresh one would be drawn over it: over the lines another process,
// e.g. a `tee` of the standard output, may have printed below it since).
Progress::~Progress() {
  std::lock_guard<std::mutex> lock(mutex_);
  relay_.reset();
}

void Progress::restart(std::string phase, std::vector<std::int64_t> steps, std::size_t done, std::size_t planned) {
  std::lock_guard<std::mutex> lock(mutex_);
  phase_ = std::move(phase);
  total_steps_ = std::accumulate(steps.begin(), steps.end(), std::int64_t{0});
  done_steps_ = 0;
  done_ = done;
  planned_ = planned;
  began_ = drawn_at_ = Clock::now();
}

void Progress::add(const std::vector<std::int64_t>& steps, std::size_t done, std::size_t planned) {
  std::lock_guard<std::mutex> lock(mutex_);
  total_steps_ += std::accumulate(steps.begin(), steps.end(), std::int64_t{0});
  done_ += done;
  planned_ += planned;
}

void Progress::relabel(std::string phase) {
  std::lock_guard<std::mutex> lock(mutex_);
  phase_ = std::move(phase);
}

void Progress::uncount(std::size_t finished) {
  std::lock_guard<std::mutex> lock(mutex_);
  finished = std::min({finished, done_, planned_});
  done_ -= finished;
  planned_ -= finished;
}

void Progress::started(int slot, const std::string& run_id, std::int64_t steps) {
  std::lock_guard<std::mutex> lock(mutex_);
  slots_.at(static_cast<std::size_t>(slot)) = {run_id, 0, steps, Clock::now(), {}};
  draw(false);
}

void Progress::step(int slot, std::int64_t step) {
  std::lock_guard<std::mutex> lock(mutex_);
  Slot& s = slots_.at(static_cast<std::size_t>(slot));
  if (s.run_id.empty()) return;
  s.step = std::max(s.step, std::min(step, s.steps));
  draw(false);
}

void Progress::waiting(int slot, const std::string& processes) {
  std::lock_guard<std::mutex> lock(mutex_);
  Slot& s = slots_.at(static_cast<std::size_t>(slot));
  if (s.run_id.empty() || s.waiting == processes) return;
  s.waiting = processes;
  draw(true);
}

void Progress::ended(int slot, bool finished) {
  std::lock_guard<std::mutex> lock(mutex_);
  Slot& s = slots_.at(static_cast<std::size_t>(slot));
  if (finished) {
    done_steps_ += s.steps;
    ++done_;
  }
  s = Slot{};
  draw(false);
}

void Progress::say(const std::function<void()>& print) {
  std::lock_guard<std::mutex> lock(mutex_);
  print();
  draw(true);
}

std::vector<std::string> Progress::lines() const {
  std::vector<std::string> out;
  const auto now = Clock::now();
  std::int64_t under_way = 0;
  std::string waiting;  // for processes not heard: no estimate of the time left (it would only grow)
  char buf[256];
  for (std::size_t k = 0; k < slots_.size(); ++k) {
    const Slot& s = slots_[k];
    if (s.run_id.empty()) {
      std::snprintf(buf, sizeof buf, "  slot %zu: idle", k);
    } else {
      const double t = std::chrono::duration<double>(now - s.since).count();
      std::snprintf(buf, sizeof buf, "  slot %zu: %s step %lld/%lld (%.0f steps/s)", k, s.run_id.c_str(),
                    static_cast<long long>(s.step), static_cast<long long>(s.steps), t > 0 ? s.step / t : 0.0);
      if (!s.waiting.empty()) {
        std::snprintf(buf, sizeof buf, "  slot %zu: %s step %lld/%lld, waiting for %s", k, s.run_id.c_str(),
                      static_cast<long long>(s.step), static_cast<long long>(s.steps), s.waiting.c_str());
        waiting += (waiting.empty() ? "" : ", ") + s.waiting;
      }
    }
    under_way += s.step;
    out.emplace_back(buf);
  }
  const double elapsed = std::chrono::duration<double>(now - began_).count();
  const std::int64_t done = done_steps_ + under_way;
  std::string left = "estimating the time left";
  if (!waiting.empty())
    left = "waiting for " + waiting;
  else if (done > 0 && elapsed > 0 && total_steps_ > 0)
    left = "about " + durationText((total_steps_ - done) / (done / elapsed)) + " left";
  std::snprintf(buf, sizeof buf, "%s: %zu of %zu done, %.0f%% of the steps, %s (%s so far)", phase_.c_str(),
                done_, planned_,
                total_steps_ > 0 ? 100.0 * static_cast<double>(done) / total_steps_ : 100.0, left.c_str(),
                durationText(elapsed).c_str());
  out.insert(out.begin(), buf);
  return out;
}

void Progress::draw(bool force) {
  if (!enabled_) return;
  const auto now = Clock::now();
  if (!force && std::chrono::duration<double>(now - drawn_at_).count() < every_) return;
  if (!terminal_ && force) return;  // as lines: only at its pace
  drawn_at_ = now;
  const std::vector<std::string> text = lines();
  if (terminal_) {
    relay_->show(text);
    return;
  }
  std::string one = "progress: " + text.front();
  for (std::size_t k = 1; k < text.size(); ++k) one += ";" + text[k].substr(1);
  if (write_) {
    write_(one);
    return;
  }
  std::fprintf(out_, "%s\n", one.c_str());
  std::fflush(out_);
}

}  // namespace afford

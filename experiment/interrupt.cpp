// SIGINT and SIGTERM during an experiment (experiment/pipeline.hpp): the first
// stops the runs under way in order, what finished is written and the
// command that resumes is said; a second quits at once.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstring>

#include "afford/process_main.hpp"
#include <nlohmann/json.hpp>

#include <filesystem>

#include "experiment/pipeline.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

volatile std::sig_atomic_t g_signal = 0;  // the first SIGINT or SIGTERM received (0: none)
// What a second signal says, in one of two buffers: the handler writes the one g_quit names; a new message is
// made in the other, then named, so that the handler never reads one being written.
char g_quit_text[2][4096];
std::size_t g_quit_size[2] = {0, 0};
std::atomic<int> g_quit{0};

void onInterrupt(int sig) {
  if (g_signal != 0) {  // a second one: quit now; every file written so far is whole (written aside, then renamed)
    const int q = g_quit.load(std::memory_order_acquire);
    (void)!write(STDERR_FILENO, g_quit_text[q], g_quit_size[q]);
    _exit(128 + sig);
  }
  g_signal = sig;
  static const char msg[] =
      "\nafford: stopping the runs under way, then writing what finished (a second signal quits at once)\n";
  (void)!write(STDERR_FILENO, msg, sizeof msg - 1);
  requestStop();  // (stopRequested(): the drivers stop their runs)
}

void sayOnQuit(const std::string& text) {
  const int next = 1 - g_quit.load(std::memory_order_relaxed);
  g_quit_size[next] = std::min(text.size(), sizeof g_quit_text[next]);
  std::memcpy(g_quit_text[next], text.data(), g_quit_size[next]);
  g_quit.store(next, std::memory_order_release);
}

}  // namespace

void installInterruptHandlers(const std::string& resume) {
  sayOnQuit("\nafford: a second signal: quitting at once; what finished is kept." +
            (resume.empty() ? std::string() : " To resume: " + resume) + "\n");
  struct sigaction sa {};
  sa.sa_handler = onInterrupt;
  sigemptyset(&sa.sa_mask);
  sigaddset(&sa.sa_mask, SIGINT);
  sigaddset(&sa.sa_mask, SIGTERM);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

InterruptScope::InterruptScope() {
  sigaction(SIGINT, nullptr, &int_);
  sigaction(SIGTERM, nullptr, &term_);
  installInterruptHandlers("");  // from here, before the experiment is even checked, a signal stops it
}

InterruptScope::~InterruptScope() {
  restore();
  g_signal = 0;
  clearStopRequest();  // and its reason
}

int InterruptScope::restore() {
  sigaction(SIGINT, &int_, nullptr);
  sigaction(SIGTERM, &term_, nullptr);
  return g_signal;
}

std::string InterruptScope::stoppedFor() const { return stopReason(); }

// The reason is kept beside the stop itself (afford/process_main.hpp), where a lower layer may give one too: a
// runner that finds another driving its bus (experiment/run/runners.hpp).
void stopExperiment(const std::string& why) { requestStop(why.empty() ? "stopped" : why); }

// A stop the program asked for counts as a SIGINT (the exit status 130).
int stopSignal() {
  if (g_signal) return g_signal;
  return stopReason().empty() ? 0 : SIGINT;
}

namespace {
std::string signalName(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : std::to_string(sig); }

bool elsewhere(const PhaseRuns& phase, std::size_t i) { return !phase.elsewhere.empty() && phase.elsewhere[i]; }

}  // namespace

std::string stoppedShort(const PhaseRuns& phase, const SlotPool* pool) {
  if (g_signal) return signalName(g_signal);
  if (std::string why = stopReason(); !why.empty()) return why;
  if (pool)
    if (std::string why = pool->halted(); !why.empty()) return why;
  for (std::size_t i = 0; i < phase.finished.size(); ++i)
    if (!phase.finished[i] && !elsewhere(phase, i)) return "runs that did not run";
  return "";
}

// Once the runs under way have stopped: the summary of what finished, where the others stopped, and the command
// that goes on. `phase_name` is "intrinsic" or "extrinsic"; `why` what stopped it (stoppedShort).
Interruption interruption(const std::string& phase_name, const std::vector<PlannedRun>& runs, const PhaseRuns& phase,
                          bool extrinsic_to_come, const ExperimentRequest& o, const std::string& why) {
  Interruption in;
  in.signal = why;
  in.phase = phase_name;
  in.finished = static_cast<std::int64_t>(phase.finishedCount());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (elsewhere(phase, i)) continue;  // another shard's
    ++in.planned;
    if (phase.finished[i]) continue;
    const std::string& id = runs[i].spec.run_id;
    const fs::path dir = fs::path(o.plan.log_root) / id;
    if (auto c = phase.cut.find(i); c != phase.cut.end())
      in.cut.push_back({id, c->second, fs::exists(dir) ? Nullable<std::string>(dir.string()) : Nullable<std::string>()});
    else
      in.not_started.push_back(id);
  }
  in.extrinsic_tests_to_come = extrinsic_to_come;
  in.resume = resumeCommand(o);
  in.resume_in = fs::current_path().string();
  return in;
}

// Once `in` is in summary.json: the experiment's state says so, and the log what is kept and what comes. Returns
// the exit status: 128 + the signal's number, or 1 when the program stopped it (a run that could not begin).
int stopHere(const Interruption& in, const ExperimentRequest& o, ExperimentState& state, spdlog::logger& log) {
  const std::string &signal = in.signal, &phase_name = in.phase, &cwd = in.resume_in, &command = in.resume;
  state.state = "interrupted";
  state.interruptions.push_back({signal, phase_name, in.cut});
  writeState(o.write.out_dir, state);

  const std::string what = phase_name == "intrinsic" ? "intrinsic run(s)" : "extrinsic test(s)";
  if (stopSignal())
    log.warn("interrupted by {} during the {} phase", signal, phase_name);
  else
    log.error("stopped during the {} phase: {} (said above); what did not run is not marked done and runs when the "
              "experiment is resumed",
              phase_name, signal);
  log.info("kept: {} of {} {} finished{}, in {} and the CSV files beside it", in.finished, in.planned, what,
           phase_name == "extrinsic" ? " (and every intrinsic run)" : "",
           (fs::path(o.write.out_dir) / "summary.json").string());
  for (const CutRun& c : in.cut)
    log.info("cut: {} ({}){}", c.run_id, c.where, c.log_dir ? "; its log, incomplete, stays in " + *c.log_dir : "");
  if (!in.not_started.empty()) log.info("not started: {} {}", in.not_started.size(), what);
  if (in.extrinsic_tests_to_come) log.info("not started: the extrinsic tests");
  log.warn("to resume (in {}): {}", cwd, command);
  return stopSignal() ? 128 + stopSignal() : 1;
}


}  // namespace afford

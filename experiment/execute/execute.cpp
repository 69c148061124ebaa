#include "experiment/execute/execute.hpp"

#include "afford/bus.hpp"
#include "afford/names.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <sstream>
#include <thread>

#include "experiment/run/group.hpp"
#include "experiment/run/host.hpp"
#include "afford/logging.hpp"
#include "afford/processes.hpp"
#include "experiment/execute/bus_note.hpp"
#include "experiment/execute/progress.hpp"
#include "experiment/execute/run_folder.hpp"
#include "experiment/run/outcome.hpp"
#include "experiment/schema/summary.hpp"
#include "afford/config.hpp"
#include "afford/process_main.hpp"

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

struct Slot {
  int index = 0;
  std::string url;
  // What the slot's processes (or nodes) were started for: the experiment folder they write in, the log
  // root, the transport and the options they were started with. A run for another starts them afresh.
  std::string serving;
  // As many slots as cores, or more: no core is free for the eye to scan ahead with (its `--speculate`).
  bool machine_full = false;
  std::unique_ptr<ProcessGroup> group;   // environment, eye, predictors, and motivation or planner
  Phase phase = Phase::Intrinsic;        // the phase whose processes the group (or the host) has
  std::unique_ptr<ProcessGroup> logger;  // started with the slot's first recorded run, kept for the others
  // One bus connection and driver for all the slot's runs: the driver keeps
  // what each process last said, so a run starts as soon as they are free.
  std::unique_ptr<lcm::LCM> lcm;
  std::unique_ptr<RunDriver> driver;
  // Over memq, the slot's nodes in this process, kept between its runs as a
  // udpm slot keeps its processes (declared after the bus they are on).
  std::unique_ptr<InProcessHost> host;
};

namespace {

// Handle what is pending (up to a batch), or wait briefly for something.
void pumpLcm(lcm::LCM& lcm) { pumpBus(lcm, 5, 512); }

// What the runner is told while a run goes: each process's step (the progress display), each table of its curve.
struct RunHooks {
  std::function<void(std::int64_t)> step;
  std::function<void(const TableSnapshot&)> table;
  std::function<void(const std::string&)> waiting;  // processes not heard (RunDriver::onWaiting)
};



// Start the slot afresh (its bus, driver and processes or nodes) when the run is of the other phase, or for
// another folder, log root, transport or process options: the driver's memory of the processes is of theirs.
void serve(Slot& slot, const PlannedRun& run, const HostRequest& o, const std::string& log_root,
           const std::string& out_dir) {
  std::string key = std::string(nameOf(kPhaseNames, run.spec.phase)) + '\n' + o.transport + '\n' + out_dir + '\n' + log_root + '\n' + o.bus_key + '\n' + o.process_log_level;
  for (const auto& [name, cmd] : o.processes) key += '\n' + name + '=' + cmd;
  if (key == slot.serving) return;
  slot.host.reset();  // its nodes are on the slot's bus: gone first
  slot.logger.reset();
  slot.group.reset();
  slot.driver.reset();
  slot.lcm.reset();
  slot.serving = std::move(key);
}

// A run over, its processes' snapshots go: each removes its own on the run's STOP, but a process that never
// took the STOP (a host replaced between phases, one killed and not restarted) leaves it.
void removeSnapshots(const fs::path& run_dir) {
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(run_dir, ec)) {
    const fs::path& p = f.path();
    if (p.extension() == ".snapshot" || (p.extension() == ".tmp" && p.stem().extension() == ".snapshot"))
      fs::remove(p, ec);
  }
}

RunOutcome runInProcess(const PlannedRun& run, const HostRequest& o, const std::string& log_root,
                        const ProtocolConfig& protocol, Slot& slot, const RunHooks& hooks) {
  const std::string tag = o.jobs > 1 ? "#" + std::to_string(slot.index) : "";
  const std::string level = o.process_log_level == "info" ? "warn" : o.process_log_level;
  if (!slot.lcm) {
    slot.lcm = std::make_unique<lcm::LCM>("memq://");
    slot.driver = std::make_unique<RunDriver>(*slot.lcm, makeLogger("runner" + tag, level), protocol);
  }
  // Each phase has its own processes (and deciders): another phase, a new host.
  if (!slot.host || slot.phase != run.spec.phase) {
    slot.host.reset();
    slot.phase = run.spec.phase;
    slot.host = std::make_unique<InProcessHost>(
        *slot.lcm, protocol, [tag, level](const std::string& p) { return makeLogger(p + tag, level); },
        HostOptions{/*single_thread=*/true, log_root, nullptr, /*snapshot_root=*/log_root, /*fork_snapshots=*/false,
                    /*runner_says_failures=*/true});
  }
  // The logger, once started with a recorded run, stays free during the runs not recorded (run.record).
  for (const std::string& p : run.spec.processes)
    if (!slot.host->hosts(p)) slot.host->start(p);
  InProcessHost& host = *slot.host;
  lcm::LCM& lcm = *slot.lcm;
  slot.driver->onStep(hooks.step);
  slot.driver->onTable(hooks.table);
  slot.driver->onWaiting(hooks.waiting);
  RunOutcome r = slot.driver->run(
      run.spec,
      [&] {
        pumpLcm(lcm);
        host.tick();
      },
      [] { return std::string(); });
  r.peak_rss_kb["all (one process)"] = peakRssKb(getpid());
  if (!r.ok) slot.host.reset();  // a host whose run failed is not reused
  return r;
}

RunOutcome runOverUdpm(const PlannedRun& run, const HostRequest& o, const std::string& log_root,
                       const std::string& out_dir, const ProtocolConfig& protocol, Slot& slot, const std::string& bin,
                       const RunHooks& hooks) {
  const std::string out = (fs::path(out_dir) / "processes" / ("slot" + std::to_string(slot.index))).string();
  const bool attached = !o.attach.empty();  // the user started the processes; none are ours to start
  // The runner listens before it starts any process: it hears each one's first STATUS.
  if (!slot.lcm) {
    // This thread only watches the runs (see kWatcherNice); LCM's receive
    // thread, created on the first handle(), inherits the priority.
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), kWatcherNice);
    try {
      slot.lcm = openBus(slot.url, protocol.bus);
    } catch (const std::exception& e) {
      RunOutcome r;
      r.error = "run '" + run.spec.run_id + "': cannot open the bus " + slot.url + ": " + e.what();
      r.unreached = true;  // nothing was said to any process
      return r;
    }
    slot.driver = std::make_unique<RunDriver>(*slot.lcm, makeLogger("runner", "warn"), protocol);
    slot.driver->useBusKey(busKeyFrom(o.bus_key));
  }
  // The processes' own arguments: the bus's key (if given here; they read $AFFORD_BUS_KEY themselves), and
  // the folder each writes in.
  std::vector<std::string> common;
  if (!o.bus_key.empty()) common = {"--bus-key", fs::absolute(o.bus_key).string()};
  if (o.process_log_level != "info") common.insert(common.end(), {"--log-level", o.process_log_level});
  if (!attached && (!slot.group || !slot.group->health().empty() || slot.phase != run.spec.phase)) {
    slot.group.reset();
    slot.phase = run.spec.phase;
    std::map<std::string, std::vector<std::string>> own{{"predictors", {"--checkpoint-dir", log_root}}};
    if (!o.processes.count("eye")) own["eye"] = {"--speculate", slot.machine_full ? "off" : "on"};  // ours only
    // Every process's snapshots in the log root, a --process command's too (processMain gives it --state-dir):
    // else its default, $AFFORD_LOGS or the working folder's logs/.
    for (const std::string& p : runProcesses(run.spec.phase, /*recorded=*/false))
      own[p].insert(own[p].end(), {"--state-dir", log_root});
    slot.group = std::make_unique<ProcessGroup>(bin, runProcesses(run.spec.phase, /*recorded=*/false), slot.url,
                                                out, common, own, o.processes);
  }
  // The logger serves the slot's runs one after another; those not to be kept
  // say so in their configuration (run.record), and it stays free during them.
  if (run.keep_log && !attached && (!slot.logger || !slot.logger->health().empty()))
    slot.logger = std::make_unique<ProcessGroup>(
        bin, std::vector<std::string>{"logger"}, slot.url, out, common,
        std::map<std::string, std::vector<std::string>>{{"logger", {"--log-dir", log_root}}}, o.processes);
  lcm::LCM& lcm = *slot.lcm;
  RunDriver& driver = *slot.driver;
  driver.onStep(hooks.step);
  driver.onTable(hooks.table);
  driver.onWaiting(hooks.waiting);
  auto health = [&]() {
    std::string h = slot.group ? slot.group->health() : std::string();
    if (h.empty() && slot.logger && run.keep_log) h = slot.logger->health();
    return h;
  };
  RunOutcome r = driver.run(run.spec, [&] { pumpLcm(lcm); }, health);
  if (slot.group) r.peak_rss_kb = slot.group->peakRssKb();
  if (slot.logger && run.keep_log)
    for (const auto& [name, kb] : slot.logger->peakRssKb()) r.peak_rss_kb[name] = kb;
  r.peak_rss_kb["runner"] = peakRssKb(getpid());  // this process: the runs' driver and whatever it keeps
  if (!r.ok) {  // a broken group is not reused
    slot.group.reset();
    slot.logger.reset();
  }
  return r;
}

}  // namespace

void checkHostRequest(const HostRequest& o) {
  if (o.jobs < 1) throw ConfigError("--jobs must be at least 1, not " + std::to_string(o.jobs));
  if (!(o.stall_seconds > 0))
    throw ConfigError("--stall-seconds must be more than 0, not " + (std::ostringstream() << o.stall_seconds).str() +
                      ": a run is failed after this many seconds without progress");
  if (!o.attach.empty() && (o.jobs != 1 || o.transport != "udpm"))
    throw ConfigError("--attach runs one run at a time over the given bus: it needs --jobs 1 and --transport udpm");
  if (o.transport != "udpm" && o.transport != "memq")
    throw ConfigError("--transport must be udpm or memq, not \"" + o.transport + "\"");
  if (o.shard_count && (o.shard_count < 1 || o.shard_index < 0 || o.shard_index >= o.shard_count))
    throw ConfigError("--shard must be i/n with 0 <= i < n, not " + std::to_string(o.shard_index) + "/" +
                      std::to_string(o.shard_count));
}

std::vector<char> shardMask(const HostRequest& o, std::size_t n) {
  std::vector<char> mask;
  if (o.shard_count > 0)
    for (std::size_t k = 0; k < n; ++k)
      mask.push_back(static_cast<int>(k % static_cast<std::size_t>(o.shard_count)) != o.shard_index);
  return mask;
}

PhaseRuns slicePhase(const PhaseRuns& all, std::size_t offset, std::size_t n) {
  PhaseRuns p;
  p.outcomes.assign(all.outcomes.begin() + offset, all.outcomes.begin() + offset + n);
  p.finished.assign(all.finished.begin() + offset, all.finished.begin() + offset + n);
  if (!all.elsewhere.empty()) p.elsewhere.assign(all.elsewhere.begin() + offset, all.elsewhere.begin() + offset + n);
  for (const auto& [i, where] : all.cut)
    if (i >= offset && i < offset + n) p.cut[i - offset] = where;
  return p;
}

std::string movedPath(std::string path, const std::vector<PathMove>& moves) {
  for (const PathMove& m : moves)
    if (path == m.from || path.rfind(m.from + "/", 0) == 0) path = m.to + path.substr(m.from.size());
  return path;
}

// The outcomes kept by an earlier invocation (--resume); none on a fresh start.
PhaseRuns keptRuns(const std::vector<PlannedRun>& runs, const fs::path& out, const std::vector<PathMove>& moves) {
  PhaseRuns phase;
  phase.outcomes.resize(runs.size());
  phase.finished.assign(runs.size(), 0);
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (auto r = keptOutcome(out, runs[i].spec)) {
      if (!r->checkpoint.empty()) r->checkpoint = movedPath(r->checkpoint, moves);
      if (!r->log_dir.empty()) r->log_dir = movedPath(r->log_dir, moves);
      phase.outcomes[i] = std::move(*r);
      phase.finished[i] = 1;
    }
  return phase;
}

// A run that did not finish may have left its folder (an incomplete log): it
// is never reused nor deleted, but moved aside as <run-id>.cut-<k>, and the
// run starts afresh.
std::vector<MovedAside> moveUnfinishedAside(const std::vector<PlannedRun>& runs, const PhaseRuns& phase,
                                            const std::string& log_root, const std::string& out_dir,
                                            spdlog::logger& log) {
  std::vector<MovedAside> moved;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const fs::path dir = fs::path(log_root) / runs[i].spec.run_id;
    // (Another shard's run is its own; a folder claimed and never begun is the run's, as it is.)
    if (phase.finished[i] || (!phase.elsewhere.empty() && phase.elsewhere[i]) || !fs::exists(dir) ||
        onlyClaimed(dir, out_dir))
      continue;
    if (const std::string whose = anotherHolder(dir, out_dir); !whose.empty())
      throw ConfigError("--resume: run '" + runs[i].spec.run_id + "' did not finish, and its log folder " +
                        dir.string() + " is another experiment's (" + whose +
                        "): it is not moved aside; move it away yourself, or resume where the experiment started");
    fs::path aside;
    for (int k = 1; fs::exists(aside = dir.string() + ".cut-" + std::to_string(k)); ++k) {
    }
    fs::rename(dir, aside);
    moved.push_back({runs[i].spec.run_id, aside.string()});
    log.info("run '{}' did not finish: its folder is now {}; the run starts again", runs[i].spec.run_id, aside.string());
  }
  return moved;
}

// ---- the slots ---------------------------------------------------------------

struct SlotPool::Batch {
  std::vector<Work> works;
  std::size_t left = 0;  // works not run nor dropped yet
};

struct SlotPool::Impl {
  struct Job {
    std::shared_ptr<Batch> batch;
    std::size_t index = 0;
  };
  int jobs = 1;
  HostRequest host;
  bool queue = false;
  Progress progress;
  std::mutex mutex;
  std::condition_variable wake, finished;
  std::deque<Job> waiting;
  bool closing = false;
  std::string halted;  // why no more work starts (halt), "" while it does
  std::vector<std::thread> threads;

  Impl(const HostRequest& o, bool q, std::string label)
      : jobs(o.jobs), host(o), queue(q),
        progress(ProgressOptions{o.progress, o.progress_every, o.progress_to}, std::move(label), o.jobs, {}, 0, 0) {}

  void serveSlot(int index) {
    Slot slot;
    slot.index = index;
    slot.machine_full = jobs >= static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    slot.url = slotUrls(host)[index];
    for (;;) {
      Job job;
      {
        std::unique_lock<std::mutex> lock(mutex);
        wake.wait(lock, [&] { return closing || !waiting.empty(); });
        if (waiting.empty()) return;
        job = std::move(waiting.front());
        waiting.pop_front();
      }
      // After a stop signal or a halt the works not begun are dropped; a work never lets an exception out.
      bool dropped = stopRequested();
      {
        std::lock_guard<std::mutex> lock(mutex);
        dropped = dropped || !halted.empty();
      }
      if (!dropped) try {
          job.batch->works[job.index](slot);
        } catch (const std::exception&) {
        }
      std::lock_guard<std::mutex> lock(mutex);
      --job.batch->left;
      finished.notify_all();
    }
  }
};

SlotPool::SlotPool(const HostRequest& o, bool queue, std::string label)
    : impl_(std::make_unique<Impl>(o, queue, std::move(label))) {
  for (int k = 0; k < o.jobs; ++k) impl_->threads.emplace_back([this, k] { impl_->serveSlot(k); });
}

SlotPool::~SlotPool() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->closing = true;
  }
  impl_->wake.notify_all();
  for (auto& t : impl_->threads) t.join();
}

std::shared_ptr<SlotPool::Batch> SlotPool::submit(std::vector<Work> works) {
  auto batch = std::make_shared<Batch>();
  batch->works = std::move(works);
  batch->left = batch->works.size();
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    for (std::size_t i = 0; i < batch->works.size(); ++i) impl_->waiting.push_back(Impl::Job{batch, i});
  }
  impl_->wake.notify_all();
  return batch;
}

void SlotPool::wait(const std::shared_ptr<Batch>& batch) {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  impl_->finished.wait(lock, [&] { return batch->left == 0; });
}

void SlotPool::halt(const std::string& why) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (impl_->halted.empty()) impl_->halted = why;
}

std::string SlotPool::halted() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->halted;
}

Progress& SlotPool::progress() { return impl_->progress; }
bool SlotPool::queue() const { return impl_->queue; }
int SlotPool::slots() const { return impl_->jobs; }

namespace {

// What the runs of one executeRuns (or RunsAhead) share while they run.
struct PhaseState {
  const std::vector<PlannedRun>* runs = nullptr;
  PhaseRuns* phase = nullptr;
  RunContext c;
  OnFinished on_finished;
  std::mutex mutex;
  std::shared_ptr<Tally> tally = std::make_shared<Tally>();  // finished, for the [k/N] lines
};

// Where a process of the slot writes its output, if this runner started it (for a message about what it did
// not write; "" when its output is elsewhere: over memq in this one's, attached in its own).
std::string processLog(const RunContext& c, const Slot& slot, const std::string& process) {
  if (!c.o.attach.empty() || c.o.transport != "udpm") return "";
  return (fs::path(c.out_dir) / "processes" / ("slot" + std::to_string(slot.index)) / (process + ".log")).string();
}

// Run `planned` on the slot: its outcome, as the driver (or the bus) gave it.
RunOutcome driveOne(const RunContext& c, const PlannedRun& planned, Slot& slot, Progress& progress) {
  const HostRequest& o = c.o;
  const int slot_index = slot.index;
  RunHooks hooks;
  hooks.step = [&progress, slot_index](std::int64_t step) { progress.step(slot_index, step); };
  hooks.waiting = [&progress, slot_index](const std::string& who) { progress.waiting(slot_index, who); };
  if (o.on_curve && !planned.spec.extrinsic && !planned.target.empty())
    hooks.table = [&o, &run = planned](const TableSnapshot& t) {
      o.on_curve({run.spec.run_id, run.system, run.index, t.step, meanAbsError(t.affordance, run.target)});
    };
  PlannedRun run = planned;
  run.spec.stall_seconds = o.stall_seconds;
  RunOutcome r;
  try {
    serve(slot, run, o, c.log_root, c.out_dir);
    r = o.transport == "memq" ? runInProcess(run, o, c.log_root, c.protocol, slot, hooks)
                              : runOverUdpm(run, o, c.log_root, c.out_dir, c.protocol, slot, c.bin, hooks);
  } catch (const std::exception& e) {
    slot.host.reset();  // (memq) nodes left mid-run are not reused
    r.ok = false;
    r.error = "run '" + run.spec.run_id + "': " + e.what();
  }
  if (!r.ok) slot.serving.clear();  // the next run starts the slot afresh: its bus, driver and processes
  return r;
}

// Run i on the slot, and keep its outcome. A run that did not begin (its processes never said they were free,
// the bus did not open, its log folder is not this experiment's) is not kept: it stays to be run, and no run
// starts after it (SlotPool::halt).
void runOne(PhaseState& st, std::size_t i, Slot& slot, SlotPool& pool) {
  const std::vector<PlannedRun>& runs = *st.runs;
  PhaseRuns& phase = *st.phase;
  const RunContext& c = st.c;
  spdlog::logger& log = *c.log;
  Progress& progress = pool.progress();
  const std::string& id = runs[i].spec.run_id;
  progress.started(slot.index, id, runs[i].spec.steps);
  // Whose the run's folder is, before any process writes in it: `afford clean` checks that experiment's lock and
  // state (running, or stopped and resumable) and leaves the folder alone while it is in use.
  const fs::path run_dir = fs::path(c.log_root) / id;
  RunOutcome r;
  const std::string refused = takeRunFolder(run_dir, runs[i], c.out_dir);
  if (refused.empty()) r = driveOne(c, runs[i], slot, progress);
  removeSnapshots(run_dir);
  if (!refused.empty() || r.unreached) {
    progress.ended(slot.index, false);
    pool.halt(refused.empty() ? "processes not reached" : "a log folder not its own");
    const std::string why = refused.empty() ? r.error : "run '" + id + "': " + refused;
    progress.say([&] { log.error("{}; the run did not begin, and no other starts", why); });
    return;
  }
  // A run that fails while the processes are being stopped failed because of it: cut too.
  const bool cut = r.interrupted || (!r.ok && stopRequested());
  if (r.ok && !r.log_dir.empty()) {
    std::error_code ec;
    for (const auto& f : fs::directory_iterator(r.log_dir, ec))
      if (f.path().extension() == ".lcm") r.log_bytes += fs::file_size(f.path(), ec);
  }
  if (r.ok)  // what the run had to leave and did not is its failure, not a silent ""
    if (const std::string missing = missingOutputs(runs[i], r, processLog(c, slot, "predictors")); !missing.empty()) {
      r.ok = false;
      r.error = "run '" + id + "': " + missing;
    }
  // A run that wrote nothing in its folder (a test whose log is not kept) leaves none. (Not one cut or failed: a
  // logger may still be closing a log there, and run.json says whose it is.)
  if (r.ok) releaseUnused(run_dir, c.out_dir);
  if (!cut) try {
      keepOutcome(c.out_dir, id, r);
    } catch (const std::exception& e) {
      log.error("cannot keep the outcome of run '{}' ({}): --resume would run it again", id, e.what());
    }
  progress.ended(slot.index, !cut);
  std::unique_lock<std::mutex> lock(st.mutex);
  if (cut) {
    const std::string prefix = "run '" + id + "': ";
    std::string where = r.error.rfind(prefix, 0) == 0 ? r.error.substr(prefix.size()) : r.error;
    // (The step is the last one the processes reported, in their heartbeats.)
    if (const std::string none = "at step -1"; where.size() > none.size() && where.substr(where.size() - none.size()) == none)
      where = where.substr(0, where.size() - none.size()) + "before any step was reported";
    phase.cut[i] = where;
    progress.say([&] { log.warn("{}: {}", id, phase.cut[i]); });
    return;
  }
  phase.outcomes[i] = std::move(r);
  phase.finished[i] = 1;
  const RunOutcome& out = phase.outcomes[i];
  const std::size_t done = ++st.tally->done, total = std::max(st.tally->total, done);
  progress.say([&] {
    if (out.ok && runs[i].spec.extrinsic)
      log.info("[{}/{}] {}: {}, {}, utility {}", done, total, id,
               out.extrinsic.success ? "solved in " + counted(out.extrinsic.completion, "step") : "not solved",
               counted(out.extrinsic.attempts, "action"), out.extrinsic.utility);
    else if (out.ok)
      log.info("[{}/{}] {} done in {:.1f} s, weights {}", done, total, id, out.wall_seconds,
               out.weights_checksum);
    else
      log.error("[{}/{}] {}", done, total, out.error);
  });
  lock.unlock();
  if (st.on_finished) st.on_finished(i);
}

// The works of the runs not finished yet (nor run elsewhere), and their steps.
std::vector<SlotPool::Work> worksOf(const std::shared_ptr<PhaseState>& st, SlotPool& pool,
                                    std::vector<std::int64_t>& steps) {
  std::vector<SlotPool::Work> works;
  const PhaseRuns& phase = *st->phase;
  for (std::size_t i = 0; i < st->runs->size(); ++i)
    if (!phase.finished[i] && (phase.elsewhere.empty() || !phase.elsewhere[i])) {
      works.emplace_back([st, i, &pool](Slot& slot) { runOne(*st, i, slot, pool); });
      steps.push_back((*st->runs)[i].spec.steps);
    }
  return works;
}

}  // namespace

// Run every planned run not finished yet (nor run elsewhere) on the pool's
// slots, and keep each outcome in DIR/runs/ as it comes. After a SIGINT or
// SIGTERM no run starts; a run it stopped is cut, not finished. A run that
// could not begin (runOne) is neither: it stays to be run, and the pool halts.
void executeRuns(const std::vector<PlannedRun>& runs, PhaseRuns& phase, const RunContext& c, SlotPool& pool,
                 const OnFinished& on_finished) {
  auto st = std::make_shared<PhaseState>();
  st->runs = &runs;
  st->phase = &phase;
  st->c = c;
  st->on_finished = on_finished;
  const std::size_t done = phase.finishedCount();
  st->tally->done = done;
  st->tally->total = runs.size();
  std::vector<std::int64_t> steps;
  std::vector<SlotPool::Work> works = worksOf(st, pool, steps);
  std::size_t planned = runs.size();
  for (std::size_t i = 0; i < runs.size(); ++i) planned -= !phase.elsewhere.empty() && phase.elsewhere[i];
  Progress& progress = pool.progress();
  if (pool.queue())
    progress.add(steps, done, planned);
  else
    progress.restart(!runs.empty() && runs.front().spec.extrinsic ? "extrinsic tests" : "intrinsic runs",
                     std::move(steps), done, planned);
  pool.wait(pool.submit(std::move(works)));
}

struct RunsAhead::State : PhaseState {
  std::vector<PlannedRun> owned_runs;
  PhaseRuns owned_phase;
};

RunsAhead::RunsAhead(std::vector<PlannedRun> runs, const RunContext& c, SlotPool& pool, std::shared_ptr<Tally> tally)
    : state_(std::make_shared<State>()), pool_(pool) {
  state_->tally = std::move(tally);
  state_->owned_runs = std::move(runs);
  state_->owned_phase.outcomes.resize(state_->owned_runs.size());
  state_->owned_phase.finished.assign(state_->owned_runs.size(), 0);
  state_->runs = &state_->owned_runs;
  state_->phase = &state_->owned_phase;
  state_->c = c;
  std::vector<std::int64_t> steps;
  const std::shared_ptr<PhaseState> st = state_;
  std::vector<SlotPool::Work> works = worksOf(st, pool, steps);
  pool.progress().add(steps, 0, works.size());
  if (!pool.queue()) pool.progress().relabel("intrinsic runs, and the tests of the agents trained");
  batch_ = pool.submit(std::move(works));
}

RunsAhead::~RunsAhead() { wait(); }

std::size_t RunsAhead::wait() {
  pool_.wait(batch_);
  return state_->owned_phase.finishedCount();
}

std::map<std::string, std::string> RunsAhead::cut() const {
  std::map<std::string, std::string> out;
  for (const auto& [i, where] : state_->owned_phase.cut) out[state_->owned_runs[i].spec.run_id] = where;
  return out;
}

}  // namespace afford

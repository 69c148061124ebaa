// afford experiment NAME ...: run an experiment's repetitions and summarise them;
// afford experiment A B ... or --plan FILE: several side by side, in one queue of job slots.
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <limits>
#include <memory>
#include <set>

#include "apps/afford/commands.hpp"
#include "afford/config.hpp"
#include "experiment/experiment.hpp"
#include "experiment/state.hpp"
#include "experiment/design/experiment_file.hpp"
#include "experiment/watch/live.hpp"

namespace afford {

namespace {

struct Args {
  ExperimentRequest o;
  std::vector<std::string> names;
  std::string system, netns = "auto", file, shard, plan;
  std::vector<std::string> processes;
  bool watch = false;
  std::string watch_bind = "127.0.0.1";
  int watch_port = 8077;
  int reps = 0, tables = 0, extrinsic_reps = 0;
  std::int64_t steps = 0, table_seed = 0;
  CLI::Option* tables_option = nullptr;
  CLI::Option* table_seed_option = nullptr;
};

// The options --help lists first: the experiment, its counts and seed, jobs, transport, what is kept, settings.
void addFirstOptions(CLI::App* exp, Args& a) {
  ExperimentRequest& o = a.o;
  exp->add_option("name", a.names,
                  "experiment (see `afford experiments`); optional with --resume. Several run side by side in one "
                  "queue of job slots, each in <out>/<name>");
  exp->add_option("--plan", a.plan,
                  "a YAML list of experiments to run side by side in one queue, each an argument line of `afford "
                  "experiment` (e.g. \"late1 --system all --extrinsic-reps 10\"); the command line's options apply "
                  "to every entry that does not give its own");
  exp->add_option("--system", a.system, "FIX, IGN, IMP, all, or a list (FIX,IMP) (default: the experiment's systems, else all)");
  exp->add_option("--reps", a.reps, "repetitions per system (default: the experiment's)");
  exp->add_option("--steps", a.steps, "intrinsic steps per run (default: the experiment's)");
  exp->add_option("--jobs,-j", o.host.jobs, "runs at a time")->capture_default_str();
  exp->add_option("--seed", o.plan.seed, "seed of the first repetition (then seed+1, ...)")->capture_default_str();
  exp->add_option("--out", o.write.out_dir,
                  "folder for summary.json and CSV files (default: a new folder out/NAME, the experiment's name, "
                  "else out/NAME-2, ...; a queue's entries: OUT/NAME; with --resume: out)")->capture_default_str();
  exp->add_flag("--replace", o.write.replace,
                "--out holds a finished experiment: remove its files and write this one in their place (without "
                "it, such a folder is refused)");
  exp->add_option("--transport", o.host.transport, "udpm (real processes) or memq (one process)")->capture_default_str();
  exp->add_option("--keep-logs", o.plan.keep_logs, "which runs keep an LCM log: all, first or none")->capture_default_str();
  exp->add_option("--keep-checkpoints", o.plan.keep_checkpoints,
                  "which intrinsic runs keep their checkpoints once the experiment is over: all, first or none")
      ->capture_default_str();
  exp->add_flag("--reuse-agents,!--no-reuse-agents", o.host.reuse_agents,
                "take the trained agent of an earlier run with the same configuration and seed, stored in "
                "<log-root>/agents, instead of training it again (default: on)");
  exp->add_option("--config", a.file,
                  "an experiment file anywhere, instead of NAME (it may extend a shipped one: extends: base)");
  exp->add_option("--log-root", o.plan.log_root, "folder of the run logs (<log-root>/<run-id>/)")->capture_default_str();
  exp->add_option("--truth-dir", o.plan.truth_dir,
                  "a table world's truth, read there or estimated there first (default: <log-root>/truth; "
                  "afford tune's trials share their study's)");
  exp->add_option("--run-prefix", o.plan.run_prefix, "first part of every run id (default: date-time)");
  exp->add_option("--set", o.plan.settings,
                  "override a config value, e.g. --set motivation.leak=0.2 (repeatable); several values sweep it: "
                  "--set motivation.leak=0.1,0.2,0.4 runs each (the cross product of every swept key)");
  exp->add_option("--sweep", o.plan.sweep_file,
                  "a YAML file mapping config keys to lists of values, swept as --set key=v1,v2 would");
}

// ... then shards, the network and the processes, progress, tests, attaching and resuming.
void addMoreOptions(CLI::App* exp, Args& a) {
  ExperimentRequest& o = a.o;
  exp->add_option("--shard", a.shard,
                  "i/n: run only intrinsic runs k with k mod n == i (and their tests); `afford merge` joins the "
                  "n shards' folders (needs --run-prefix)");
  exp->add_option("--netns", a.netns, "auto, on or off: run the process group in a private network namespace")
      ->capture_default_str();
  exp->add_option("--base-port", o.host.base_port, "UDP port of the first job slot (one port per slot)")
      ->capture_default_str();
  exp->add_option("--process-log-level", o.host.process_log_level, "log level of the processes")->capture_default_str();
  exp->add_option("--stall-seconds", o.host.stall_seconds, "fail a run after this long without progress")
      ->capture_default_str();
  exp->add_flag("--quiet", o.write.quiet, "do not print the table at the end");
  exp->add_option("--progress", o.host.progress,
                  "progress of the runs under way (a line per job slot, and the time left): auto (redrawn in place "
                  "on a terminal, else plain lines), terminal, lines or none")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "terminal", "lines", "none"}));
  exp->add_option("--progress-every", o.host.progress_every,
                  "seconds between progress lines (default: 0.25 on a terminal, 30 otherwise)");
  exp->add_option("--extrinsic-reps", a.extrinsic_reps,
                  "extrinsic tests of each scenario (and planner condition) from every trained agent; 0: none, "
                  "the intrinsic phase only (default: the experiment's extrinsic.tests, else 0)");
  exp->add_option("--scenarios", o.plan.scenarios, "scenarios to test (default: all in config/scenarios)");
  a.tables_option = exp->add_option("--tables", a.tables,
                                        "experiments on random affordance tables (random-tables): how many tables "
                                        "(default: the experiment's)")
                            ->check(CLI::Range(1, 100000));
  a.table_seed_option =
      exp->add_option("--table-seed", a.table_seed,
                      "... and the seed of the series they are drawn from (default: the experiment's)")
          ->check(CLI::Range(std::int64_t{0}, std::numeric_limits<std::int64_t>::max()));
  exp->add_option("--attach", o.host.attach,
                  "drive the runs on this LCM URL, with processes started by hand (afford-environment ..., "
                  "and afford-logger for logs): the runner starts none");
  exp->add_option("--bus-key", o.host.bus_key,
                  "key file of a keyed bus: the runner and the processes it starts tag what they send and take "
                  "only tagged messages (default: the file $AFFORD_BUS_KEY names; none: untagged)");
  exp->add_option("--process", a.processes,
                  "NAME='CMD ARGS': start CMD in place of the shipped process NAME (repeatable; real processes "
                  "only). CMD gets the arguments the shipped one would (--lcm-url URL ...) appended; see "
                  "docs/writing-a-component.md");
  exp->add_flag("--watch", a.watch,
                "serve a page that follows the runs in the browser, from this process (its address is printed; "
                "the page opens from this machine, whatever namespace the runs are in)");
  exp->add_option("--watch-port", a.watch_port, "with --watch: the page's port (0: any free one)")
      ->capture_default_str()->check(CLI::Range(0, 65535));
  exp->add_option("--watch-bind", a.watch_bind, "with --watch: the address to serve the page on; anything but "
                                                "loopback requires a token, which the address printed has")
      ->capture_default_str();
  exp->add_flag("--resume", o.resume,
                "continue the interrupted experiment of --out: the runs not finished, with its stored options");
}

// The request the options make (checked as far as no file is needed).
// `also_given`: options of the command line a queue entry takes as its own.
ExperimentRequest requestOf(Args& a, const CLI::App& app, const CLI::App* exp, const FrontDoor& door,
                            const std::set<std::string>& also_given = {}) {
  ExperimentRequest o = a.o;
  o.plan.config_dir = door.config_dir;
  o.write.program = door.program;
  o.given = also_given;
  for (const CLI::Option* opt : exp->get_options())
    if (opt->count() > 0) o.given.insert(opt->get_name());
  if (app.count("--config-dir") > 0) o.given.insert("--config-dir");
  if (a.names.size() > 1) throw ConfigError("one experiment NAME per queue entry, not " + std::to_string(a.names.size()));
  o.plan.experiment = a.names.empty() ? std::string() : a.names.front();
  if (!a.file.empty()) {
    if (!o.plan.experiment.empty())
      throw ConfigError("give an experiment NAME or --config FILE, not both");
    if (!isExperimentPath(a.file)) a.file = "./" + a.file;  // a file, even without '/' or .yaml
    o.plan.experiment = std::filesystem::absolute(a.file).lexically_normal().string();
    o.given.insert("name");
  }
  if (o.resume && o.write.replace)
    throw ConfigError("--resume continues the unfinished experiment of --out, --replace starts a new one in place of a "
                      "finished one: give one of them");
  if (!o.resume && o.plan.experiment.empty())
    throw ConfigError("which experiment? `afford experiment NAME` (see `afford experiments`), or "
                      "`afford experiment --resume --out DIR` to continue an interrupted one");
  if (!o.plan.sweep_file.empty()) o.plan.sweep_file = std::filesystem::absolute(o.plan.sweep_file).lexically_normal().string();
  if (!a.shard.empty()) {
    const auto slash = a.shard.find('/');
    try {
      std::size_t used = 0, used2 = 0;
      if (slash == std::string::npos) throw std::invalid_argument("no /");
      o.host.shard_index = std::stoi(a.shard.substr(0, slash), &used);
      o.host.shard_count = std::stoi(a.shard.substr(slash + 1), &used2);
      if (used != slash || used2 != a.shard.size() - slash - 1) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw ConfigError("--shard must be i/n (e.g. 0/4), not \"" + a.shard + "\"");
    }
    if (o.host.shard_count < 1 || o.host.shard_index < 0 || o.host.shard_index >= o.host.shard_count)
      throw ConfigError("--shard must be i/n with 0 <= i < n, not \"" + a.shard + "\"");
  }
  o.host.processes = parseProcessSwaps(a.processes, "--process");
  // Given is given: `--steps 0` is refused (checkPlanRequest), not read as "the experiment's".
  if (o.given.count("--reps")) o.plan.reps = a.reps;
  if (o.given.count("--steps")) o.plan.steps = a.steps;
  if (o.given.count("--tables")) o.plan.tables = a.tables;
  if (o.given.count("--extrinsic-reps")) o.plan.extrinsic_reps = a.extrinsic_reps;
  if (o.given.count("--table-seed")) o.plan.table_seed = a.table_seed;
  if (!a.system.empty()) o.plan.systems = parseSystems({a.system}, "--system");
  if (a.netns == "auto")
    o.host.netns = NetnsMode::Auto;
  else if (a.netns == "on")
    o.host.netns = NetnsMode::On;
  else if (a.netns == "off")
    o.host.netns = NetnsMode::Off;
  else
    throw ConfigError("--netns must be auto, on or off, not \"" + a.netns + "\"");
  return o;
}

// The options of the queue as a whole: a queue entry does not give them.
const std::set<std::string> kQueueOptions = {"--jobs",     "--transport", "--base-port", "--netns", "--progress",
                                             "--progress-every", "--attach", "--shard", "--plan", "--resume",
                                             "--watch", "--watch-port", "--watch-bind"};

// The entries of a --plan file: a YAML list of argument lines.
std::vector<std::string> planEntries(const std::string& file) {
  const YAML::Node root = loadGivenYaml(file, "--plan");
  if (!root.IsSequence())
    throw ConfigError("--plan " + file + ": a YAML list of experiments, each an argument line of `afford experiment` "
                      "(e.g. - late1 --system all)");
  constexpr std::size_t kMostEntries = 1000;  // each runs on a thread of its own
  if (root.size() > kMostEntries)
    throw ConfigError("--plan " + file + ": " + std::to_string(root.size()) + " entries, more than a queue takes (" +
                      std::to_string(kMostEntries) + ")");
  std::vector<std::string> lines;
  for (std::size_t k = 0; k < root.size(); ++k) {
    if (!root[k].IsScalar() || root[k].as<std::string>().empty())
      throw ConfigError("--plan " + file + ": entry " + std::to_string(k + 1) +
                        " is not an argument line (a string such as \"late1 --system all\")");
    lines.push_back(root[k].as<std::string>());
  }
  return lines;
}

// `dir` if it does not exist or is empty; else the first of dir-2, dir-3, ... that does not.
std::string freeFolder(const std::string& dir) {
  namespace fs = std::filesystem;
  const auto free = [](const fs::path& p) {
    std::error_code ec;
    return !fs::exists(p, ec) || (fs::is_directory(p, ec) && fs::is_empty(p, ec));
  };
  if (free(dir)) return dir;
  for (int k = 2;; ++k)
    if (free(dir + "-" + std::to_string(k))) return dir + "-" + std::to_string(k);
}

// The folder an entry writes when it gives no --out: <out>/<name> (a --config file: its stem).
std::string entryFolder(const std::string& out, const std::string& name) {
  const std::filesystem::path p(name);
  return (std::filesystem::path(out) / (isExperimentPath(name) ? p.stem() : p)).string();
}

// afford experiment A B ... / --plan FILE: every entry's request, then the queue.
int runQueueOf(Args& a, CLI::App& app, const CLI::App* exp, const FrontDoor& door) {
  std::set<std::string> common;  // what the command line gives every entry
  for (const CLI::Option* opt : exp->get_options())
    if (opt->count() > 0 && opt->get_name() != "name" && opt->get_name() != "--plan") common.insert(opt->get_name());
  if (!a.file.empty()) throw ConfigError("--config runs one experiment file: give it in a --plan entry instead");
  for (const char* alone : {"--shard", "--attach"})
    if (common.count(alone)) throw ConfigError(std::string(alone) + " is for one experiment, not a queue");
  struct Entry {
    std::string what, line;  // how the error names it; the argument line ("" for a name)
  };
  std::vector<Entry> entries;
  for (const std::string& name : a.names) entries.push_back({"experiment " + name, name});
  if (!a.plan.empty()) {
    std::size_t k = 0;
    for (std::string& line : planEntries(a.plan)) entries.push_back({a.plan + " entry " + std::to_string(++k), line});
  }
  std::vector<ExperimentRequest> requests;
  for (const Entry& entry : entries) {
    Args e = a;  // the command line's values, an entry's own options replacing them
    e.names.clear();
    e.plan.clear();
    CLI::App sub{"afford experiment (a queue entry)", "experiment"};
    addFirstOptions(&sub, e);
    addMoreOptions(&sub, e);
    try {
      sub.parse(entry.line, false);
    } catch (const CLI::ParseError& err) {
      throw ConfigError(entry.what + " (\"" + entry.line + "\"): " + err.what());
    }
    for (const CLI::Option* opt : sub.get_options())
      if (opt->count() > 0 && kQueueOptions.count(opt->get_name()))
        throw ConfigError(entry.what + ": " + opt->get_name() + " is the queue's option: give it on the command line");
    ExperimentRequest o;
    try {
      o = requestOf(e, app, &sub, door, common);
    } catch (const ConfigError& err) {
      throw ConfigError(entry.what + ": " + err.what());
    }
    if (!sub.get_option("--out")->count()) o.write.out_dir = entryFolder(a.o.write.out_dir, o.plan.experiment);
    // --resume: each entry goes on where it stopped; one that finished is kept, one not begun starts.
    if (a.o.resume) {
      const auto state = std::filesystem::path(o.write.out_dir) / "experiment.json";
      o.resume = std::filesystem::exists(state);
      if (o.resume && readState(o.write.out_dir).state == "finished") {
        door.log->info("{} finished already in {}", entry.what, o.write.out_dir);
        continue;
      }
    }
    requests.push_back(std::move(o));
  }
  std::string resume = shellQuoted(door.program);
  bool resuming = false;
  for (const std::string& arg : door.args) {
    resume += " " + shellQuoted(arg);
    resuming = resuming || arg == "--resume";
  }
  if (!resuming) resume += " --resume";
  if (requests.empty()) {
    door.log->info("every experiment of the queue finished already");
    return 0;
  }
  return runQueue(requests, resume, *door.log);
}

// --watch: the page served here, before the runs' network namespace is entered, so that it opens from this
// machine; its listeners join the slots' buses once the experiment has entered it (HostRequest::on_bus).
std::unique_ptr<LiveWatch> servePage(Args& a, const FrontDoor& door, std::unique_ptr<ProtocolConfig>& protocol) {
  if (a.o.host.transport != "udpm")
    throw ConfigError("--watch follows the runs on their bus: it needs --transport udpm (memq runs them inside this "
                      "process, on no bus)");
  protocol = std::make_unique<ProtocolConfig>(loadProtocol(door.config_dir));
  LiveWatchOptions o;
  o.server.bind = a.watch_bind, o.server.port = a.watch_port;
  o.server.token = isLoopback(a.watch_bind) ? "" : newToken();
  o.bus_key = a.o.host.bus_key;
  o.say_runs = false;  // (the experiment says what runs)
  auto watch = std::make_unique<LiveWatch>(*protocol, o);
  watch->serve();
  const std::vector<std::string> urls = watch->pageUrls();
  std::printf("the page of this experiment (--watch): %s\n", urls.front().c_str());
  for (std::size_t k = 1; k < urls.size(); ++k) std::printf("                                    or: %s\n", urls[k].c_str());
  std::fflush(stdout);
  LiveWatch* w = watch.get();
  a.o.host.on_bus = [w](const std::vector<std::string>& buses) { w->listen(buses); };
  return watch;
}

}  // namespace

Command experimentCommand(CLI::App& app, const FrontDoor& door) {
  auto a = std::make_shared<Args>();
  auto* exp = app.add_subcommand("experiment", "run an experiment's repetitions and summarise them");
  addFirstOptions(exp, *a);
  addMoreOptions(exp, *a);
  return {exp, [&app, exp, a, &door] {
            std::unique_ptr<ProtocolConfig> protocol;
            std::unique_ptr<LiveWatch> watch;
            if (a->watch) watch = servePage(*a, door, protocol);
            if (a->names.size() > 1 || !a->plan.empty()) return runQueueOf(*a, app, exp, door);
            ExperimentRequest r = requestOf(*a, app, exp, door);
            // Without --out, a new folder of the experiment's own, out/NAME (then out/NAME-2, ...): a second
            // experiment never meets the files of one before it.
            if (!r.given.count("--out") && !r.resume) r.write.out_dir = freeFolder(entryFolder(r.write.out_dir, r.plan.experiment));
            return runExperiment(r, *door.log);
          }};
}

}  // namespace afford

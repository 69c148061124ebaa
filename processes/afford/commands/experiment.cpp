// afford experiment NAME ...: run an experiment's repetitions and summarise them.
#include <filesystem>
#include <limits>
#include <memory>

#include "afford/commands.hpp"
#include "afford/config.hpp"
#include "experiment/experiment.hpp"

namespace afford {

namespace {

struct Args {
  ExperimentRequest o;
  std::string system, netns = "auto", file, shard;
  std::vector<std::string> processes;
  int reps = 0, tables = 0;
  std::int64_t steps = 0, table_seed = 0;
  CLI::Option* tables_option = nullptr;
  CLI::Option* table_seed_option = nullptr;
};

// The options --help lists first: the experiment, its counts and seed, jobs, transport, what is kept, settings.
void addFirstOptions(CLI::App* exp, Args& a) {
  ExperimentRequest& o = a.o;
  exp->add_option("name", o.plan.experiment, "experiment (see `afford experiments`); optional with --resume");
  exp->add_option("--system", a.system, "FIX, IGN, IMP, all, or a list (FIX,IMP) (default: the experiment's systems, else all)");
  exp->add_option("--reps", a.reps, "repetitions per system (default: the experiment's)");
  exp->add_option("--steps", a.steps, "intrinsic steps per run (default: the experiment's)");
  exp->add_option("--jobs,-j", o.host.jobs, "runs at a time")->capture_default_str();
  exp->add_option("--seed", o.plan.seed, "seed of the first repetition (then seed+1, ...)")->capture_default_str();
  exp->add_option("--out", o.write.out_dir, "folder for summary.json and CSV files")->capture_default_str();
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
  exp->add_option("--extrinsic-reps", o.plan.extrinsic_reps,
                  "extrinsic tests of each scenario (and planner condition) from every trained agent "
                  "(default: the experiment's extrinsic.tests, else 0: intrinsic phase only)")
      ->capture_default_str();
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
  exp->add_flag("--resume", o.resume,
                "continue the interrupted experiment of --out: the runs not finished, with its stored options");
}

// The request the options make (checked as far as no file is needed).
ExperimentRequest requestOf(Args& a, const CLI::App& app, const CLI::App* exp, const FrontDoor& door) {
  ExperimentRequest o = a.o;
  o.plan.config_dir = door.config_dir;
  o.write.program = door.program;
  for (const CLI::Option* opt : exp->get_options())
    if (opt->count() > 0) o.given.insert(opt->get_name());
  if (app.count("--config-dir") > 0) o.given.insert("--config-dir");
  if (!a.file.empty()) {
    if (!o.plan.experiment.empty())
      throw ConfigError("give an experiment NAME or --config FILE, not both");
    if (!isExperimentPath(a.file)) a.file = "./" + a.file;  // a file, even without '/' or .yaml
    o.plan.experiment = std::filesystem::absolute(a.file).lexically_normal().string();
    o.given.insert("name");
  }
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
  if (a.reps) o.plan.reps = a.reps;
  if (a.steps) o.plan.steps = a.steps;
  if (a.tables_option->count()) o.plan.tables = a.tables;
  if (a.table_seed_option->count()) o.plan.table_seed = a.table_seed;
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

}  // namespace

Command experimentCommand(CLI::App& app, const FrontDoor& door) {
  auto a = std::make_shared<Args>();
  auto* exp = app.add_subcommand("experiment", "run an experiment's repetitions and summarise them");
  addFirstOptions(exp, *a);
  addMoreOptions(exp, *a);
  return {exp, [&app, exp, a, &door] { return runExperiment(requestOf(*a, app, exp, door), *door.log); }};
}

}  // namespace afford

// afford: the front door. `afford experiment NAME ...` runs experiments over
// real processes (udpm, default) or in one process (memq); `afford experiments`
// lists them; `afford config NAME` prints an effective configuration.
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <chrono>
#include <limits>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "afford/image.hpp"
#include "afford/plots.hpp"
#include "afford/edge.hpp"
#include "afford/explain.hpp"
#include "afford/node.hpp"
#include "afford/process_status_t.hpp"
#include "afford/replay.hpp"
#include "afford/report.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <cstdio>

#include "afford/config.hpp"
#include "afford/experiment.hpp"
#include "afford/generate.hpp"
#include "afford/logging.hpp"

int main(int argc, char** argv) {
  CLI::App app{"afford: an embodied agent learning affordances (intrinsic phase) and solving extrinsic tasks", "afford"};
  app.require_subcommand(1);
  std::string config_dir = std::string(AFFORD_SOURCE_DIR) + "/config";
  app.add_option("--config-dir", config_dir, "folder with defaults.yaml and experiments/")->capture_default_str();

  afford::ExperimentOptions o;
  std::string system, netns = "auto";
  int reps = 0;
  std::int64_t steps = 0;
  auto* exp = app.add_subcommand("experiment", "run an experiment's repetitions and summarise them");
  exp->add_option("name", o.experiment, "experiment (see `afford experiments`); optional with --resume");
  exp->add_option("--system", system, "FIX, IGN, IMP or all (default: the experiment's systems, else all)");
  exp->add_option("--reps", reps, "repetitions per system (default: the experiment's)");
  exp->add_option("--steps", steps, "intrinsic steps per run (default: the experiment's)");
  exp->add_option("--jobs,-j", o.jobs, "runs at a time")->capture_default_str();
  exp->add_option("--seed", o.seed, "seed of the first repetition (then seed+1, ...)")->capture_default_str();
  exp->add_option("--out", o.out_dir, "folder for summary.json and CSV files")->capture_default_str();
  exp->add_option("--transport", o.transport, "udpm (real processes) or memq (one process)")->capture_default_str();
  exp->add_option("--keep-logs", o.keep_logs, "which runs keep an LCM log: all, first or none")->capture_default_str();
  exp->add_option("--log-root", o.log_root, "folder of the run logs (<log-root>/<run-id>/)")->capture_default_str();
  exp->add_option("--run-prefix", o.run_prefix, "first part of every run id (default: date-time)");
  exp->add_option("--set", o.settings, "override a config value, e.g. --set motivation.leak=0.2 (repeatable)");
  exp->add_option("--netns", netns, "auto, on or off: run the process group in a private network namespace")
      ->capture_default_str();
  exp->add_option("--base-port", o.base_port, "UDP port of the first job slot (one port per slot)")
      ->capture_default_str();
  exp->add_option("--process-log-level", o.process_log_level, "log level of the processes")->capture_default_str();
  exp->add_option("--stall-seconds", o.stall_seconds, "fail a run after this long without progress")
      ->capture_default_str();
  exp->add_flag("--quiet", o.quiet, "do not print the table at the end");
  exp->add_option("--extrinsic-reps", o.extrinsic_reps,
                  "extrinsic tests of each scenario (and planner condition) from every trained agent "
                  "(default: the experiment's extrinsic.tests, else 0: intrinsic phase only)")
      ->capture_default_str();
  exp->add_option("--scenarios", o.scenarios, "scenarios to test (default: all in config/scenarios)");
  int tables = 0;
  std::int64_t table_seed = 0;
  auto* tables_option = exp->add_option("--tables", tables,
                                        "experiments on random affordance tables (random-tables): how many tables "
                                        "(default: the experiment's)")
                            ->check(CLI::Range(1, 100000));
  auto* table_seed_option = exp->add_option("--table-seed", table_seed,
                                            "... and the seed of the series they are drawn from (default: the experiment's)")
                                ->check(CLI::Range(std::int64_t{0}, std::numeric_limits<std::int64_t>::max()));
  exp->add_option("--attach", o.attach,
                  "drive the runs on this LCM URL, with processes started by hand (afford-environment ..., "
                  "and afford-logger for logs): the runner starts none");
  exp->add_flag("--resume", o.resume,
                "continue the interrupted experiment of --out: the runs not finished, with its stored options");

  auto* list = app.add_subcommand("experiments", "list the experiments in the config folder");
  std::string show_name, show_system = "IMP";
  std::vector<std::string> show_settings;
  auto* show = app.add_subcommand("config", "print the effective configuration of one run");
  show->add_option("name", show_name, "experiment")->required();
  show->add_option("--system", show_system, "FIX, IGN or IMP")->capture_default_str();
  show->add_option("--set", show_settings, "override a config value (repeatable)");

  std::string plot_dir;
  auto* plot = app.add_subcommand("plot", "draw the paper's figures (PNG + CSV) from an experiment's output folder");
  plot->add_option("dir", plot_dir, "folder with summary.json (an experiment's --out)")->required();
  std::vector<std::string> report_dirs;
  std::string report_out = "docs/results.md", report_figures = "docs/results";
  double report_wall = 0;
  auto* report = app.add_subcommand("report", "write docs/results.md from experiment output folders (plotted)");
  report->add_option("dirs", report_dirs, "experiment output folders")->required();
  report->add_option("--out", report_out, "the markdown file")->capture_default_str();
  report->add_option("--figures", report_figures, "where the figures are copied")->capture_default_str();
  report->add_option("--wall-seconds", report_wall, "wall time of the reproduction, to report");
  std::string report_note;
  report->add_option("--note", report_note, "a paragraph on how the runs were made");
  afford::ReplayOptions replay_options;
  std::string replay_into;
  auto* replay = app.add_subcommand("replay", "feed a recorded run into fresh learning processes and compare");
  replay->add_option("log", replay_options.log_dir, "the run's log folder (logs/<run-id>) or one .lcm file")->required();
  replay->add_option("--run", replay_options.run_id, "the run to replay, in a log that holds several (default: the first)");
  replay->add_option("--into", replay_into,
                     "processes to replay, comma-separated: predictors, motivation, planner "
                     "(default: predictors and the run's decider)");
  std::string explain_log, explain_run;
  bool explain_json = false;
  auto* explain = app.add_subcommand(
      "explain", "why an extrinsic test ended as it did, from its log; or every test in a folder of logs, summarised");
  explain
      ->add_option("log", explain_log,
                   "the test's log folder (<log-root>/<run-id>) or one .lcm file; or a folder of run log folders "
                   "(an experiment's --log-root) for a summary")
      ->required();
  explain->add_option("--run", explain_run, "the test to explain, in a log that holds several (default: the first)");
  explain->add_flag("--json", explain_json, "print one JSON object (for scripts) instead of text");
  bool explain_by_agent = false;
  explain->add_flag("--by-agent", explain_by_agent,
                    "with a folder of run logs: by system, scenario and sub-goal, then by trained agent, how often it "
                    "was reached, why not, and each agent's closest predicted effect");
  std::string status_url = "udpm://239.255.76.67:7667?ttl=0";
  double status_seconds = 1.5;
  auto* status = app.add_subcommand("status", "list the processes heard on a bus: pid, state, run, last step");
  status->add_option("--lcm-url", status_url, "the bus")->capture_default_str();
  status->add_option("--seconds", status_seconds, "how long to listen (processes report every 0.5 s)")
      ->capture_default_str();
  std::string status_wait, status_state;
  status->add_option("--wait-for", status_wait,
                     "processes, comma-separated: list as soon as each has been heard (with --state: in that "
                     "state); --seconds is then the deadline, and missing it exits 1");
  status->add_option("--state", status_state, "with --wait-for: the state to wait for")
      ->check(CLI::IsMember({"waiting", "ready", "running", "done", "failed"}));
  std::string scenario_name, scenario_png;
  auto* scen = app.add_subcommand("scenario", "check a scenario file and draw its goal and initial scenes");
  std::vector<int> scenario_generate;
  std::int64_t scenario_seed = 1, scenario_index = 0;
  std::string scenario_experiment = "base";
  scen->add_option("name", scenario_name, "scenario (config/scenarios/<name>.yaml)");
  scen->add_option("--png", scenario_png, "write the picture to this PNG file");
  scen->add_option("--generate", scenario_generate,
                   "draw one instead: SUB_GOALS TWO_ACTION OBJECTS (k m n), printed as a scenario file")
      ->expected(3);
  scen->add_option("--seed", scenario_seed, "with --generate: the seed of the draw");
  scen->add_option("--index", scenario_index, "with --generate: which scenario of the seed");
  scen->add_option("--experiment", scenario_experiment, "the experiment whose world the scenario is for (default: base)");

  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(0);  // small images: OpenCV's thread pool only adds wake-ups
  auto log = afford::makeLogger("afford");
  try {
    if (list->parsed()) {
      for (const auto& n : afford::listExperiments(config_dir)) {
        const auto e = afford::loadExperiment(config_dir, n);
        std::printf("%-16s %s\n", n.c_str(), e.description.c_str());
      }
      return 0;
    }
    if (report->parsed()) {
      const std::string link = std::filesystem::relative(report_figures, std::filesystem::path(report_out).parent_path()).string();
      const std::string md = afford::writeReport(report_dirs, report_figures, link, report_wall, report_note, config_dir);
      std::ofstream(report_out) << md;
      std::printf("%s\n", report_out.c_str());
      return 0;
    }
    if (status->parsed()) {
      lcm::LCM bus(status_url);
      if (!bus.good()) throw std::runtime_error("cannot open LCM at " + status_url);
      std::map<std::string, afford::process_status_t> heard;  // process#pid -> its last STATUS
      afford::Edge edge(bus, afford::makeLogger("status", "warn"), "status", afford::loadProtocol(config_dir));
      edge.subscribe<afford::process_status_t>(
          "STATUS",
          [&heard](const afford::process_status_t& m) {
            heard[m.process + "#" + std::to_string(m.pid)] = m;
            return afford::Turn::take();
          },
          afford::Scope::Any, afford::Order::None);
      const char* states[] = {"waiting", "ready", "running", "done", "failed"};
      std::vector<std::string> awaited;
      std::stringstream names(status_wait);
      for (std::string p; std::getline(names, p, ',');)
        if (!p.empty()) awaited.push_back(p);
      auto allHeard = [&] {  // each awaited process's latest STATUS (any pid) says the state asked for
        for (const auto& p : awaited) {
          bool ok = false;
          for (const auto& [key, m] : heard) ok = ok || (m.process == p && (status_state.empty() || status_state == states[m.state]));
          if (!ok) return false;
        }
        return true;
      };
      const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(status_seconds);
      while (std::chrono::steady_clock::now() < until && !(awaited.size() && allHeard())) bus.handleTimeout(50);
      std::printf("%-12s %8s  %-8s %10s  %s\n", "process", "pid", "state", "last step", "run");
      for (const auto& [key, m] : heard)
        std::printf("%-12s %8d  %-8s %10lld  %s%s%s\n", m.process.c_str(), m.pid, states[m.state],
                    static_cast<long long>(m.step), m.run_id.empty() ? "-" : m.run_id.c_str(), m.detail.empty() ? "" : "  ",
                    m.detail.c_str());
      if (heard.empty()) std::printf("(no process heard on %s in %.1f s)\n", status_url.c_str(), status_seconds);
      if (!awaited.empty() && !allHeard()) {
        std::fprintf(stderr, "afford status: not every one of %s was heard%s within %.1f s on %s\n", status_wait.c_str(),
                     status_state.empty() ? "" : (" " + status_state).c_str(), status_seconds, status_url.c_str());
        return 1;
      }
      return 0;
    }
    if (replay->parsed()) {
      std::stringstream ss(replay_into);
      for (std::string p; std::getline(ss, p, ',');)
        if (!p.empty()) replay_options.into.push_back(p);
      const afford::ReplayResult r = afford::replayRun(replay_options, *log);
      std::printf("run: %s (%s)\nevents: %lld%s\n", r.run_id.c_str(), r.extrinsic ? "extrinsic" : "intrinsic",
                  static_cast<long long>(r.events), r.torn_bytes ? " (then an incomplete event, skipped)" : "");
      if (!r.incomplete.empty()) std::printf("the log is incomplete: %s\n", r.incomplete.c_str());
      for (const auto& g : r.gaps)
        std::printf("missing from the recording: %s serial%s %lld%s\n", g.channel.c_str(), g.first == g.last ? "" : "s",
                    static_cast<long long>(g.first),
                    g.first == g.last ? "" : (".." + std::to_string(g.last)).c_str());
      if (r.dropped) std::printf("refused: %lld recorded message(s) (corrupted; see the warnings)\n", static_cast<long long>(r.dropped));
      if (!r.weights_checksum.empty() || !r.recorded_checksum.empty())
        std::printf("weights_checksum: %s\nrecorded: %s\n",
                    r.weights_checksum.empty() ? "(not reached: the replay stopped before the end)" : r.weights_checksum.c_str(),
                    r.recorded_checksum.empty() ? "(none in the log)" : r.recorded_checksum.c_str());
      std::printf("decisions: %lld replayed, %lld recorded, %lld differing\n", static_cast<long long>(r.decisions),
                  static_cast<long long>(r.decisions_recorded), static_cast<long long>(r.decisions_differing));
      if (r.ok())
        std::printf("replay equals the record\n");
      else if (!r.consistent())
        std::printf("REPLAY DIFFERS FROM THE RECORD\n");
      else
        std::printf("replay equals the record as far as it goes, but the record is %s\n",
                    r.gaps.empty() ? "incomplete" : "missing messages (above)");
      return r.ok() ? 0 : 1;
    }
    if (explain->parsed()) {
      if (afford::isLogRoot(explain_log)) {
        if (!explain_run.empty())
          throw afford::ConfigError("--run picks a run in one log, but " + explain_log + " is a folder of run logs");
        const afford::ExplainSummary s = afford::explainLogRoot(explain_log, *log);
        if (explain_by_agent)
          std::printf("%s", explain_json ? (afford::byAgentJson(s).dump(2) + "\n").c_str() : afford::byAgentText(s).c_str());
        else
          std::printf("%s", explain_json ? (afford::summaryJson(s).dump(2) + "\n").c_str() : afford::summaryText(s).c_str());
        return s.errors.empty() ? 0 : 1;  // a log that could not be explained is named, and fails the summary
      }
      if (explain_by_agent)
        throw afford::ConfigError("--by-agent summarises a folder of run logs, but " + explain_log + " is one run's log");
      const afford::Explanation e = afford::explainLog(explain_log, explain_run, *log);
      std::printf("%s", explain_json ? (afford::explanationJson(e).dump(2) + "\n").c_str() : afford::explanationText(e).c_str());
      return 0;
    }
    if (plot->parsed()) {
      for (const auto& f : afford::plotExperiment(plot_dir)) std::printf("%s\n", f.c_str());
      return 0;
    }
    if (scen->parsed()) {
      const afford::RunConfig run =
          afford::parseRunConfig(afford::effectiveConfig(config_dir, {scenario_experiment, afford::System::IMP, 1, std::nullopt, {}}));
      const afford::WorldConfig& world = run.world;
      afford::Scenario s;
      if (!scenario_generate.empty()) {
        if (!scenario_name.empty()) throw afford::ConfigError("afford scenario: give a scenario name or --generate, not both");
        const afford::ScenarioSpec spec{scenario_generate[2], scenario_generate[0], scenario_generate[1]};
        s = afford::generateScenario(run, spec, scenario_seed, scenario_index).scenario;
        std::printf("%s", afford::emitYaml(afford::scenarioNode(s)).c_str());
      } else {
        if (scenario_name.empty()) throw afford::ConfigError("afford scenario: name a scenario, or --generate K M N");
        s = afford::loadScenario(config_dir, scenario_name, world);
        std::printf("%s: %zu object(s), valid. %s\n", s.name.c_str(), s.objects.size(), s.description.c_str());
      }
      if (!scenario_png.empty() && !cv::imwrite(scenario_png, afford::scenarioPicture(s, world)))
        throw std::runtime_error("cannot write " + scenario_png);
      return 0;
    }
    if (show->parsed()) {
      afford::RunRequest req{show_name, afford::parseSystem(show_system), 1, std::nullopt, show_settings};
      std::printf("%s", afford::emitYaml(afford::effectiveConfig(config_dir, req)).c_str());
      return 0;
    }
    o.config_dir = config_dir;
    o.program = argv[0];
    for (const CLI::Option* opt : exp->get_options())
      if (opt->count() > 0) o.given.insert(opt->get_name());
    if (app.count("--config-dir") > 0) o.given.insert("--config-dir");
    if (!o.resume && o.experiment.empty())
      throw afford::ConfigError("which experiment? `afford experiment NAME` (see `afford experiments`), or "
                                "`afford experiment --resume --out DIR` to continue an interrupted one");
    if (reps) o.reps = reps;
    if (steps) o.steps = steps;
    if (tables_option->count()) o.tables = tables;
    if (table_seed_option->count()) o.table_seed = table_seed;
    if (system == "all")
      o.systems = {"FIX", "IGN", "IMP"};
    else if (!system.empty())
      o.systems = {afford::toString(afford::parseSystem(system))};
    if (netns == "auto")
      o.netns = afford::NetnsMode::Auto;
    else if (netns == "on")
      o.netns = afford::NetnsMode::On;
    else if (netns == "off")
      o.netns = afford::NetnsMode::Off;
    else
      throw afford::ConfigError("--netns must be auto, on or off, not \"" + netns + "\"");
    return afford::runExperiment(o, *log);
  } catch (const afford::ConfigError& e) {
    log->error("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    log->error("{}", e.what());
    return 1;
  }
}

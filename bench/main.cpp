// afford-bench: benchmarks of afford (docs/performance.md). Without a mode:
// intrinsic steps per second over udpm and memq; `boundaries`: the cost of
// starting and ending runs (extrinsic tests, short runs, the main job);
// `replay`: the cost of the memory options of issue 11; `auth`: the cost of an
// authenticated bus.
#include <CLI/CLI.hpp>

#include <cstdio>

#include "bench.hpp"

int main(int argc, char** argv) {
  using namespace afford::bench;
  CLI::App app{"afford benchmarks: intrinsic throughput (default) or run boundaries", "afford-bench"};
  IntrinsicOptions in;
  app.add_option("--steps", in.steps, "steps per run")->capture_default_str();
  app.add_option("--reps", in.reps, "runs per transport (seeds 1..reps)")->capture_default_str();
  app.add_option("--out", in.out, "working folder")->capture_default_str();

  BoundaryOptions bo;
  auto* b = app.add_subcommand("boundaries", "extrinsic tests per second and their wall time, short runs per minute, "
                                             "the main job's wall time; logs kept and not");
  b->add_option("--tests", bo.tests, "extrinsic tests of each of the five scenarios")->capture_default_str();
  b->add_option("--train-steps", bo.train_steps, "intrinsic steps of the agent the tests use")->capture_default_str();
  b->add_option("--runs", bo.runs, "short intrinsic runs")->capture_default_str();
  b->add_option("--run-steps", bo.run_steps, "steps of each short run")->capture_default_str();
  b->add_option("--transports", bo.transports, "udpm, memq or both")
      ->delimiter(',')
      ->check(CLI::IsMember({"udpm", "memq"}))
      ->capture_default_str();
  b->add_option("--parts", bo.parts, "what to measure: extrinsic, short, main")
      ->delimiter(',')
      ->check(CLI::IsMember({"extrinsic", "short", "main"}))
      ->capture_default_str();
  b->add_option("--out", bo.out, "working folder")->capture_default_str();
  ReplayOptions ro;
  auto* r = app.add_subcommand("replay", "what the memory options of issue 11 cost: steps per second with replay and "
                                         "revisits against without, predictors' memory, checkpoint size");
  r->add_option("--experiment", ro.experiment, "experiment to run")->capture_default_str();
  r->add_option("--system", ro.system, "FIX, IGN or IMP")->check(CLI::IsMember({"FIX", "IGN", "IMP"}))->capture_default_str();
  r->add_option("--steps", ro.steps, "steps per run")->capture_default_str();
  r->add_option("--reps", ro.reps, "runs per transport and setting (seeds 1..reps)")->capture_default_str();
  r->add_option("--transports", ro.transports, "udpm, memq or both")
      ->delimiter(',')
      ->check(CLI::IsMember({"udpm", "memq"}))
      ->capture_default_str();
  r->add_option("--floor", ro.floor, "the least ratio of steps per second, on / off, that passes")->capture_default_str();
  r->add_option("--out", ro.out, "working folder")->capture_default_str();
  AuthOptions ao;
  auto* a = app.add_subcommand("auth", "what an authenticated bus costs: steps per second over udpm with a bus key "
                                       "against without, and the time to tag a message");
  a->add_option("--steps", ao.steps, "steps per run")->capture_default_str();
  a->add_option("--reps", ao.reps, "runs each way (seeds 1..reps, alternating)")->capture_default_str();
  a->add_option("--floor", ao.floor, "the least ratio of steps per second, with / without, that passes")
      ->capture_default_str();
  a->add_option("--out", ao.out, "working folder")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (a->parsed()) {
    if (ao.steps < 1 || ao.reps < 1) {
      std::fprintf(stderr, "afford-bench auth: --steps and --reps must be at least 1\n");
      return 2;
    }
    return authBench(ao);
  }
  if (r->parsed()) {
    if (ro.steps < 1 || ro.reps < 1) {
      std::fprintf(stderr, "afford-bench replay: --steps and --reps must be at least 1\n");
      return 2;
    }
    return replayBench(ro);
  }
  if (bo.tests < 1 || bo.train_steps < 1 || bo.runs < 1 || bo.run_steps < 1) {
    std::fprintf(stderr, "afford-bench boundaries: --tests, --train-steps, --runs and --run-steps must be at least 1\n");
    return 2;
  }
  return b->parsed() ? boundariesBench(bo) : intrinsicBench(in);
}

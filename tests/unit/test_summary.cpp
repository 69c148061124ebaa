// The structure of summary.json (experiment/schema/summary.hpp): what it
// writes reads back the same, and what it cannot read is named by its path.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "experiment/run/outcome.hpp"
#include "experiment/schema/summary.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

using nlohmann::json;

// A summary with every optional part there, and nulls where a key may be null.
Summary fullSummary() {
  Summary s;
  s.experiment = "base";
  s.steps = 60;
  s.repetitions = 2;
  s.seed = 3;
  s.experiment_file = "/x/e.yaml";
  s.processes = std::map<std::string, std::string>{{"motivation", "my-motivation"}};
  s.objects = {"red square"};
  s.actions = {"move", "turn green", "turn red", "turn blue"};
  s.reference_completion_fit = Fit{1.3, -0.9};
  SystemSummary& imp = s.systems["IMP"];
  imp.target = SummaryTable{{1, 0, 1, 1}};
  RunEntry run;
  run.run_id = "r-IMP-s3";
  run.affordance = {{0.9, 0.1, 0.8, 0.7}};
  run.actions_executed = {5, 6, 7, 8};
  run.log_dir = Nullable<std::string>();  // hosted, its log not kept
  run.checkpoint = Nullable<std::string>("logs/r/predictors.ckpt");
  run.peak_rss_kb = std::map<std::string, std::int64_t>{{"environment", 11000}};
  imp.runs.push_back(run);
  imp.curve_gaps = std::vector<CurveGap>{{"r-IMP-s3", 4}};
  SystemExtrinsic& ex = imp.extrinsic.emplace();
  ex.scenarios = {"scenario1"};
  ex.completion_steps.emplace().scenarios["scenario1"].n = 3;
  ex.completion_steps->fit = Fit{1.0, 0.5};
  PlannerCondition c;
  c.label = "planner.kind=goal";
  c.settings = {{"planner.kind", "goal"}};
  c.points.push_back(DesignPoint{});
  ex.conditions = std::vector<PlannerCondition>{c};
  DesignSummary& d = s.extrinsic_design.emplace();
  d.generate = GenerateSummary{{1, 2}, {}, 1, 7, {true, 0}};
  SearchAnalysis& search = s.search.emplace();
  search.p_value = 1e-9;  // t and df stay null
  s.interrupted = Interruption{"SIGINT", "intrinsic", 1, 2, {{"r-IMP-s4", "step 9", {}}}, {}, true, "afford ...", "/w"};
  return s;
}

// A kept outcome is read back whatever the run's length: what it may take
// grows with the curve the run's configuration makes (a table every
// run.curve_interval steps); a file beyond what such a run keeps is refused,
// naming it.
TEST(KeptOutcome, WhatALongRunKeepsIsReadBackAndAFileBeyondItIsRefused) {
  const std::string out = test::tempDir("kept-outcome");
  RunSpec spec;
  spec.run_id = "long-run";
  spec.steps = 20000;
  spec.config_yaml = "run:\n  curve_interval: 1\n";
  RunOutcome r;
  r.ok = true;
  for (std::int64_t step = 0; step <= spec.steps; ++step)
    r.curve.push_back({step, std::vector<std::vector<double>>(4, {0.123456789012345, 0.9876543210987654,
                                                                   0.5555555555555556, 1e-17})});
  keepOutcome(out, spec.run_id, r);
  const auto back = keptOutcome(out, spec);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->curve.size(), r.curve.size());
  EXPECT_EQ(back->curve.back().affordance, r.curve.back().affordance);
  // The same file, said to be the outcome of a run of 10 steps: more than such a run keeps.
  RunSpec short_run = spec;
  short_run.steps = 10;
  ASSERT_GT(std::filesystem::file_size(out + "/runs/long-run.json"), mostOutcomeBytes(short_run));
  try {
    keptOutcome(out, short_run);
    ADD_FAILURE() << "a file beyond what the run keeps was read";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("long-run.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("more than such a file holds"), std::string::npos) << e.what();
  }
  // Ten times the interval, a tenth of the bound's curve.
  RunSpec sparse = spec;
  sparse.config_yaml = "run:\n  curve_interval: 10\n";
  EXPECT_LT(mostOutcomeBytes(sparse), mostOutcomeBytes(spec) / 5);
}

TEST(SummarySchema, WhatItWritesReadsBackTheSame) {
  const json j = toJson(fullSummary());
  EXPECT_EQ(toJson(summaryFromJson(j)).dump(), j.dump());
  // Absent and null are kept apart: an empty optional is no key, an empty Nullable is null.
  const json& run = j["systems"]["IMP"]["runs"][0];
  EXPECT_TRUE(run["log_dir"].is_null());
  EXPECT_TRUE(run["reused_from"].is_null());
  EXPECT_FALSE(run.contains("table"));
  EXPECT_TRUE(j["search"]["t"].is_null());
  EXPECT_EQ(j["extrinsic_design"]["generate"]["multi_step"], "all");
  EXPECT_EQ(j["systems"]["IMP"]["extrinsic"]["completion_steps"]["fit"]["a"], 1.0);
  EXPECT_TRUE(j["steps"].is_number_integer());
  EXPECT_TRUE(j["systems"]["IMP"]["target"][0][0].is_number_float());  // a table is real numbers

  SweepSummary sweep;
  sweep.sweep.keys["motivation.leak"] = {"0.1", "0.3"};
  sweep.sweep.conditions.push_back({"motivation.leak=0.1", {"motivation.leak=0.1"}, "conditions/motivation.leak=0.1"});
  sweep.conditions["motivation.leak=0.1"] = fullSummary();
  const json w = toJson(sweep);
  EXPECT_TRUE(isSweepSummary(w));
  EXPECT_FALSE(isSweepSummary(j));
  EXPECT_EQ(toJson(sweepSummaryFromJson(w)).dump(), w.dump());
}

std::string errorOf(const json& j) {
  try {
    summaryFromJson(j, "out/summary.json");
  } catch (const SummaryError& e) {
    return e.what();
  }
  return "";
}

TEST(SummarySchema, AKeyMissingUnknownOrOfAnotherTypeIsNamedByItsPath) {
  const json good = toJson(fullSummary());
  EXPECT_EQ(errorOf(good), "");
  json j = good;
  j["systems"]["IMP"]["runs"][0]["seed"] = "three";
  EXPECT_EQ(errorOf(j), "out/summary.json: key 'systems.IMP.runs[0].seed': expected an integer, got a string");
  j = good;
  j["systems"]["IMP"]["runs"][0]["seed"] = 3.5;  // an integer key holds no fraction
  EXPECT_NE(errorOf(j).find("'systems.IMP.runs[0].seed': expected an integer, got a number"), std::string::npos);
  j = good;
  j["systems"]["IMP"].erase("runs");
  EXPECT_EQ(errorOf(j), "out/summary.json: key 'systems.IMP.runs': missing");
  j = good;
  j["systems"]["IMP"]["extrinsic"]["tabel_metric"] = json::object();
  EXPECT_EQ(errorOf(j), "out/summary.json: key 'systems.IMP.extrinsic.tabel_metric': unknown key");
  j = good;
  j["extrinsic_design"]["generate"]["multi_step"] = "some";
  EXPECT_NE(errorOf(j).find("'extrinsic_design.generate.multi_step': expected an integer or \"all\""), std::string::npos);
  j = good;
  j["systems"]["IMP"]["affordance_mae"] = nullptr;  // absent or a number, never null
  EXPECT_NE(errorOf(j).find("'systems.IMP.affordance_mae': expected a number, got null"), std::string::npos);
  EXPECT_NE(errorOf(json::array()).find("key '<top>': expected a map, got a list"), std::string::npos);
}

// The readers index tables by object and action: a table of another shape is named before any of them reads it.
TEST(SummarySchema, ATableOfAnotherShapeThanObjectsByActionsIsNamed) {
  const json good = toJson(fullSummary());
  json j = good;
  j["systems"]["IMP"]["runs"][0]["affordance"][0] = {0.5, 0.5};
  EXPECT_EQ(errorOf(j), "out/summary.json: key 'systems.IMP.runs[0].affordance[0]': 2 entries, not one per action (4)");
  j = good;
  j["systems"]["IMP"]["target"].push_back({1.0, 1.0, 1.0, 1.0});
  EXPECT_EQ(errorOf(j), "out/summary.json: key 'systems.IMP.target': 2 rows, not one per object (1)");
  j = good;
  j["systems"]["IMP"]["curves"] = {{"steps", {0, 100}}, {"mean", {{{0.1, 0.2, 0.3, 0.4}}}}};
  EXPECT_EQ(errorOf(j), "out/summary.json: key 'systems.IMP.curves.mean': not one table per step of curves.steps");
  SweepSummary sweep;
  sweep.conditions["a"] = fullSummary();
  json w = toJson(sweep);
  w["conditions"]["a"]["systems"]["IMP"]["affordance"] = {{0.5}};
  try {
    sweepSummaryFromJson(w);
    FAIL() << "a condition's table of another shape was read";
  } catch (const SummaryError& e) {
    EXPECT_NE(std::string(e.what()).find("'conditions.a.systems.IMP.affordance[0]'"), std::string::npos) << e.what();
  }
}

// A file given to a reader: too large, not JSON, missing or not a regular file, it is named and not read whole.
TEST(SummarySchema, AFileTooLargeNotJsonOrMissingIsNamed) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("afford-summary-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto errorOfDir = [&](std::uintmax_t max_bytes) {
    try {
      readSummaryJson(dir.string(), max_bytes);
    } catch (const SummaryError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(errorOfDir(kMaxSummaryBytes).find("no summary.json in " + dir.string()), std::string::npos);
  std::ofstream(dir / "summary.json") << toJson(fullSummary()).dump();
  EXPECT_EQ(errorOfDir(kMaxSummaryBytes), "");
  EXPECT_NE(errorOfDir(100).find("bytes, more than a summary holds (at most 100)"), std::string::npos);
  std::ofstream(dir / "summary.json") << "{\"experiment\": ";
  EXPECT_NE(errorOfDir(kMaxSummaryBytes).find("summary.json: not JSON (") , std::string::npos);
  fs::remove(dir / "summary.json");
  ASSERT_EQ(::mkfifo((dir / "summary.json").c_str(), 0600), 0);  // opening it would wait for a writer
  EXPECT_NE(errorOfDir(kMaxSummaryBytes).find("summary.json: not a regular file"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace afford

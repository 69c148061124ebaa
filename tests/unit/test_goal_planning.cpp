// Algorithm 2 with the real cores (no messages): with predictors trained by a
// base-test intrinsic phase, the planner solves the paper's scenarios.
#include <gtest/gtest.h>

#include "tests/reference_loops.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

const std::string kConfigDir = std::string(AFFORD_SOURCE_DIR) + "/config";

// Scenario 5 is left out: its moved circle lands at a pixel phase the learned
// move prediction misses by about planner.image_match, and some agents fail
// it, as in the authors' code (docs/results-discussion.md).
TEST(GoalPlanning, TrainedAgentSolvesTheFirstFourScenarios) {
  RunConfig c = test::shippedConfig("base", System::IMP, 1);
  const Predictors trained = test::runIntrinsic(c);
  int solved = 0, tests = 0;
  for (int k = 1; k <= 4; ++k) {
    const Scenario s = loadScenario(kConfigDir, "scenario" + std::to_string(k), c);
    for (int rep = 0; rep < 4; ++rep) {
      c.seed = 1000 * k + rep;
      const test::GoalTestOutcome o = test::runGoalTest(c, s, trained);
      ++tests;
      solved += o.success;
      std::printf("scenario %d rep %d: %s in %d steps, %d actions\n", k, rep, o.success ? "solved" : "FAILED",
                  o.completion, o.attempts);
    }
  }
  EXPECT_GE(solved, tests - 1);
}

}  // namespace
}  // namespace afford

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <stdexcept>

#include "afford/actions.hpp"
#include "afford/config.hpp"
#include "experiment/design/generate.hpp"
#include "environment/environment.hpp"
#include "tests/support.hpp"
#include "experiment/design/experiment_file.hpp"

namespace afford {
namespace {

const std::string kConfigDir = std::string(AFFORD_SOURCE_DIR) + "/config";
const RunConfig kRun = test::shippedConfig();
const WorldConfig kWorld = kRun.world;

// The error of parsing and validating a scenario written as YAML, or "".
std::string errorOf(const std::string& yaml) {
  try {
    validateScenario(parseScenario(YAML::Load(yaml), "", kWorld), kWorld);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string one(const std::string& object) { return "name: t\nobjects:\n  - " + object + "\n"; }

const char* kBlueSquare = "{shape: square, initial: {colour: blue, position: [0.2, 0.5]}, goal: {colour: green, position: [0.2, 0.5]}}";

TEST(Scenario, TheFiveScenariosOfFigure4Load) {
  EXPECT_EQ(listScenarios(kConfigDir),
            (std::vector<std::string>{"scenario1", "scenario2", "scenario3", "scenario4", "scenario5", "utility",
                                      "utility-authors"}));
  for (int k = 1; k <= 5; ++k) {
    const Scenario s = loadScenario(kConfigDir, "scenario" + std::to_string(k), kRun);
    EXPECT_EQ(s.objects.size(), static_cast<std::size_t>(k));
  }
  const Scenario s5 = loadScenario(kConfigDir, "scenario5", kRun);
  EXPECT_EQ(s5.objects[0].initial.colour, Colour::Blue);
  EXPECT_EQ(s5.objects[0].goal.colour, Colour::Green);
  EXPECT_DOUBLE_EQ(s5.objects[4].goal.y, 0.2);  // the red circle moves to (0.5, 0.2)
  EXPECT_DOUBLE_EQ(s5.objects[4].value, 1.0);
  // The authors' utility test: scenario 4's objects, with values.
  const Scenario ua = loadScenario(kConfigDir, "utility-authors", kRun), s4 = loadScenario(kConfigDir, "scenario4", kRun);
  ASSERT_EQ(ua.objects.size(), s4.objects.size());
  const double values[] = {1, 2, 4, 1};
  for (std::size_t i = 0; i < ua.objects.size(); ++i) {
    EXPECT_EQ(ua.objects[i].shape, s4.objects[i].shape);
    EXPECT_DOUBLE_EQ(ua.objects[i].initial.x, s4.objects[i].initial.x);
    EXPECT_EQ(ua.objects[i].goal.colour, s4.objects[i].goal.colour);
    EXPECT_DOUBLE_EQ(ua.objects[i].value, values[i]);
  }
}

TEST(Scenario, TheUtilityTestHasTheValuesOfTable8) {
  const Scenario u = loadScenario(kConfigDir, "utility", kRun);
  ASSERT_EQ(u.objects.size(), 4u);
  std::vector<double> values;
  for (const auto& o : u.objects) values.push_back(o.value);
  EXPECT_EQ(values, (std::vector<double>{1, 1, 2, 4}));
}

TEST(Scenario, AValidScenarioPasses) { EXPECT_EQ(errorOf(one(kBlueSquare)), ""); }

TEST(Scenario, UnknownShapeIsNamed) {
  const std::string e = errorOf(one("{shape: star, initial: {colour: blue, position: [0.2, 0.5]}, goal: {colour: blue, position: [0.2, 0.5]}}"));
  EXPECT_NE(e.find("'objects[0].shape'"), std::string::npos) << e;
}

TEST(Scenario, UnknownColourIsNamed) {
  const std::string e = errorOf(one("{shape: square, initial: {colour: blue, position: [0.2, 0.5]}, goal: {colour: pink, position: [0.2, 0.5]}}"));
  EXPECT_NE(e.find("'objects[0].goal.colour'"), std::string::npos) << e;
}

TEST(Scenario, PositionOffTheTableIsNamed) {
  const std::string e = errorOf(one("{shape: square, initial: {colour: blue, position: [0.2, 0.95]}, goal: {colour: blue, position: [0.2, 0.5]}}"));
  EXPECT_NE(e.find("'objects[0].initial.position[1]'"), std::string::npos) << e;
}

TEST(Scenario, OverlappingObjectsAreNamed) {
  const std::string e = errorOf(std::string("name: t\nobjects:\n  - ") + kBlueSquare +
                                "\n  - {shape: circle, initial: {colour: red, position: [0.25, 0.5]}, goal: {colour: red, position: [0.25, 0.5]}}\n");
  EXPECT_NE(e.find("'objects[1].initial.position': overlaps objects[0]"), std::string::npos) << e;
}

TEST(Scenario, AGoalTwoActionsAwayIsRefused) {
  const std::string e = errorOf(one("{shape: square, initial: {colour: blue, position: [0.2, 0.5]}, goal: {colour: green, position: [0.5, 0.5]}}"));
  EXPECT_NE(e.find("'objects[0].goal'"), std::string::npos) << e;
  EXPECT_NE(e.find("both colour and position"), std::string::npos) << e;
}

TEST(Scenario, AGoalTwoActionsAwayPassesWhenItSaysSo) {
  EXPECT_EQ(errorOf(one("{shape: square, initial: {colour: blue, position: [0.2, 0.5]}, "
                        "goal: {colour: green, position: [0.5, 0.5]}, actions: 2}")),
            "");
  const std::string e = errorOf(one("{shape: square, initial: {colour: blue, position: [0.2, 0.5]}, "
                                    "goal: {colour: blue, position: [0.5, 0.5]}, actions: 9}"));
  EXPECT_NE(e.find("'objects[0].actions'"), std::string::npos) << e;
}

// ---- generated scenarios (issue 12) ------------------------------------------

int countSubGoals(const Scenario& s, int* two_actions) {
  int k = 0;
  *two_actions = 0;
  for (const auto& o : s.objects) {
    const bool turns = o.goal.colour != o.initial.colour, moves = o.goal.x != o.initial.x || o.goal.y != o.initial.y;
    k += turns || moves;
    *two_actions += turns && moves;
  }
  return k;
}

// Many draws on the twenty-object world: the counts asked for, valid layouts, and a true plan that the environment
// carries out to the goal image, each action afforded by the table.
TEST(GeneratedScenario, HasTheCountsAskedForAndItsTruePlanReachesTheGoal) {
  const RunConfig c = test::shippedConfig("large-world", System::IMP, 1);
  std::map<std::string, int> kinds;  // of the one-action sub-goals: every kind is drawn
  for (int k = 1; k <= 10; ++k)
    for (int m : {0, k / 2, k}) {
      const ScenarioSpec spec{20, k, m};
      for (std::int64_t i = 0; i < 3; ++i) {
        const GeneratedScenario g = generateScenario(c, spec, 17, i);
        const Scenario& s = g.scenario;
        ASSERT_EQ(s.objects.size(), 20u);
        EXPECT_EQ(s.name, generatedName(spec, 17, i));
        int two = 0;
        EXPECT_EQ(countSubGoals(s, &two), k) << s.name;
        for (const auto& o : s.objects)
          if (o.actions == 1 && o.goal.colour != o.initial.colour) ++kinds["turn"];
          else if (o.actions == 1 && (o.goal.x != o.initial.x || o.goal.y != o.initial.y)) ++kinds["move"];
        EXPECT_EQ(two, m) << s.name;
        EXPECT_NO_THROW(validateScenario(s, c.world)) << s.name;
        EXPECT_EQ(static_cast<int>(g.plan.size()), k + m) << s.name;
        Environment env(c, s);
        EXPECT_GT(env.goalDistance(), c.planner.success_distance) << s.name;
        std::int64_t step = 0;
        for (const PlannedAction& a : g.plan) {
          const WorldObject& before = env.objects()[static_cast<std::size_t>(a.object)];
          EXPECT_DOUBLE_EQ(c.world.objects[static_cast<std::size_t>(env.tableRow(before))].affordance[a.action], 1.0);
          std::optional<std::pair<double, double>> target;
          if (a.action == kMove) target = std::make_pair(a.target_x, a.target_y);
          EXPECT_TRUE(env.execute(step++, a.action, a.x, a.y, target).succeeded) << s.name << " step " << step;
        }
        EXPECT_LT(env.goalDistance(), c.planner.success_distance) << s.name;
      }
    }
  EXPECT_GT(kinds["turn"], 20);
  EXPECT_GT(kinds["move"], 20);
}

TEST(GeneratedScenario, IsKeyedBySeedAndIndex) {
  const RunConfig c = test::shippedConfig("large-world", System::IMP, 1);
  const ScenarioSpec spec{12, 5, 2};
  auto places = [&](std::int64_t seed, std::int64_t index) {
    std::vector<double> out;
    for (const auto& o : generateScenario(c, spec, seed, index).scenario.objects)
      out.insert(out.end(), {o.initial.x, o.initial.y, o.goal.x, o.goal.y, static_cast<double>(o.goal.colour)});
    return out;
  };
  EXPECT_EQ(places(3, 4), places(3, 4));
  EXPECT_NE(places(3, 4), places(3, 5));
  EXPECT_NE(places(3, 4), places(4, 4));
}

TEST(GeneratedScenario, ABadSpecIsNamedAndAFullTableSaysSo) {
  const RunConfig base = test::shippedConfig();
  auto error = [&](const ScenarioSpec& spec) -> std::string {
    try {
      generateScenario(base, spec, 1, 0);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error({3, 4, 0}).find("sub_goals = 4"), std::string::npos);
  EXPECT_NE(error({3, 2, 3}).find("multi_step = 3"), std::string::npos);
  EXPECT_NE(error({0, 0, 0}).find("objects = 0"), std::string::npos);
  EXPECT_EQ(error({5, 5, 2}), "");  // the base world holds the paper's five
  EXPECT_NE(error({20, 10, 0}).find("fits the world's table"), std::string::npos);
}

TEST(Scenario, AGoalWhereAnotherObjectStartsIsRefused) {
  // The square must go where the circle starts; the circle leaves, but one-step
  // plans cannot count on the order.
  const std::string e = errorOf(
      "name: t\nobjects:\n"
      "  - {shape: square, initial: {colour: red, position: [0.2, 0.5]}, goal: {colour: red, position: [0.2, 0.2]}}\n"
      "  - {shape: circle, initial: {colour: red, position: [0.2, 0.2]}, goal: {colour: red, position: [0.5, 0.5]}}\n");
  EXPECT_NE(e.find("'objects[0].goal.position': no action can get there"), std::string::npos) << e;
}

TEST(Scenario, UnknownScenarioIsRefusedWithTheKnownOnes) {
  try {
    loadScenario(kConfigDir, "scenario9", kRun);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("scenario1, scenario2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace afford

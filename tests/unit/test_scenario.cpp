#include <gtest/gtest.h>

#include "afford/config.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

const std::string kConfigDir = std::string(AFFORD_SOURCE_DIR) + "/config";
const WorldConfig kWorld = test::shippedConfig().world;

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
    const Scenario s = loadScenario(kConfigDir, "scenario" + std::to_string(k), kWorld);
    EXPECT_EQ(s.objects.size(), static_cast<std::size_t>(k));
  }
  const Scenario s5 = loadScenario(kConfigDir, "scenario5", kWorld);
  EXPECT_EQ(s5.objects[0].initial.colour, Colour::Blue);
  EXPECT_EQ(s5.objects[0].goal.colour, Colour::Green);
  EXPECT_DOUBLE_EQ(s5.objects[4].goal.y, 0.2);  // the red circle moves to (0.5, 0.2)
  EXPECT_DOUBLE_EQ(s5.objects[4].value, 1.0);
  // The authors' utility test: scenario 4's objects, with values.
  const Scenario ua = loadScenario(kConfigDir, "utility-authors", kWorld), s4 = loadScenario(kConfigDir, "scenario4", kWorld);
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
  const Scenario u = loadScenario(kConfigDir, "utility", kWorld);
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
    loadScenario(kConfigDir, "scenario9", kWorld);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("scenario1, scenario2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace afford

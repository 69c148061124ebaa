// `afford explain`'s words (experiment/replay/explain.hpp holds the analysis):
// one test, a folder of tests, and the tests grouped by agent and sub-goal,
// each as text and as JSON.
#pragma once
#include <nlohmann/json.hpp>

#include <string>

#include "experiment/replay/explain.hpp"

namespace afford {

// One test: how it ended, its sub-goals, and with steps each iteration's checks.
std::string explanationText(const Explanation& e);
nlohmann::json explanationJson(const Explanation& e, bool steps = true);
// A folder of tests: one line each, the end reasons counted overall and per system.
std::string summaryText(const ExplainSummary& s);
nlohmann::json summaryJson(const ExplainSummary& s);
// By agent and sub-goal (afford explain --by-agent).
std::string byAgentText(const ExplainSummary& s);
nlohmann::json byAgentJson(const ExplainSummary& s);

}  // namespace afford

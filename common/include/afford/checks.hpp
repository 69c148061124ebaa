// Field checks of every message type, shared by all subscribers so that each
// process rejects the same malformed messages (ARCHITECTURE.md: "validate
// every field (sizes, ranges, NaN)"). Each returns "" or the reason.
#pragma once
#include <string>

#include "afford/config.hpp"
#include "afford/decision_t.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/look_t.hpp"
#include "afford/object_probe_t.hpp"
#include "afford/prediction_t.hpp"
#include "afford/scene_t.hpp"
#include "afford/trained_t.hpp"

namespace afford {

std::string checkFinite(const char* field, double v);
std::string checkRange(const char* field, double v, double lo, double hi);
std::string checkSize(const char* field, long got, long want);

std::string checkMessage(const scene_t& m, const RunConfig& c);
std::string checkMessage(const focus_t& m, const RunConfig& c);
std::string checkMessage(const prediction_t& m, const RunConfig& c);
std::string checkMessage(const decision_t& m, const RunConfig& c);
std::string checkMessage(const effect_t& m, const RunConfig& c);
std::string checkMessage(const trained_t& m, const RunConfig& c);
std::string checkMessage(const object_probe_t& m, const RunConfig& c);
std::string checkMessage(const look_t& m, const RunConfig& c);
std::string checkMessage(const forward_query_t& m, const RunConfig& c);
std::string checkMessage(const forward_prediction_t& m, const RunConfig& c);

}  // namespace afford

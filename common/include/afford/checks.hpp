// Field checks of every message type, shared by all subscribers so that each
// process rejects the same malformed messages: every field is validated
// (sizes, ranges, NaN; docs/processes-and-channels.md#the-message-edge). Each returns "" or the reason, naming
// the field. The edge (afford/edge.hpp) calls the one of each type it
// decodes: a type without one does not compile. With the run's configuration
// in the context, sizes and steps are checked against it; without one (an
// observer that has not heard the run's RUN_CONFIG), only what any run allows.
#pragma once
#include <string>

#include "afford/bounds.hpp"
#include "afford/config.hpp"
#include "afford/affordance_table_t.hpp"
#include "afford/decision_t.hpp"
#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/goal_result_t.hpp"
#include "afford/goal_t.hpp"
#include "afford/look_t.hpp"
#include "afford/object_probe_t.hpp"
#include "afford/prediction_t.hpp"
#include "afford/process_status_t.hpp"
#include "afford/resend_t.hpp"
#include "afford/run_config_t.hpp"
#include "afford/run_control_t.hpp"
#include "afford/run_result_t.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/sub_goal_t.hpp"
#include "afford/scene_t.hpp"
#include "afford/trained_t.hpp"

namespace afford {

std::string checkFinite(const char* field, double v);
std::string checkRange(const char* field, double v, double lo, double hi);
std::string checkSize(const char* field, long got, long want);

std::string checkMessage(const scene_t& m, const BoundsContext& c);
std::string checkMessage(const focus_t& m, const BoundsContext& c);
std::string checkMessage(const prediction_t& m, const BoundsContext& c);
std::string checkMessage(const decision_t& m, const BoundsContext& c);
std::string checkMessage(const effect_t& m, const BoundsContext& c);
std::string checkMessage(const trained_t& m, const BoundsContext& c);
std::string checkMessage(const object_probe_t& m, const BoundsContext& c);
std::string checkMessage(const look_t& m, const BoundsContext& c);
std::string checkMessage(const forward_query_t& m, const BoundsContext& c);
std::string checkMessage(const forward_prediction_t& m, const BoundsContext& c);
std::string checkMessage(const goal_t& m, const BoundsContext& c);
std::string checkMessage(const goal_result_t& m, const BoundsContext& c);
std::string checkMessage(const affordance_table_t& m, const BoundsContext& c);
std::string checkMessage(const run_result_t& m, const BoundsContext& c);
std::string checkMessage(const extrinsic_result_t& m, const BoundsContext& c);
std::string checkMessage(const sub_goal_t& m, const BoundsContext& c);
std::string checkMessage(const process_status_t& m, const BoundsContext& c);
std::string checkMessage(const resend_t& m, const BoundsContext& c);
std::string checkMessage(const run_config_t& m, const BoundsContext& c);
std::string checkMessage(const run_control_t& m, const BoundsContext& c);

}  // namespace afford

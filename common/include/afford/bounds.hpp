// The maxima of every type's variable-length fields (afford/wire.hpp): what a
// receiver accepts before LCM's decode. With the run's configuration they are
// what the run itself sends; without one (observers between runs: viewer,
// status) they are the protocol's limits (config key protocol.limits).
#pragma once
#include "afford/config.hpp"
#include "afford/wire_bounds.hpp"

namespace afford {

struct BoundsContext {
  const ProtocolConfig* protocol;
  const RunConfig* run = nullptr;  // the run's config, when known
};

// One overload per type, picked by a null pointer of the type (boundsFor).
wire::affordance_table_t_bounds boundsOf(const BoundsContext&, const affordance_table_t*);
wire::decision_t_bounds boundsOf(const BoundsContext&, const decision_t*);
wire::effect_t_bounds boundsOf(const BoundsContext&, const effect_t*);
wire::extrinsic_result_t_bounds boundsOf(const BoundsContext&, const extrinsic_result_t*);
wire::focus_t_bounds boundsOf(const BoundsContext&, const focus_t*);
wire::forward_prediction_t_bounds boundsOf(const BoundsContext&, const forward_prediction_t*);
wire::forward_query_t_bounds boundsOf(const BoundsContext&, const forward_query_t*);
wire::goal_t_bounds boundsOf(const BoundsContext&, const goal_t*);
wire::goal_result_t_bounds boundsOf(const BoundsContext&, const goal_result_t*);
wire::look_t_bounds boundsOf(const BoundsContext&, const look_t*);
wire::object_probe_t_bounds boundsOf(const BoundsContext&, const object_probe_t*);
wire::prediction_t_bounds boundsOf(const BoundsContext&, const prediction_t*);
wire::process_status_t_bounds boundsOf(const BoundsContext&, const process_status_t*);
wire::resend_t_bounds boundsOf(const BoundsContext&, const resend_t*);
wire::run_config_t_bounds boundsOf(const BoundsContext&, const run_config_t*);
wire::run_control_t_bounds boundsOf(const BoundsContext&, const run_control_t*);
wire::run_result_t_bounds boundsOf(const BoundsContext&, const run_result_t*);
wire::scene_t_bounds boundsOf(const BoundsContext&, const scene_t*);
// Parts (fields of the types above).
wire::sub_goal_t_bounds boundsOf(const BoundsContext&, const sub_goal_t*);
wire::trained_t_bounds boundsOf(const BoundsContext&, const trained_t*);

template <class Msg>
typename wire::Bounds<Msg>::type boundsFor(const BoundsContext& c) {
  return boundsOf(c, static_cast<const Msg*>(nullptr));
}

}  // namespace afford

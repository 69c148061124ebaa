// The maxima of every type in a context (afford/bounds.hpp). Each is at least
// what the project itself sends: a run's own messages always pass.
#include "afford/bounds.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <iterator>

#include "afford/actions.hpp"
#include "afford/edge_peers.hpp"
#include "afford/protocol.hpp"

namespace afford {
namespace {

using wire::Max;

// Run ids, process, channel, experiment, system, scenario and object names.
Max nameBytes(const BoundsContext& c) { return Max(c.protocol->limits.name_bytes); }
// Free text: STATUS detail, a checkpoint's path.
Max textBytes(const BoundsContext& c) { return Max(c.protocol->limits.text_bytes); }
Max configBytes(const BoundsContext& c) { return Max(c.protocol->limits.config_bytes); }
// Values per action: the four actions of paper 2.3.2.
Max actions() { return Max(kNumActions); }
// Training reports in one message: the update of the previous step, if any.
Max trainedReports() { return Max(1); }
Max channels() { return Max(static_cast<std::int64_t>(kChannelCount)); }

// Bytes of a focus image: side x side x RGB.
Max focusImageBytes(const BoundsContext& c) {
  const std::int64_t side = c.run ? c.run->eye.focus_side : c.protocol->limits.focus_side;
  return Max(3 * side * side);
}
// Probe objects and affordance table rows: the world's objects.
Max objects(const BoundsContext& c) {
  return Max(c.run ? static_cast<std::int64_t>(c.run->world.objects.size()) : c.protocol->limits.objects);
}
// A zlib scene (image.hpp encodeScene) is at most zlib's bound for px x px x RGB.
Max sceneBytes(const BoundsContext& c) {
  const auto px = static_cast<uLong>(c.run ? c.run->world.size_px : c.protocol->limits.scene_side);
  const auto rows = static_cast<uLong>(c.run ? c.run->world.rows() : c.protocol->limits.scene_side);
  return Max(static_cast<std::int64_t>(compressBound(3 * px * rows)));
}
// Objects a scene lists (eye.fovea = true_centre): those of the world, or of
// the run's scenario, whichever a run has more of.
Max sceneObjects(const BoundsContext& c) {
  if (!c.run) return Max(c.protocol->limits.objects);
  const std::size_t n = std::max(c.run->world.objects.size(), c.run->scenario ? c.run->scenario->objects.size() : 0);
  return Max(static_cast<std::int64_t>(n));
}
// Places where a goal and a scene differ: each object of the scenario (or of
// the world) at most twice, where the goal shows it and where the scene does.
Max differences(const BoundsContext& c) {
  if (!c.run) return Max(2 * c.protocol->limits.objects);
  const std::size_t n = c.run->scenario ? c.run->scenario->objects.size() : c.run->world.objects.size();
  return Max(2 * static_cast<std::int64_t>(n));
}
// Actions imagined before a query: a plan's length less one (planner.search.max_depth is at most 4).
Max imagined(const BoundsContext& c) { return Max(c.run ? c.run->planner.max_depth - 1 : 3); }
// At most one sub-goal record per planner iteration.
Max subGoals(const BoundsContext& c) { return Max(c.run ? c.run->planner.budget : c.protocol->limits.sub_goals); }

}  // namespace

wire::affordance_table_t_bounds boundsOf(const BoundsContext& c, const affordance_table_t*) {
  return {nameBytes(c), /*n_objects*/ objects(c), /*n_actions*/ actions()};
}

wire::decision_t_bounds boundsOf(const BoundsContext& c, const decision_t*) { return {nameBytes(c)}; }

wire::effect_t_bounds boundsOf(const BoundsContext& c, const effect_t*) {
  return {nameBytes(c), /*size*/ focusImageBytes(c)};
}

wire::extrinsic_result_t_bounds boundsOf(const BoundsContext& c, const extrinsic_result_t*) {
  return {nameBytes(c), /*scenario*/ nameBytes(c), /*n_sub_goals*/ subGoals(c), boundsFor<sub_goal_t>(c)};
}

wire::focus_t_bounds boundsOf(const BoundsContext& c, const focus_t*) {
  return {nameBytes(c), /*size*/ focusImageBytes(c), /*n_diffs*/ differences(c)};
}

wire::forward_prediction_t_bounds boundsOf(const BoundsContext& c, const forward_prediction_t*) {
  return {nameBytes(c), /*n_actions*/ actions(), /*size*/ focusImageBytes(c), /*n_input*/ actions()};
}

wire::forward_query_t_bounds boundsOf(const BoundsContext& c, const forward_query_t*) {
  return {nameBytes(c), /*size*/ focusImageBytes(c), /*n_actions*/ actions(), /*n_prefix*/ imagined(c)};
}

wire::goal_t_bounds boundsOf(const BoundsContext& c, const goal_t*) {
  return {nameBytes(c), /*size*/ focusImageBytes(c)};
}

wire::goal_result_t_bounds boundsOf(const BoundsContext& c, const goal_result_t*) { return {nameBytes(c)}; }

wire::look_t_bounds boundsOf(const BoundsContext& c, const look_t*) { return {nameBytes(c)}; }

wire::object_probe_t_bounds boundsOf(const BoundsContext& c, const object_probe_t*) {
  return {nameBytes(c), /*n_objects*/ objects(c), /*names*/ nameBytes(c), /*size*/ focusImageBytes(c)};
}

wire::prediction_t_bounds boundsOf(const BoundsContext& c, const prediction_t*) {
  return {nameBytes(c), /*n_actions*/ actions(), /*n_tried*/ actions(), /*n_trained*/ trainedReports(),
          boundsFor<trained_t>(c)};
}

wire::process_status_t_bounds boundsOf(const BoundsContext& c, const process_status_t*) {
  return {nameBytes(c),
          /*process*/ nameBytes(c),
          /*detail*/ textBytes(c),
          /*stuck*/ textBytes(c),
          /*counts_run*/ nameBytes(c),
          /*n_channels*/ channels(),
          /*channels*/ nameBytes(c),
          /*n_takes*/ channels(),
          /*takes*/ nameBytes(c),
          /*host*/ nameBytes(c),
          /*n_copies*/ Max(kCopiesNamed),
          /*copies*/ nameBytes(c)};
}

wire::resend_t_bounds boundsOf(const BoundsContext& c, const resend_t*) {
  return {nameBytes(c), /*channel*/ nameBytes(c), /*requester*/ nameBytes(c)};
}

wire::run_config_t_bounds boundsOf(const BoundsContext& c, const run_config_t*) {
  return {nameBytes(c), /*experiment*/ nameBytes(c), /*system*/ nameBytes(c), /*config_yaml*/ configBytes(c)};
}

wire::run_control_t_bounds boundsOf(const BoundsContext& c, const run_control_t*) { return {nameBytes(c)}; }

wire::run_result_t_bounds boundsOf(const BoundsContext& c, const run_result_t*) {
  return {nameBytes(c),
          /*weights_checksum*/ nameBytes(c),
          /*checkpoint*/ textBytes(c),
          /*n_actions*/ actions(),
          /*n_trained*/ trainedReports(),
          boundsFor<trained_t>(c)};
}

wire::scene_t_bounds boundsOf(const BoundsContext& c, const scene_t*) {
  return {nameBytes(c), /*size*/ sceneBytes(c), /*n_objects*/ sceneObjects(c)};
}

wire::sub_goal_t_bounds boundsOf(const BoundsContext&, const sub_goal_t*) { return {}; }

wire::trained_t_bounds boundsOf(const BoundsContext& c, const trained_t*) { return {nameBytes(c)}; }

}  // namespace afford

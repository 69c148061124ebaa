// Every key of a run's configuration, declared once, in the manner of Drake's
// Serialize/Visit: its name, its type and range or choices, where its value
// comes from, and its meaning. A visitor walks the declaration: the parser
// (config.cpp) reads a YAML tree through it, the describer lists the keys
// (`afford config --keys`, the tables of docs/configuration.md, the tests
// that check defaults.yaml and the docs against it). The values themselves,
// with their sources, are in config/defaults.yaml and the experiment files.
//
// A visitor V has:
//   section(key, body)                  a map of keys; body() declares them
//   given(key, body)                    body's keys are read only if `key` is in the YAML (older logs lack it)
//   number(key, field, lo, hi, meaning) integer(...) text(key, field, meaning) kind(key, field, meaning)
//   choice(key, field, names, meaning)  pair(key, a, b, lo, hi, meaning)  (a list of two numbers)
//   interval(key, lo_field, hi_field, lo, hi, meaning)  (a pair [min, max] with min < max)
//   custom(key, type, read, meaning)    read(Reader&) parses what the declaration cannot say (lists of maps)
//   from(origin)                        where the keys declared next get their value (KeyInfo::Origin)
#pragma once
#include <cstdint>

#include "afford/config.hpp"

namespace afford {

template <class V>
void declareProtocol(V& v, ProtocolConfig& c) {
  v.integer("heartbeat_ms", c.heartbeat_ms, 10, 60'000, "`STATUS` period: liveness and message counts");
  v.integer("idle_announce_ms", c.idle_announce_ms, 1, 60'000,
            "a process of a run idle this long announces its counts at once (then backing off to the heartbeat): "
            "a lost last message is asked for within milliseconds");
  v.given("idle_announce_pace", [&] {  // the runs of older logs announced after idle_announce_ms alone
    v.integer("idle_announce_pace", c.idle_announce_pace, 1, 1'000,
              "... once idle this many times as long as it usually waits for its next input after publishing "
              "(0 ms at first, a moving average): on a loaded machine every wait is longer, and none is a loss");
  });
  v.given("freshness_ms", [&] {  // the runs of older logs had no freshness on a keyed bus
    v.integer("freshness_ms", c.freshness_ms, 0, 86'400'000,
              "on a keyed bus, a message of a sender this process has not heard yet is taken only if it was sent "
              "less than this long ago by its clock (0: any); a sender heard is held to its counter's window");
  });
  v.integer("retry_ms", c.retry_ms, 1, 60'000,
            "an unanswered `RESEND` is asked again after this, doubling up to the heartbeat; the runner says a "
            "configuration again on the same schedule");
  v.integer("resend_batch", c.resend_batch, 1, 100'000, "serials asked for in one `RESEND`");
  v.integer("resend_cap", c.resend_cap, 1, 100'000, "serials republished for one `RESEND`");
  v.integer("resend_budget", c.resend_budget, 1, 1'000'000,
            "serials a publisher republishes per channel within `retry_ms`");
  v.integer("stop_grace_ms", c.stop_grace_ms, 0, 600'000,
            "after `STOP`, the logger waits for missing messages until this long passes with none coming");
  v.integer("ready_timeout_ms", c.ready_timeout_ms, 100, 600'000,
            "the runner fails a run whose processes are not free, or not configured, after this long in which no "
            "more of them became so");
  v.integer("close_timeout_ms", c.close_timeout_ms, 100, 600'000,
            "... whose logger, heard after `STOP`, has neither recorded more nor closed the log for this long "
            "(longer than `stop_grace_ms`)");
  v.integer("max_deferred", c.max_deferred, 1, 1'000'000,
            "messages waiting for their turn in a process; reaching it fails the run naming the channel "
            "(at least `resend_batch`)");
  v.integer("queue_capacity", c.queue_capacity, 30, 1'000'000, "LCM's queue of each subscription, in messages");
  v.section("limits", [&] {
    ProtocolLimits& l = c.limits;
    v.integer("name_bytes", l.name_bytes, 16, 65'536,
              "what a receiver accepts before a run's configuration tells it more (the viewer, `afford status`): "
              "run ids, process, channel and object names");
    v.integer("text_bytes", l.text_bytes, 16, 1'048'576, "... a `STATUS` detail (an error message)");
    v.integer("config_bytes", l.config_bytes, 1024, 64 * 1'048'576,
              "... a `RUN_CONFIG` text (the largest shipped configuration is under 10 KB)");
    v.integer("objects", l.objects, 1, 100'000, "... objects of a probe or an affordance table");
    v.integer("focus_side", l.focus_side, 3, 4096,
              "... the side of a focus image (the largest `eye.focus_side` the configuration accepts)");
    v.integer("scene_side", l.scene_side, 32, 8192,
              "... the side of a scene (the largest `world.size_px` the configuration accepts)");
    v.integer("sub_goals", l.sub_goals, 1, 1'000'000, "... sub-goal records of one extrinsic test");
    v.integer("run_id_bytes", l.run_id_bytes, 16, 240,
              "the longest run id (at most `name_bytes`); a run id is letters, digits, `.`, `_` and `-`, not "
              "beginning with `.` or `-` (it names folders and files: docs/security.md)");
    v.integer("peers", l.peers, 8, 100'000,
              "(process, pid) pairs a receiver tracks the heartbeats of (the edge, `afford status`); beyond, the "
              "one heard from longest ago is forgotten");
    v.integer("control_messages", l.control_messages, 4, 100'000,
              "distinct `RUN_CONFIG` and `RUN_CONTROL` messages the logger records in one run (a run has 3); the "
              "manifest counts the rest");
  });
  v.given("recovery", [&] {  // the runs of older logs held everything and snapshotted nothing
    v.section("recovery", [&] {
      RecoveryConfig& r = c.recovery;
      v.integer("snapshot_steps", r.snapshot_steps, 0, 1'000'000'000,
                "each process saves its state in the run (a snapshot) every this many steps, and its peers let go "
                "of what they published before every reader's latest snapshot (0: never: a restart replays the run)");
      v.integer("history_keep", r.history_keep, 1, 1'000'000,
                "messages of each channel a publisher holds whatever its readers' snapshots say (for receivers that "
                "take no snapshot: the runner, observers)");
      v.integer("history_mb", r.history_mb, 1, 1'048'576,
                "what a process holds of what it published, at most, in MiB; beyond it the oldest is let go even if "
                "a reader's restart would need it (that restart then fails, naming the channel)");
      v.integer("snapshot_mb", r.snapshot_mb, 1, 1'048'576,
                "the largest snapshot a restarted process reads back, in MiB (a larger file is refused)");
    });
  });
  v.section("bus", [&] {
    BusConfig& b = c.bus;
    v.integer("max_message_bytes", b.max_message_bytes, 65'536, 1 << 30,
              "LCM drops a larger message at its first datagram, and a publisher refuses to send one (naming the "
              "channel and this key); at least 64 KiB more than `limits.config_bytes` and `limits.text_bytes`");
    v.integer("fragment_bytes", b.fragment_bytes, 65'536, 1 << 30,
              "incomplete fragmented messages hold at most this together (at least `max_message_bytes`)");
    v.integer("fragment_timeout_ms", b.fragment_timeout_ms, 10, 600'000,
              "an incomplete fragmented message is dropped this long after its first fragment");
    v.integer("queue_bytes", b.queue_bytes, 65'536, 1 << 30,
              "received messages waiting to be handled hold at most this together; a message beyond it is dropped "
              "(at least `max_message_bytes`)");
  });
}

template <class V>
void declareWorld(V& v, RunConfig& c) {
  v.section("world", [&] {
    WorldConfig& w = c.world;
    v.given("kind", [&] {  // the runs of older logs were all of the paper's world
      v.choice("kind", w.kind, kWorldKindNames,
               "`grid`: the paper's world of flat shapes and a configured affordance table; `table`: a physical "
               "table simulated by MuJoCo, seen by a camera, acted on by a hand (the `table` section; "
               "[model](model.md#a-physical-table))");
    });
    v.integer("size_px", w.size_px, 32, 2048, "scene side in pixels (side = 1 unit)");
    v.number("object_size", w.object_size, 0.01, 0.3, "square side; circle and rectangle have the same area");
    v.interval("table", w.table_min, w.table_max, 0.0, 1.0, "range of object centres");
    v.integer("max_target_draws", w.max_target_draws, 1, 1'000'000,
              "redraws of a random move target before the move does nothing");
    v.choice("positions", w.positions, kPositionsNames,
             "`continuous`: real centres and move targets, each shape drawn from its centre, late objects at "
             "random free places (the authors' code); `pixel`: centres snapped to a pixel, one footprint per "
             "shape, late objects at their configured places ([model](model.md#positions): how each draws, and "
             "when a place is free)");
    v.choice("late_overlap", w.late_overlap, kBoolNames,
             "continuous positions: a late object's place need only be free of the objects present before its "
             "step, so late objects of one step may overlap");
    v.from(KeyInfo::Origin::Experiment);
    v.custom("objects", "a list of objects", [&](auto& r) { readObjects(r, w); },
             "name, shape, colour, position, `appears_at`, `affordance` [move, green, red, blue]. The objects "
             "present at step 0 may not overlap or touch, and objects of one look (shape and colour) have one "
             "affordance row (`grid` only: a table's are `table.objects`)");
    v.from(KeyInfo::Origin::Defaults);
  });
}

// The physical table world (world.kind: table), its values in config/defaults.yaml with their sources.
template <class V>
void declareTable(V& v, RunConfig& c) {
  v.given("table", [&] {  // the runs of older logs had no table world
    v.section("table", [&] {
      table::TableWorldConfig& t = c.table;
      table::TableSpec& s = t.spec;
      v.section("top", [&] {
        v.number("half_x", s.half_x, 0.05, 2.0, "the table top's half-extent across (x, m), inside its rim");
        v.number("half_y", s.half_y, 0.05, 2.0, "... along (y, m)");
        v.number("rim_height", s.rim_height, 0.001, 0.5, "the rim that keeps objects on the table (m)");
        v.number("friction", s.friction, 0.01, 10.0, "the top's sliding friction coefficient");
        v.custom("colour", "three numbers in [0, 1]", [&](auto& r) { readTriple(r, "colour", s.rgb.data(), 0, 1); },
                 "the top's colour (RGB)");
      });
      v.number("timestep", s.timestep, 0.0005, 0.01, "the physics step (s)");
      v.section("camera", [&] {
        v.integer("width", s.camera.width, 16, 2048, "the camera image's width (pixels; the scene a SCENE carries, as world.size_px)");
        v.integer("height", s.camera.height, 16, 2048, "... its height");
        v.number("above", s.camera.above, 0.1, 10.0, "the camera's height over the table's centre, looking down (m)");
        v.number("fovy_deg", s.camera.fovy_deg, 1.0, 170.0, "its vertical field of view (degrees)");
      });
      v.section("hand", [&] {
        table::HandSpec& h = s.hand;
        v.custom("palm", "three numbers in [0.001, 0.5]", [&](auto& r) { readTriple(r, "palm", h.palm_half, 0.001, 0.5); },
                 "the palm's half-extents (x, y, z; m)");
        v.custom("finger", "three numbers in [0.001, 0.5]",
                 [&](auto& r) { readTriple(r, "finger", h.finger_half, 0.001, 0.5); },
                 "each finger's half-extents (x, y, z; m): the fingers close along the palm's y");
        v.number("finger_travel", h.finger_travel, 0.002, 0.5, "each finger's centre from the palm's, open (m)");
        v.number("mass", h.mass, 0.001, 100.0, "the palm's mass (kg); each finger's is a quarter of it");
        v.number("friction", h.friction, 0.01, 10.0, "the fingers' sliding friction coefficient");
        v.number("kp_move", h.kp_move, 1.0, 1e7, "the x, y, z slides' position gain (N/m)");
        v.number("kp_yaw", h.kp_yaw, 0.01, 1e6, "the yaw hinge's position gain (N m/rad)");
        v.number("kp_finger", h.kp_finger, 1.0, 1e6, "each finger's position gain (N/m)");
        v.number("time_constant", h.time_constant, 0.001, 10.0,
                 "each joint's damping is its gain times this (s): the hand's settling time");
        v.number("rest_height", h.rest_height, 0.01, 5.0, "the palm's centre over the table at the gantry's zero (m)");
        v.custom("park", "three numbers in [-5, 5]", [&](auto& r) { readTriple(r, "park", h.park, -5, 5); },
                 "where the palm's centre waits between actions, out of the camera's view (x, y, z; m)");
        v.pair("reach", h.reach_x, h.reach_y, 0.01, 5.0, "the slides' half-ranges (x, y; m)");
        v.custom("colour", "three numbers in [0, 1]", [&](auto& r) { readTriple(r, "colour", h.rgb.data(), 0, 1); },
                 "the hand's colour (RGB)");
      });
      v.section("primitives", [&] {
        table::PrimitiveSpec& p = t.primitives;
        v.number("travel_speed", p.travel_speed, 0.01, 10.0, "the hand's speed between places (m/s)");
        v.number("contact_speed", p.contact_speed, 0.01, 10.0, "... while it pushes, lowers or lifts an object (m/s)");
        v.number("tap_speed", p.tap_speed, 0.01, 10.0, "... in roll's tap (m/s)");
        v.number("safe_height", p.safe_height, 0.01, 5.0, "the fingers' tips over the table while the hand travels (m)");
        v.number("clearance", p.clearance, 0.0, 0.5, "the gap left behind an object before contact (m)");
        v.number("push_height", p.push_height, 0.0, 0.5, "the fingers' tips over the table in a push or a tap (m)");
        v.number("push_gap", p.push_gap, 0.0, 1.0, "a push's fork: the fingers' gap, a fraction of the object's width");
        v.number("grasp_height", p.grasp_height, 0.0, 1.0, "carry: the fingers' tips, a fraction of the object's height");
        v.number("carry_height", p.carry_height, 0.01, 5.0, "carry: the fingers' tips over the table while carrying (m)");
        v.number("topple_height", p.topple_height, 0.0, 1.0, "topple: where the tips hit, a fraction of the height");
        v.number("topple_drop", p.topple_drop, 0.01, 0.99,
                 "topple's goal: the object's centre this fraction of its resting height lower");
        v.number("tap_stroke", p.tap_stroke, 0.001, 0.5, "roll: how far the tap goes past the first contact (m)");
        v.number("roll_distance", p.roll_distance, 0.001, 5.0, "roll's goal: the object rests this far away (m)");
        v.number("success_radius", p.success_radius, 0.001, 1.0, "push's and carry's goal: this close to the place (m)");
        v.number("reach_tolerance", p.reach_tolerance, 0.0001, 0.5, "a set-point is reached this close (m)");
        v.number("waypoint_bound_s", p.waypoint_bound_s, 0.01, 60.0, "at most this long per set-point (s)");
        v.number("rest_speed", p.rest_speed, 1e-5, 1.0, "at rest: every body slower than this (m/s; rad/s: tenfold)");
        v.number("rest_hold_s", p.rest_hold_s, 0.0, 10.0, "... for this long (s)");
        v.number("settle_bound_s", p.settle_bound_s, 0.01, 60.0, "at most this long waiting for rest (s)");
        v.number("noise_position", p.noise_position, 0.0, 0.5, "where the hand comes down: sd of x and y (m)");
        v.number("noise_height", p.noise_height, 0.0, 0.5, "the tips' height in a push, topple or tap: sd (m)");
        v.number("noise_direction", p.noise_direction, 0.0, 3.2, "the direction of a push, topple or tap: sd (rad)");
        v.number("noise_yaw", p.noise_yaw, 0.0, 3.2, "the hand's yaw in a grasp: sd (rad)");
      });
      v.section("scene", [&] {
        v.integer("reset_every", t.scene.reset_every, 0, 1'000'000'000,
                  "a run's scene is set up anew every this many steps (0: never): the objects at drawn free places "
                  "of the truth's region, in their configured poses");
        v.number("gap", t.scene.gap, 0.0, 1.0, "... at least this far apart, footprint to footprint (m)");
      });
      v.section("perception", [&] {
        v.number("topple_area", t.perception.topple_area, 1.01, 100.0,
                 "the eye sees a topple's effect when the object's silhouette grows by this factor at least");
      });
      v.section("truth", [&] {
        v.pair("region", t.truth.region_x, t.truth.region_y, 0.01, 2.0,
               "a trial's object is drawn in [-x, x] x [-y, y] (m)");
        v.interval("places", t.truth.place_min, t.truth.place_max, 0.001, 4.0,
                   "push and carry: the place drawn this far from the object (m)");
        v.integer("trials", t.truth_trials, 1, 1'000'000, "trials of each (object, action) by `afford world truth`");
      });
      v.from(KeyInfo::Origin::Experiment);
      v.custom("objects", "a list of objects", [&](auto& r) { readTableObjects(r, s); },
               "a table experiment's objects: name, shape (`box`, `cylinder`, `sphere`), size (half-extents; "
               "radius and half-length; radius), `lying` (a cylinder on its side), mass, friction, "
               "torsional_friction, rolling_friction, colour, and optionally `affordance` [push, carry, topple, roll]: the "
               "truth a run's learned table is measured against (`afford experiment` writes the estimate of `afford "
               "world truth` there)");
      v.from(KeyInfo::Origin::Defaults);
    });
  });
}

template <class V>
void declareEye(V& v, RunConfig& c) {
  v.section("eye", [&] {
    EyeConfig& e = c.eye;
    v.integer("focus_side", e.focus_side, 3, 101, "focus image side, odd (0.14 x 150)");
    v.number("saliency_noise", e.saliency_noise, 0.0, 1.0, "uniform noise half-width");
    v.number("saliency_sigma_px", e.saliency_sigma_px, 0.0, 20.0, "Gaussian smoothing of the saliency image");
    v.choice("saliency_order", e.saliency_order, kSaliencyOrderNames,
             "`noise_then_smooth` is the paper's wording, `smooth_then_noise` the authors' code");
    v.number("change_sigma_px", e.change_sigma_px, 0.0, 20.0, "smoothing of the change image");
    v.pair("initial_gaze", e.initial_gaze_x, e.initial_gaze_y, 0.0, 1.0, "where the eye looks at first");
    v.number("image_change_threshold", e.image_change_threshold, 0.0, 1.0, "tau_i");
    v.number("position_change_threshold", e.position_change_threshold, 0.0, 1.0, "tau_p");
    v.integer("max_scan_draws", e.max_scan_draws, 1, 100000, "bound on redraws until the gaze lands on another object");
    v.choice("attention", e.attention, kAttentionNames,
             "`bottom_up`: the paper's saliency scans of goal and scene; `top_down`: one look at where scene and "
             "goal differ, objects remembered by the planner, inhibition of return (docs/model.md)");
    v.given("fovea", [&] {  // the runs of older logs had the centroid eye
      v.choice("fovea", e.fovea, kFoveaNames,
               "`blob_centroid`: the window on the found blob's centroid, from the image alone; `true_centre`: on "
               "the true centre of the object the blob shows, which the environment then lists in every SCENE (the "
               "authors' eye; the eye no longer works from the image alone: docs/model.md#fovea)");
    });
  });
}

template <class V>
void declarePredictors(V& v, RunConfig& c) {
  v.section("predictors", [&] {
    PredictorsConfig& p = c.predictors;
    v.section("affordance", [&] {
      v.given("kind", [&] {
        v.kind("kind", p.affordance_kind,
               "the affordance component, the affordance and learning-progress predictors (paper 2.3.3): `paper`, "
               "or a kind a process of one's own registers (docs/writing-a-component.md)");
      });
      v.number("learning_rate", p.affordance_learning_rate, 0.0, 10.0, "the affordance predictor's learning rate");
    });
    v.section("learning_progress", [&] {
      v.number("learning_rate", p.learning_progress_learning_rate, 0.0, 10.0,
               "the learning-progress predictor's learning rate");
      v.number("init_magnitude", p.learning_progress_init, 0.0, 1.0, "initial weights are +- this, with random sign");
    });
    v.section("what_effect", [&] {
      v.number("learning_rate", p.what_effect_learning_rate, 0.0, 10.0, "the what-effect forward model's learning rate");
    });
    v.section("where_effect", [&] {
      v.number("learning_rate", p.where_effect_learning_rate, 0.0, 10.0,
               "the where-effect forward model's learning rate");
    });
    v.section("memory", [&] {
      MemoryConfig& m = p.memory;
      v.number("look_threshold", m.look_threshold, 0.0, 1.0,
               "beyond the paper (docs/model.md#memory): two focus images show one look below this mean absolute "
               "difference per value");
      v.integer("look_shift_px", m.look_shift_px, 0, 10,
                "... with the images shifted against each other by up to this many pixels");
      v.integer("max_looks", m.max_looks, 1, 100'000, "looks remembered; a new one replaces the one seen least recently");
      v.integer("per_look_action", m.per_look_action, 1, 100'000, "experiences kept per look and action (the newest)");
      v.given("keep", [&] {
        v.choice("keep", m.keep, kMemoryKeepNames,
                 "keep the memory: `auto` (when replay, revisits or a motivation other than `paper` may use it), "
                 "`always` or `never` (refused with replay or revisits)");
      });
    });
    v.section("replay", [&] {
      ReplayConfig& r = p.replay;
      v.choice("enabled", r.enabled, kBoolNames,
               "experience replay (docs/model.md#replay); false is the paper's agent");
      v.integer("ratio", r.ratio, 0, 10'000, "replayed affordance updates per intrinsic step (passes included)");
      v.number("effects_ratio", r.effects_ratio, 0.0, 10'000.0,
               "forward-model updates per intrinsic step, on average: the step's own if its action had its effect, "
               "remembered ones for the rest");
      v.choice("sampling", r.sampling, kReplaySamplingNames,
               "`balanced`: a remembered look and action uniformly, then one of its experiences; `uniform`: any "
               "remembered experience");
    });
  });
}

template <class V>
void declareMotivation(V& v, RunConfig& c) {
  v.section("motivation", [&] {
    MotivationConfig& m = c.motivation;
    v.kind("kind", m.kind,
           "the motivation component: `paper` (FIX, IGN or IMP, the run's system: paper 2.4.1) or `novelty` "
           "(count-based, beyond the paper), or one a process of one's own registers (docs/writing-a-component.md)");
    v.section("novelty", [&] {
      v.number("threshold", m.novelty_threshold, 0.0, 1.0,
               "`novelty` acts while 1/sqrt(1+n) is at least this, n the times it chose the least chosen action on "
               "the focused look");
    });
    v.number("fixed_threshold", m.fixed_threshold, 0.0, 1.0, "FIX's threshold");
    v.number("leak", m.leak, 0.0, 1.0, "nu of equation 2");
    v.number("initial_threshold", m.initial_threshold, 0.0, 1.0, "IGN's and IMP's first threshold (th_0)");
    v.number("act_margin", m.act_margin, 0.0, 1.0, "act when motivation + margin >= threshold");
    v.choice("imp_threshold_input", m.imp_threshold_input, kImpThresholdInputNames,
             "what IMP's threshold averages: `signal` (the IM signal) or `observed_change` (the observed absolute "
             "change of the affordance output, as the authors' code)");
    v.section("revisit", [&] {
      RevisitConfig& r = m.revisit;
      v.choice("enabled", r.enabled, kBoolNames,
               "try on the focused look an action never tried on it, or not tried for `after_steps` "
               "(docs/model.md#revisit); false is the paper's agent");
      v.integer("after_steps", r.after_steps, 0, 100'000'000, "0: only actions never tried on the look");
      v.choice("order", r.order, kRevisitOrderNames,
               "which never-tried action first: `actions` (the action order) or `random` (move, then the colours in "
               "an order drawn from seed and step)");
    });
  });
}

template <class V>
void declareGoals(V& v, RunConfig& c) {
  v.section("goals", [&] {
    GoalsConfig& g = c.goals;
    v.kind("kind", g.kind,
           "the goal chooser of the goals phase: `imgep` (goals from what the agent saw, chosen by competence "
           "progress: docs/model.md#goals-of-its-own), or one a process of one's own registers");
    v.integer("budget", g.budget, 1, 1'000'000, "actions the planner may spend on one goal");
    v.integer("window", g.window, 1, 1'000'000, "attempts per module in each half of its competence window");
    v.number("random_share", g.random_share, 0.0, 1.0,
             "share of module choices drawn uniformly; the others follow |competence progress|");
    v.number("explore_share", g.explore_share, 0.0, 1.0,
             "share of goals that try a random action on the object a saliency scan picks");
    v.integer("bootstrap", g.bootstrap, 0, 100'000'000, "goals at the start of a run that are explorations");
    v.integer("memory", g.memory, 1, 100'000, "outcomes, places and objects the chooser keeps (the oldest go first)");
    v.integer("held", g.held, 32, 10'000'000,
              "object looks, forward predictions and effects (each kind apart) the motivation holds ahead of the goal "
              "results they come before (a process catching up gets them early); more than one goal brings");
  });
}

template <class V>
void declarePlanner(V& v, RunConfig& c) {
  v.section("planner", [&] {
    PlannerConfig& p = c.planner;
    v.number("subgoal_match", p.subgoal_match, 0.0, 1.0, "sub-goal reached: image distance below this");
    v.number("image_match", p.image_match, 0.0, 1.0, "predicted what-effect matches the sub-goal image");
    v.number("position_match", p.position_match, 0.0, 1.0, "predicted where-effect matches the sub-goal position");
    v.choice("position_metric", p.position_metric, kPositionMetricNames,
             "`euclidean`: the plain distance of the predicted where-effect from the sub-goal place; "
             "`half_euclidean`: half of it");
    v.integer("subgoal_timeout", p.subgoal_timeout, 1, 1000, "iterations before another sub-goal is chosen");
    v.integer("budget", p.budget, 1, 1'000'000, "iterations per extrinsic test");
    v.integer("max_attempts", p.max_attempts, 1, 1'000'000,
              "actions per extrinsic test (the action budget of the utility tests)");
    v.choice("restrict_by_affordance", p.restrict_by_affordance, kBoolNames, "check only afforded actions");
    v.number("affordance_threshold", p.affordance_threshold, 0.0, 1.0, "\"afforded\" means affordance above this");
    v.number("success_distance", p.success_distance, 0.0, 1.0, "the scene matches the goal (distance / 67,500)");
    v.choice("kind", p.kind, kPlannerKindNames, "`goal`: Algorithm 2; `utility`: Algorithm 3");
    v.section("search", [&] {
      v.integer("max_depth", p.max_depth, 1, 4,
                "actions in a plan: 2 to 4 chain predicted effects through the forward models, restricted by the "
                "predicted affordances (docs/model.md#multi-step-planning)");
      v.integer("max_queries", p.max_queries, 1, 10000,
                "forward queries per iteration (1 + 4 + 16 covers every two-action chain)");
    });
    v.section("utility", [&] {
      v.integer("evaluation_iterations", p.evaluation_iterations, 0, 1'000'000,
                "first iterations only estimate the potential utility");
      v.number("raise_leak", p.raise_leak, 0.0, 1.0, "nu raising the potential utility to a better couple's U");
      v.number("lower_leak", p.lower_leak, 0.0, 1.0, "nu lowering it towards 0 for each chosen action");
    });
  });
}

template <class V>
void declareRunConfig(V& v, RunConfig& c) {
  v.from(KeyInfo::Origin::Runner);
  v.text("experiment", c.experiment, "the experiment's name (or file) the run belongs to");
  v.choice("system", c.system, kSystemNames,
           "FIX, IGN or IMP: the motivation of the paper's three systems; GOALS: the agent that sets its own goals "
           "(it learns in the goals phase)");
  v.integer("seed", c.seed, 0, INT64_MAX, "the run's seed: every draw is keyed by (seed, step, purpose)");
  v.from(KeyInfo::Origin::Defaults);
  v.choice("phase", c.phase, kPhaseNames,
           "`intrinsic` (learning, Algorithm 1), `goals` (learning, the agent setting its own goals: system GOALS) "
           "or `extrinsic` (a test, Algorithm 2 or 3); set by the runner, with `extrinsic.checkpoint` and "
           "`extrinsic.scenario`");
  v.section("run", [&] {
    v.integer("steps", c.steps, 1, 100'000'000, "intrinsic steps");
    v.integer("curve_interval", c.curve_interval, 1, 100'000'000, "steps between affordance tables (learning curves)");
    v.given("checkpoint", [&] {
      v.text("checkpoint", c.checkpoint, "where the predictors save their weights after the last intrinsic step "
                                         "(the runner puts it in the run's folder)");
    });
    v.integer("checkpoint_after_actions", c.checkpoint_after_actions, 0, 100'000'000,
              "also save the weights once this many actions are learned, to "
              "`<checkpoint stem>.after-<N>-actions.ckpt` (0: no)");
    v.choice("record", c.record, kBoolNames,
             "a logger on the bus records the run; `afford experiment --keep-logs` sets it per run");
  });
  declareWorld(v, c);
  declareTable(v, c);
  declareEye(v, c);
  declarePredictors(v, c);
  declareMotivation(v, c);
  declareGoals(v, c);
  v.from(KeyInfo::Origin::Runner);
  v.given("extrinsic", [&] {
    v.section("extrinsic", [&] {
      v.text("checkpoint", c.extrinsic_checkpoint, "an extrinsic test: the trained predictors it loads");
      v.custom("scenario", "a scenario", [&](auto& r) { readScenario(r, c); },
               "... and the scenario it tests (config/scenarios/*.yaml, or generated)");
    });
  });
  v.from(KeyInfo::Origin::Defaults);
  declarePlanner(v, c);
  v.section("protocol", [&] { declareProtocol(v, c.protocol); });
}

}  // namespace afford

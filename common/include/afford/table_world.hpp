// The physical table world's configuration (world.kind: table; docs/model.md, "A physical table"): the
// table, its camera, its hand and its objects, the hand's motor primitives, and how the truth is estimated,
// as numbers the configuration gives (the `table` section; config/defaults.yaml has each value's source).
// Plain data: the simulation that uses it is processes/environment/table. Units: metres, kilograms, seconds,
// radians. Frame: the table's top is the plane z = 0, its centre the origin; x across the table (its short
// side), y along it, z up.
#pragma once
#include <cstdint>
#include <array>
#include <string>
#include <vector>

namespace afford::table {


// An object's geometry. Box: `size` its three half-extents (x, y, z); cylinder: its radius and
// half-length; sphere: its radius. A lying cylinder has its axis along the table's x (it rolls along y).
enum class Shape { Box, Cylinder, Sphere };

struct ObjectSpec {
  std::string name;                 // unique; the simulation's body and geom are named after it
  Shape shape = Shape::Box;
  std::vector<double> size;         // as the shape says: 3, 2 or 1 values, each > 0
  bool lying = false;               // cylinders only: the axis horizontal
  double mass = 0;                  // kg
  double friction = 0;              // sliding friction coefficient (MuJoCo's first friction value)
  double torsional_friction = 0;    // MuJoCo's second friction value (spin about the contact normal)
  double rolling_friction = 0;      // MuJoCo's third friction value (rolling)
  std::array<double, 3> rgb{};      // colour, each in [0, 1]
  // The truth a run's learned affordances are measured against (push, carry, topple, roll), when the
  // configuration gives it: `afford experiment` writes the estimate of `afford world truth` there.
  std::array<double, 4> affordance{};
  bool has_affordance = false;

  // The height of the object's centre above the table when it rests in its configured pose.
  double restingHeight() const;
  // The radius of the smallest vertical cylinder holding the object's footprint (for free places).
  double footprintRadius() const;
};

struct CameraSpec {
  int width = 0, height = 0;       // pixels
  double above = 0;                // the camera's height above the table's centre, looking straight down
  double fovy_deg = 0;             // vertical field of view (the image's rows span the table's x)

  // The pinhole's focal length in pixels.
  double focalPx() const;
  // Where the image shows a point of the table at height z: its pixel (column, row; pixel centres at .5),
  // and the same in scene units (a pixel's column and row over the width, centres at 0).
  std::array<double, 2> pixelOf(double x, double y, double z = 0) const;
  std::array<double, 2> sceneOf(double x, double y, double z = 0) const;
  // The point of the table's top (z = 0) a pixel (u, v) shows, and the one a scene point (sx, sy) shows.
  std::array<double, 2> tableAtPixel(double u, double v) const;
  std::array<double, 2> tableAt(double sx, double sy) const;
};

struct HandSpec {
  double palm_half[3] = {0, 0, 0};  // the palm's half-extents
  double finger_half[3] = {0, 0, 0};
  double finger_travel = 0;        // how far each finger opens from the palm's centre plane
  double mass = 0;                 // the palm's mass; each finger's is a quarter of it
  double friction = 0;             // the fingers' sliding friction
  double kp_move = 0;              // position gain of the x, y, z slides (N/m)
  double kp_yaw = 0;               // ... of the yaw hinge (N m / rad)
  double kp_finger = 0;            // ... of each finger's slide
  double time_constant = 0;        // every hand joint's damping is its gain times this (s): one settling time
  double rest_height = 0;          // the palm's centre above the table: the gantry's zero
  double park[3] = {0, 0, 0};      // where the palm's centre waits between actions (out of the camera's view)
  double reach_x = 0, reach_y = 0; // the slides' half-ranges over the table
  std::array<double, 3> rgb{};
};

struct TableSpec {
  double half_x = 0, half_y = 0;   // the table top's half-extents, inside its rim
  double rim_height = 0;           // a rim around the top keeps objects on it (its thickness is 1 cm)
  double friction = 0;             // the table top's sliding friction
  std::array<double, 3> rgb{};     // the table top's colour
  double timestep = 0;             // physics step (s)
  CameraSpec camera;
  HandSpec hand;
  std::vector<ObjectSpec> objects;
};

struct PrimitiveSpec {
  double travel_speed = 0;       // the hand's set-point speed between places (m/s)
  double contact_speed = 0;      // ... while it pushes, lowers or lifts an object (m/s)
  double tap_speed = 0;          // ... of roll's tap (m/s)
  double safe_height = 0;        // the fingers' tips above the table while the hand travels (m)
  double clearance = 0;          // the gap left between fingers and object before contact (m)
  double push_height = 0;        // the fingers' tips above the table while pushing (m)
  double push_gap = 0;           // a push's fork: the gap between the fingers, a fraction of the object's width
  double grasp_height = 0;       // ... while grasping, as a fraction of the object's height
  double carry_height = 0;       // the fingers' tips above the table while carrying (m)
  double topple_height = 0;      // where topple's fingers' tips hit, as a fraction of the object's height
  double topple_drop = 0;        // topple's goal: the centre this fraction of its resting height lower
  double tap_stroke = 0;         // how far roll's fingers go past the object's first contact (m)
  double roll_distance = 0;      // roll's goal: the object rests this far from where it was (m)
  double success_radius = 0;     // push's and carry's goal: this close to the place (m)
  double reach_tolerance = 0;    // a set-point is reached when the hand is this close (m)
  double waypoint_bound_s = 0;   // at most this long per set-point (s)
  double rest_speed = 0;         // at rest: every body slower than this (m/s; rad/s for tenfold)
  double rest_hold_s = 0;        // ... for this long (s)
  double settle_bound_s = 0;     // at most this long waiting for rest at the end (s)
  // The noise of the primitives' parameters (standard deviations).
  double noise_position = 0;     // where the hand comes down, each of x and y (m)
  double noise_height = 0;       // the fingers' height in a push, topple or tap (m)
  double noise_direction = 0;    // the direction of a push, topple or tap (rad)
  double noise_yaw = 0;          // the hand's yaw in a grasp (rad)
};

// Where a trial puts the object and the place it is taken to.
struct TruthSpec {
  double region_x = 0, region_y = 0;          // the object's centre drawn in [-region_x, region_x] x [-region_y, region_y]
  double place_min = 0, place_max = 0;        // push and carry: the place this far from the object, in the region
};

// A run's scene: the objects drawn at free places of the truth's region, in their configured poses, at the
// start and again every reset_every steps (0: never), keyed by (seed, step).
struct SceneSpec {
  std::int64_t reset_every = 0;
  double gap = 0;  // the least distance between two objects' footprints when the scene is set up (m)
};

// What the eye counts as each action's effect in this world (the goals' counterparts, seen in the image).
struct PerceptionSpec {
  double topple_area = 0;  // topple: the object's silhouette grows by this factor at least (a tall object lying)
};

// The whole `table` section.
struct TableWorldConfig {
  TableSpec spec;
  PrimitiveSpec primitives;
  TruthSpec truth;
  SceneSpec scene;
  PerceptionSpec perception;
  int truth_trials = 0;  // trials of each (object, action) cell that `afford world truth` makes
};

}  // namespace afford::table

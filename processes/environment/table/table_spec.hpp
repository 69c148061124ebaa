// The physical table world (world.kind: table): what a table, its camera, its hand and its objects are,
// as numbers a configuration gives. The model MuJoCo simulates (MJCF) is built from this alone
// (tableMjcf), so that an object kind, a size, a mass or a friction is changed by configuration.
// Units: metres, kilograms, seconds, radians. Frame: the table's top is the plane z = 0, its centre the
// origin; x across the table (its short side), y along it, z up. docs/model.md, "A physical table",
// gives every value's source.
#pragma once
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

  // The height of the object's centre above the table when it rests in its configured pose.
  double restingHeight() const;
  // The radius of the smallest vertical cylinder holding the object's footprint (for free places).
  double footprintRadius() const;
};

struct CameraSpec {
  int width = 0, height = 0;       // pixels
  double above = 0;                // the camera's height above the table's centre, looking straight down
  double fovy_deg = 0;             // vertical field of view (the image's rows span the table's x)
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

// Throws std::invalid_argument naming the object and field (or the table's field) that is wrong.
void validate(const TableSpec& spec);
// The MJCF text of the whole world: table, floor, light, camera, hand with its actuators, objects (each a
// free body named after the object, resting at the origin of its own frame until placed). validate()s first.
std::string tableMjcf(const TableSpec& spec);

const char* shapeName(Shape s);

}  // namespace afford::table

// The table world's simulation: MuJoCo's model and data built from a TableSpec, stepped, read and
// saved. Deterministic: the same spec, build and commands give the same state, bit for bit, and a state
// saved and set again continues as the run it came from did (the solver's warm start is part of it).
#pragma once
#include <mujoco/mujoco.h>

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "environment/table/table_spec.hpp"

namespace afford::table {

struct Pose {
  std::array<double, 3> pos{};   // the body's centre (m)
  std::array<double, 4> quat{};  // its orientation (w, x, y, z)
};

// Where the hand is told to go: its palm's centre over the table (m), its yaw (rad) and its fingers' opening
// (0 closed, 1 open as far as they go).
struct HandCommand {
  double x = 0, y = 0, z = 0, yaw = 0, opening = 1;
};

class TablePhysics {
 public:
  // Builds the MJCF (tableMjcf) and loads it; throws std::invalid_argument for a wrong spec and
  // std::runtime_error with MuJoCo's words when it refuses the model.
  explicit TablePhysics(const TableSpec& spec);
  ~TablePhysics();
  TablePhysics(const TablePhysics&) = delete;
  TablePhysics& operator=(const TablePhysics&) = delete;

  const TableSpec& spec() const { return spec_; }
  const mjModel* model() const { return model_; }
  const mjData* data() const { return data_; }

  void step(int n = 1);
  double time() const { return data_->time; }
  // `f` called after every `every`-th physics step from now on (a person's video of a primitive); it must leave
  // the simulation as it was (forward() does). An empty `f` stops it.
  void observe(std::function<void()> f, int every = 1);

  int objectCount() const { return static_cast<int>(spec_.objects.size()); }
  Pose objectPose(int i) const;
  // The world's set-up of a scene (never during an action): object i resting in its configured pose at
  // (x, y) on the table, turned by yaw about the vertical, still.
  void placeObject(int i, double x, double y, double yaw);
  // The hand's set-point (its actuators then move it, by physics).
  void commandHand(const HandCommand& c);
  // The palm's centre and yaw as the simulation has them now.
  HandCommand handNow() const;
  // How many times the simulation became unstable (MuJoCo found a bad acceleration and set its data back to
  // the model's initial state), since it was built.
  int instabilities() const;
  // Every object and the hand moving slower than these (m/s, rad/s).
  bool atRest(double linear, double angular) const;
  // The index of the object a simulation geom belongs to, or -1 (table, floor, hand).
  int objectOfGeom(int geom) const;

  // The whole state: time, positions, velocities, actuator states, controls and the solver's warm start.
  std::vector<double> state() const;
  // The bodies' and geoms' places computed for the positions as they are now (a step leaves them as they were
  // before it), for a camera; the next step is the same as without it.
  void forward();
  // Sets a state() of the same spec; throws std::invalid_argument naming the sizes when it is of another.
  void setState(const std::vector<double>& s);

 private:
  TableSpec spec_;
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::vector<int> object_body_, object_qpos_, object_dof_;  // per object
  std::vector<int> geom_object_;                              // per geom: object index or -1
  int hand_body_ = -1;
  std::function<void()> observer_;
  int observe_every_ = 1;
  long long observed_ = 0;  // physics steps since observe()
  std::array<int, 6> actuator_{};  // hand_x, hand_y, hand_z, hand_yaw, finger_l, finger_r
  std::array<int, 4> hand_qpos_{};  // hand_x, hand_y, hand_z, hand_yaw
};

}  // namespace afford::table

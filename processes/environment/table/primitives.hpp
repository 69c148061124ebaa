// The hand's motor primitives on the table: each action a sequence of set-points for the hand's actuators,
// followed over many physics steps until the scene is at rest (or a bound), and a goal checked from the
// simulation's state at the end (paper 2.1: an action is "successful" when its goal is reached). No object
// is placed by code: the hand moves them, by contact and friction, or does not.
//
// The four actions, in the order of the agent's tables:
//   push    (takes a place) the fingers, open as a fork narrower than the object, come down behind it and
//           sweep it toward the place;
//           goal: the object rests within success_radius of the place, in the pose it had (not toppled).
//   carry   (takes a place) the open fingers come down around the object, close, lift it, carry it over
//           the place, lower it and open; goal: as push's.
//   topple  the closed fingers sweep through the object high up, in a drawn direction; goal: the object's
//           centre rests at least topple_drop of its resting height lower than before the action (it fell over).
//   roll    the closed fingers tap the object low down, in a drawn direction, and stop short; goal: the
//           object rests at least roll_distance from where it was (it rolled on after the tap).
// Noise in each primitive's parameters (where the hand comes down, its height, its direction) is drawn by
// (seed, step, purpose) from primitive_noise.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "environment/table/physics.hpp"

namespace afford::table {

enum TableAction : int { kPush = 0, kCarry = 1, kTopple = 2, kRoll = 3 };
constexpr int kTableActions = 4;
const char* tableActionName(int action);
inline bool tableActionTakesPlace(int action) { return action == kPush || action == kCarry; }

void validate(const PrimitiveSpec& p);

struct PrimitiveResult {
  bool succeeded = false;
  int physics_steps = 0;           // steps the primitive took, its settling included
  bool settled = false;            // the scene came to rest before settle_bound_s
  double place_x = -1, place_y = -1;  // the place a push or carry aimed at (-1: none)
};

// Runs `action` of the hand on object `object` (its index), with `place` for push and carry, the noise
// drawn by (seed, step). The hand starts where it waits (its park, unless a primitive was cut short) and ends
// there, open.
PrimitiveResult runPrimitive(TablePhysics& physics, const PrimitiveSpec& spec, std::int64_t seed, std::int64_t step,
                             int action, int object, std::optional<std::pair<double, double>> place);

// Whether the object's centre is now lower than `from` (its height before the action) by `drop` of its resting
// height in its configured pose: it fell over.
bool toppled(const TablePhysics& physics, int object, double drop, double from);
// The yaw of an object about the vertical (for an object in its configured pose).
double objectYaw(const Pose& p);

}  // namespace afford::table

#include "environment/table/primitives.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "afford/rng.hpp"

namespace afford::table {

const char* tableActionName(int action) {
  switch (action) {
    case kPush: return "push";
    case kCarry: return "carry";
    case kTopple: return "topple";
    case kRoll: return "roll";
  }
  return "?";
}

void validate(const PrimitiveSpec& p) {
  auto need = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("table.primitives: ") + what);
  };
  need(p.travel_speed > 0 && p.contact_speed > 0 && p.tap_speed > 0, "every speed must be above 0");
  need(p.safe_height > 0 && p.clearance >= 0 && p.push_height >= 0 && p.carry_height > 0,
       "safe_height and carry_height must be above 0, clearance and push_height 0 or more");
  need(p.push_gap >= 0 && p.push_gap <= 1, "push_gap is a fraction of the object's width, in [0, 1]");
  need(p.grasp_height >= 0 && p.grasp_height <= 1, "grasp_height is a fraction of the object's height, in [0, 1]");
  need(p.topple_height >= 0 && p.topple_height <= 1, "topple_height is a fraction of the object's height, in [0, 1]");
  need(p.topple_drop > 0 && p.topple_drop < 1, "topple_drop must be in (0, 1)");
  need(p.tap_stroke > 0 && p.roll_distance > 0 && p.success_radius > 0 && p.reach_tolerance > 0,
       "tap_stroke, roll_distance, success_radius and reach_tolerance must be above 0");
  need(p.waypoint_bound_s > 0 && p.rest_speed > 0 && p.rest_hold_s >= 0 && p.settle_bound_s > 0,
       "waypoint_bound_s, rest_speed and settle_bound_s must be above 0, rest_hold_s 0 or more");
  need(p.noise_position >= 0 && p.noise_height >= 0 && p.noise_direction >= 0 && p.noise_yaw >= 0,
       "every noise must be 0 or more");
}

double objectYaw(const Pose& p) {
  const auto& q = p.quat;  // w, x, y, z
  return std::atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3]));
}

bool toppled(const TablePhysics& physics, int object, double drop, double from) {
  const ObjectSpec& o = physics.spec().objects.at(static_cast<std::size_t>(object));
  return physics.objectPose(object).pos[2] < from - drop * o.restingHeight();
}

namespace {

constexpr double kPi = 3.14159265358979323846;

// The primitive's noise: the i-th standard normal draw of its key (Box-Muller on two uniforms).
double normal(const KeyedRng& rng, std::uint64_t i) {
  const double u1 = 1 - rng.uniform(2 * i), u2 = rng.uniform(2 * i + 1);
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * kPi * u2);
}

// The gripper is the same turned by half a turn: a yaw within (-pi/2, pi/2].
double gripperYaw(double yaw) {
  while (yaw > kPi / 2) yaw -= kPi;
  while (yaw <= -kPi / 2) yaw += kPi;
  return yaw;
}

// How far the object reaches from its centre along the horizontal direction theta.
double reachAlong(const ObjectSpec& o, const Pose& pose, double theta) {
  const double rel = theta - objectYaw(pose);
  const double c = std::abs(std::cos(rel)), s = std::abs(std::sin(rel));
  switch (o.shape) {
    case Shape::Box: return o.size[0] * c + o.size[1] * s;
    case Shape::Cylinder: return o.lying ? o.size[1] * c + o.size[0] * s : o.size[0];
    case Shape::Sphere: return o.size[0];
  }
  return o.footprintRadius();
}

// The hand's set-point, moved toward each target at a speed, and the physics stepped meanwhile.
class Mover {
 public:
  Mover(TablePhysics& physics, const PrimitiveSpec& spec) : physics_(physics), spec_(spec), at_(physics.handNow()) {
    at_.opening = 1;
  }
  int steps() const { return steps_; }
  const HandCommand& at() const { return at_; }

  // The palm's centre height that puts the fingers' tips at `tip` above the table.
  double palmFor(double tip) const {
    const HandSpec& h = physics_.spec().hand;
    return tip + h.palm_half[2] + 2 * h.finger_half[2];
  }

  void go(HandCommand to, double speed) {
    const double dt = physics_.model()->opt.timestep;
    const int bound = static_cast<int>(std::ceil(spec_.waypoint_bound_s / dt));
    to.yaw = gripperYaw(to.yaw);
    for (int i = 0; i < bound; ++i) {
      const double dx = to.x - at_.x, dy = to.y - at_.y, dz = to.z - at_.z;
      const double left = std::sqrt(dx * dx + dy * dy + dz * dz), stride = speed * dt;
      if (left <= stride) {
        at_.x = to.x, at_.y = to.y, at_.z = to.z;
      } else {
        at_.x += dx * stride / left, at_.y += dy * stride / left, at_.z += dz * stride / left;
      }
      at_.yaw += std::clamp(to.yaw - at_.yaw, -kYawRate * dt, kYawRate * dt);
      at_.opening += std::clamp(to.opening - at_.opening, -kOpeningRate * dt, kOpeningRate * dt);
      physics_.commandHand(at_);
      physics_.step();
      ++steps_;
      if (left <= stride && at_.yaw == to.yaw && at_.opening == to.opening) {
        const HandCommand now = physics_.handNow();
        if (std::hypot(now.x - to.x, now.y - to.y, now.z - to.z) <= spec_.reach_tolerance) return;
      }
    }
  }
  // Over (x, y) at the safe height, down to 2 cm above `tip` at travel speed, the rest at contact speed.
  void approach(double x, double y, double yaw, double opening, double tip) {
    go({x, y, palmFor(spec_.safe_height), yaw, opening}, spec_.travel_speed);
    go({x, y, palmFor(tip + 0.02), yaw, opening}, spec_.travel_speed);
    go({x, y, palmFor(tip), yaw, opening}, spec_.contact_speed);
  }
  // Straight up to the safe height.
  void leave() { go({at_.x, at_.y, palmFor(spec_.safe_height), at_.yaw, at_.opening}, spec_.travel_speed); }
  // The fingers close or open where the hand is, for `seconds`.
  void grip(double opening, double seconds) {
    HandCommand to = at_;
    to.opening = opening;
    go(to, spec_.contact_speed);
    hold(seconds);
  }
  void hold(double seconds) {
    const int n = static_cast<int>(std::ceil(seconds / physics_.model()->opt.timestep));
    physics_.step(n);
    steps_ += n;
  }
  // Until every body is at rest for rest_hold_s, at most settle_bound_s; true when it came to rest.
  bool settle() {
    const double dt = physics_.model()->opt.timestep;
    const int bound = static_cast<int>(std::ceil(spec_.settle_bound_s / dt));
    const int hold = static_cast<int>(std::ceil(spec_.rest_hold_s / dt));
    int still = 0;
    for (int i = 0; i < bound; ++i) {
      physics_.step();
      ++steps_;
      still = physics_.atRest(spec_.rest_speed, 10 * spec_.rest_speed) ? still + 1 : 0;
      if (still > hold) return true;
    }
    return false;
  }

 private:
  static constexpr double kYawRate = 4.0;      // rad/s
  static constexpr double kOpeningRate = 4.0;  // of the whole opening, per second
  TablePhysics& physics_;
  const PrimitiveSpec& spec_;
  HandCommand at_;
  int steps_ = 0;
};

// A sweep of the fingers along direction theta, their tips at `tip`, from behind the object to `end` (the
// distance of the fingers' front past the object's centre), at `speed`. The palm's x axis along theta, the
// fingers spread across it: closed (`gap` 0) they are one narrow pusher; open to `gap`, a fork that touches the
// object's back at two points.
void sweep(Mover& m, const PrimitiveSpec& spec, const HandSpec& hand, double ox, double oy, double theta, double reach,
           double tip, double end, double speed, double gap = 0) {
  const double cx = std::cos(theta), cy = std::sin(theta);
  const double yaw = theta;
  const double opening = std::clamp(gap / (2 * (hand.finger_travel - hand.finger_half[1])), 0.0, 1.0);
  const double depth = hand.finger_half[0];            // the fingers' half-depth along theta
  const double back = reach + depth + spec.clearance;  // the fingers' centre behind the object
  m.approach(ox - cx * back, oy - cy * back, yaw, opening, tip);
  const double front = end - depth;
  m.go({ox + cx * front, oy + cy * front, m.palmFor(tip), yaw, opening}, speed);
  m.leave();
}

}  // namespace

PrimitiveResult runPrimitive(TablePhysics& physics, const PrimitiveSpec& spec, std::int64_t seed, std::int64_t step,
                             int action, int object, std::optional<std::pair<double, double>> place) {
  if (action < 0 || action >= kTableActions) throw std::invalid_argument("no table action " + std::to_string(action));
  if (object < 0 || object >= physics.objectCount()) throw std::invalid_argument("no object " + std::to_string(object));
  if (tableActionTakesPlace(action) && !place)
    throw std::invalid_argument(std::string(tableActionName(action)) + " needs a place");
  const ObjectSpec& o = physics.spec().objects[static_cast<std::size_t>(object)];
  const HandSpec& hand = physics.spec().hand;
  const KeyedRng rng(seed, step, Purpose::PrimitiveNoise, static_cast<std::uint64_t>(action));
  const Pose start = physics.objectPose(object);
  const double ox = start.pos[0] + spec.noise_position * normal(rng, 0);
  const double oy = start.pos[1] + spec.noise_position * normal(rng, 1);
  const double height = 2 * o.restingHeight();
  PrimitiveResult r;
  Mover m(physics, spec);
  switch (action) {
    case kPush: {
      r.place_x = place->first, r.place_y = place->second;
      const double theta =
          std::atan2(place->second - start.pos[1], place->first - start.pos[0]) + spec.noise_direction * normal(rng, 3);
      const double distance = std::hypot(place->first - start.pos[0], place->second - start.pos[1]);
      const double reach = reachAlong(o, start, theta);
      const double tip = std::max(0.002, spec.push_height + spec.noise_height * normal(rng, 2));
      // A fork whose tines are push_gap of the object's width apart; its front stops where the object's centre
      // would be at the place.
      const double width = 2 * reachAlong(o, start, theta + kPi / 2);
      sweep(m, spec, hand, ox, oy, theta, reach, tip, distance - reach, spec.contact_speed, spec.push_gap * width);
      break;
    }
    case kCarry: {
      r.place_x = place->first, r.place_y = place->second;
      // The fingers close across the object's narrower side (a lying cylinder: across its axis).
      const double yaw = objectYaw(start);
      double grasp_yaw = yaw;
      if (o.shape == Shape::Box && o.size[0] <= o.size[1]) grasp_yaw = yaw - kPi / 2;
      if (o.shape == Shape::Sphere || (o.shape == Shape::Cylinder && !o.lying)) grasp_yaw = 0;
      grasp_yaw += spec.noise_yaw * normal(rng, 4);
      const double tip = std::max(0.002, spec.grasp_height * height);
      m.approach(ox, oy, grasp_yaw, 1, tip);
      m.grip(0, 0.3);
      const double lifted = m.palmFor(std::max(spec.carry_height, tip + 0.01));
      m.go({ox, oy, lifted, grasp_yaw, 0}, spec.contact_speed);
      const double tx = place->first + (ox - start.pos[0]), ty = place->second + (oy - start.pos[1]);
      m.go({tx, ty, lifted, grasp_yaw, 0}, spec.travel_speed);
      m.go({tx, ty, m.palmFor(tip + 0.003), grasp_yaw, 0}, spec.contact_speed);
      m.grip(1, 0.2);
      m.leave();
      break;
    }
    case kTopple:
    case kRoll: {
      const double theta = 2 * kPi * rng.uniform(10) + spec.noise_direction * normal(rng, 3);
      const double reach = reachAlong(o, start, theta);
      if (action == kTopple) {
        const double tip = std::max(0.002, spec.topple_height * height + spec.noise_height * normal(rng, 2));
        sweep(m, spec, hand, ox, oy, theta, reach, tip, reach + spec.tap_stroke, spec.contact_speed);
      } else {
        const double tip = std::max(0.002, spec.push_height + spec.noise_height * normal(rng, 2));
        sweep(m, spec, hand, ox, oy, theta, reach, tip, -reach + spec.tap_stroke, spec.tap_speed);
      }
      break;
    }
  }
  r.settled = m.settle();  // the hand waits where it left, at the safe height (the camera does not draw it)
  r.physics_steps = m.steps();
  const Pose end = physics.objectPose(object);
  switch (action) {
    case kPush:
    case kCarry:
      r.succeeded = std::hypot(end.pos[0] - place->first, end.pos[1] - place->second) <= spec.success_radius &&
                    !toppled(physics, object, spec.topple_drop, start.pos[2]);
      break;
    case kTopple:  // from the height it had: an object lying already does not topple again
      r.succeeded = toppled(physics, object, spec.topple_drop, start.pos[2]);
      break;
    case kRoll:
      r.succeeded = std::hypot(end.pos[0] - start.pos[0], end.pos[1] - start.pos[1]) >= spec.roll_distance;
      break;
  }
  return r;
}

}  // namespace afford::table

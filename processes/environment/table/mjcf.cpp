#include <algorithm>
#include <cmath>
#include <iomanip>
#include <set>
#include <sstream>
#include <stdexcept>

#include "environment/table/table_spec.hpp"

namespace afford::table {

const char* shapeName(Shape s) {
  switch (s) {
    case Shape::Box: return "box";
    case Shape::Cylinder: return "cylinder";
    case Shape::Sphere: return "sphere";
  }
  return "?";
}

namespace {

void need(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

std::size_t sizeCount(Shape s) { return s == Shape::Box ? 3 : s == Shape::Cylinder ? 2 : 1; }

std::string rgba(const std::array<double, 3>& c) {
  std::ostringstream o;
  o << c[0] << ' ' << c[1] << ' ' << c[2] << " 1";
  return o.str();
}

void checkColour(const std::array<double, 3>& c, const std::string& where) {
  for (double v : c) need(v >= 0 && v <= 1, where + ": each of its three values must be in [0, 1]");
}

}  // namespace

void validate(const TableSpec& t) {
  need(t.half_x > 0 && t.half_y > 0, "table: half_x and half_y must be above 0");
  need(t.friction > 0, "table: friction must be above 0");
  need(t.rim_height > 0, "table: rim_height must be above 0");
  checkColour(t.rgb, "table.rgb");
  need(t.timestep > 0 && t.timestep <= 0.01, "table: timestep must be in (0, 0.01] s");
  need(t.camera.width >= 16 && t.camera.height >= 16 && t.camera.width <= 4096 && t.camera.height <= 4096,
       "table.camera: width and height must be in [16, 4096] pixels");
  need(t.camera.above > 0, "table.camera: above must be above 0");
  need(t.camera.fovy_deg > 0 && t.camera.fovy_deg < 180, "table.camera: fovy_deg must be in (0, 180)");
  const HandSpec& h = t.hand;
  for (int i = 0; i < 3; ++i) {
    need(h.palm_half[i] > 0, "table.hand: each palm half-extent must be above 0");
    need(h.finger_half[i] > 0, "table.hand: each finger half-extent must be above 0");
  }
  need(h.finger_travel > h.finger_half[1], "table.hand: finger_travel must exceed a finger's half-width");
  need(h.mass > 0 && h.friction > 0, "table.hand: mass and friction must be above 0");
  need(h.kp_move > 0 && h.kp_yaw > 0 && h.kp_finger > 0, "table.hand: every gain (kp_*) must be above 0");
  need(h.time_constant > 0 && h.time_constant <= 10, "table.hand: time_constant must be in (0, 10] s");
  need(h.rest_height > h.palm_half[2] + 2 * h.finger_half[2], "table.hand: rest_height must hold the hand above the table");
  need(h.reach_x > 0 && h.reach_y > 0, "table.hand: reach_x and reach_y must be above 0");
  need(std::abs(h.park[0]) <= h.reach_x && std::abs(h.park[1]) <= h.reach_y && h.park[2] > 0 &&
           h.park[2] <= 2 * h.rest_height,
       "table.hand: park must be within the hand's reach (reach_x, reach_y, up to twice rest_height)");
  checkColour(h.rgb, "table.hand.rgb");
  need(!t.objects.empty(), "table.objects: at least one object");
  std::set<std::string> names;
  for (std::size_t i = 0; i < t.objects.size(); ++i) {
    const ObjectSpec& o = t.objects[i];
    const std::string at = "table.objects[" + std::to_string(i) + "]" + (o.name.empty() ? "" : " ('" + o.name + "')");
    need(!o.name.empty(), at + ": name is missing");
    need(o.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_-") == std::string::npos,
         at + ": name may hold lower-case letters, digits, '_' and '-' only");
    need(o.name.rfind("hand", 0) != 0 && o.name != "table",
         at + ": name may not be 'table' or begin with 'hand' (the world's own parts)");
    need(names.insert(o.name).second, at + ": name is used by an earlier object");
    need(o.size.size() == sizeCount(o.shape), at + ": a " + std::string(shapeName(o.shape)) + " takes " +
                                                   std::to_string(sizeCount(o.shape)) + " size values, not " +
                                                   std::to_string(o.size.size()));
    for (double v : o.size) need(v > 0 && v <= 0.5, at + ": each size value must be in (0, 0.5] m");
    need(!o.lying || o.shape == Shape::Cylinder, at + ": only a cylinder can be lying");
    need(o.mass > 0, at + ": mass must be above 0");
    need(o.friction > 0, at + ": friction must be above 0");
    need(o.torsional_friction >= 0 && o.rolling_friction >= 0, at + ": torsional and rolling friction must be 0 or more");
    checkColour(o.rgb, at + ".rgb");
  }
}

std::string tableMjcf(const TableSpec& t) {
  validate(t);
  const HandSpec& h = t.hand;
  std::ostringstream x;
  x << std::setprecision(17);
  x << "<mujoco model=\"afford-table\">\n"
    << "  <compiler angle=\"radian\" autolimits=\"true\"/>\n"
    << "  <option timestep=\"" << t.timestep << "\" gravity=\"0 0 -9.81\" cone=\"elliptic\" jacobian=\"sparse\"/>\n"
    << "  <visual>\n"
    << "    <global offwidth=\"" << t.camera.width << "\" offheight=\"" << t.camera.height << "\"/>\n"
    << "    <quality shadowsize=\"0\"/>\n"
    // The agent's camera sees flat colours, as the paper's eye sees its shapes: one ambient light, no diffuse or
    // specular part (a black top is drawn black, the eye's background), so every pixel of an object is its colour
    // and objects of equal RGB mean are equally salient to the paper's brightness saliency, whatever their shape.
    // (A person's view shades them: table/camera.hpp.)
    << "    <headlight ambient=\"0 0 0\" diffuse=\"0 0 0\" specular=\"0 0 0\"/>\n"
    << "  </visual>\n"
    << "  <worldbody>\n"
    << "    <light name=\"top\" pos=\"0 0 " << 2 * t.camera.above << "\" dir=\"0 0 -1\" directional=\"true\""
    << " castshadow=\"false\" diffuse=\"0 0 0\" ambient=\"1 1 1\" specular=\"0 0 0\"/>\n"
    // The table's top: a plane (analytic contacts with every shape), drawn as far as its rim.
    << "    <geom name=\"table\" type=\"plane\" size=\"" << t.half_x << ' ' << t.half_y << " 0.05\" friction=\""
    << t.friction << " 0.005 0.0001\" rgba=\"" << rgba(t.rgb) << "\"/>\n";
  // The rim: four walls just outside the top's edges.
  const double wall = 0.005;
  for (int side : {-1, 1}) {
    x << "    <geom name=\"table_rim_x" << (side > 0 ? "+" : "-") << "\" type=\"box\" pos=\"" << side * (t.half_x + wall)
      << " 0 " << t.rim_height / 2 << "\" size=\"" << wall << ' ' << t.half_y + 2 * wall << ' ' << t.rim_height / 2
      << "\" friction=\"" << t.friction << " 0.005 0.0001\" rgba=\"" << rgba(t.rgb) << "\"/>\n";
    x << "    <geom name=\"table_rim_y" << (side > 0 ? "+" : "-") << "\" type=\"box\" pos=\"0 " << side * (t.half_y + wall)
      << ' ' << t.rim_height / 2 << "\" size=\"" << t.half_x << ' ' << wall << ' ' << t.rim_height / 2
      << "\" friction=\"" << t.friction << " 0.005 0.0001\" rgba=\"" << rgba(t.rgb) << "\"/>\n";
  }
  // Straight down; the image's columns run along the table's y (right = -y), its rows along x (up = +x).
  x << "    <camera name=\"top\" pos=\"0 0 " << t.camera.above << "\" xyaxes=\"0 -1 0 1 0 0\" fovy=\""
    << t.camera.fovy_deg << "\"/>\n";
  const double n = static_cast<double>(t.objects.size());
  for (std::size_t i = 0; i < t.objects.size(); ++i) {
    const ObjectSpec& o = t.objects[i];
    // Until the world places them, the objects wait in a row along the table's y axis.
    const double y = -t.half_y + (static_cast<double>(i) + 0.5) * 2 * t.half_y / n;
    x << "    <body name=\"" << o.name << "\" pos=\"0 " << y << ' ' << o.restingHeight() << "\">\n"
      << "      <freejoint name=\"" << o.name << "\"/>\n"
      << "      <geom name=\"" << o.name << "\" type=\"" << shapeName(o.shape) << "\" size=\"";
    for (std::size_t k = 0; k < o.size.size(); ++k) x << (k ? " " : "") << o.size[k];
    x << "\"";
    if (o.lying) x << " quat=\"0.70710678118654757 0 0.70710678118654757 0\"";  // the axis along x
    x << " mass=\"" << o.mass << "\" friction=\"" << o.friction << ' ' << o.torsional_friction << ' '
      << o.rolling_friction << "\" condim=\"" << (o.rolling_friction > 0 ? 6 : 4) << "\" rgba=\"" << rgba(o.rgb)
      << "\"/>\n"
      << "    </body>\n";
  }
  // The hand: a palm on a gantry (x, y, z slides and a yaw hinge) with two fingers that slide apart along
  // the palm's y; every joint moved by a position actuator.
  const double finger_z = -h.palm_half[2] - h.finger_half[2];
  x << "    <body name=\"hand\" pos=\"0 0 " << h.rest_height << "\">\n"
    << "      <joint name=\"hand_x\" type=\"slide\" axis=\"1 0 0\" range=\"" << -h.reach_x << ' ' << h.reach_x
    << "\" damping=\"" << h.kp_move * h.time_constant << "\"/>\n"
    << "      <joint name=\"hand_y\" type=\"slide\" axis=\"0 1 0\" range=\"" << -h.reach_y << ' ' << h.reach_y
    << "\" damping=\"" << h.kp_move * h.time_constant << "\"/>\n"
    // Down until the fingers' tips are 2 mm above the table; up as far again as the hand waits.
    << "      <joint name=\"hand_z\" type=\"slide\" axis=\"0 0 1\" range=\""
    << -(h.rest_height - h.palm_half[2] - 2 * h.finger_half[2] - 0.002) << ' ' << h.rest_height << "\" damping=\"" << h.kp_move * h.time_constant << "\"/>\n"
    << "      <joint name=\"hand_yaw\" type=\"hinge\" axis=\"0 0 1\" range=\"-3.1415926535897931 3.1415926535897931\""
    << " damping=\"" << h.kp_yaw * h.time_constant << "\"/>\n"
    << "      <geom name=\"hand_palm\" type=\"box\" size=\"" << h.palm_half[0] << ' ' << h.palm_half[1] << ' '
    << h.palm_half[2] << "\" mass=\"" << h.mass << "\" group=\"" << kHandGroup << "\" rgba=\"" << rgba(h.rgb) << "\"/>\n";
  for (int side : {1, -1}) {
    const char* name = side > 0 ? "hand_finger_l" : "hand_finger_r";
    x << "      <body name=\"" << name << "\" pos=\"0 " << side * h.finger_travel << ' ' << finger_z << "\">\n"
      << "        <joint name=\"" << name << "\" type=\"slide\" axis=\"0 " << side << " 0\" range=\""
      << -(h.finger_travel - h.finger_half[1]) << " 0\" damping=\"" << h.kp_finger * h.time_constant << "\"/>\n"
      << "        <geom name=\"" << name << "\" type=\"box\" size=\"" << h.finger_half[0] << ' ' << h.finger_half[1]
      << ' ' << h.finger_half[2] << "\" mass=\"" << h.mass / 4 << "\" friction=\"" << h.friction
      << " 0.005 0.0001\" condim=\"4\" group=\"" << kHandGroup << "\" rgba=\"" << rgba(h.rgb) << "\"/>\n"
      << "      </body>\n";
  }
  x << "    </body>\n"
    << "  </worldbody>\n"
    << "  <actuator>\n";
  for (const char* j : {"hand_x", "hand_y"})
    x << "    <position name=\"" << j << "\" joint=\"" << j << "\" kp=\"" << h.kp_move << "\"/>\n";
  // The z slide's position control carries the hand's weight (palm and fingers) as a constant force, so that
  // the empty hand holds its height; what it grasps weighs on it.
  x << "    <general name=\"hand_z\" joint=\"hand_z\" gainprm=\"" << h.kp_move << "\" biastype=\"affine\" biasprm=\""
    << 1.5 * h.mass * 9.81 << ' ' << -h.kp_move << " 0\"/>\n";
  x << "    <position name=\"hand_yaw\" joint=\"hand_yaw\" kp=\"" << h.kp_yaw << "\"/>\n";
  for (const char* j : {"hand_finger_l", "hand_finger_r"})
    x << "    <position name=\"" << j << "\" joint=\"" << j << "\" kp=\"" << h.kp_finger << "\"/>\n";
  x << "  </actuator>\n"
    // Closed, the fingers meet at their joints' limits; they do not push each other.
    << "  <contact>\n"
    << "    <exclude body1=\"hand_finger_l\" body2=\"hand_finger_r\"/>\n"
    << "  </contact>\n"
    << "</mujoco>\n";
  return x.str();
}

}  // namespace afford::table

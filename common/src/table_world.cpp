// The table world's geometry that needs no simulation: the camera's pinhole and the objects' footprints
// (afford/table_world.hpp). The environment's camera and the scenarios' checks share it.
#include "afford/table_world.hpp"

#include <cmath>

namespace afford::table {

double ObjectSpec::restingHeight() const {
  switch (shape) {
    case Shape::Box: return size.at(2);
    case Shape::Cylinder: return lying ? size.at(0) : size.at(1);
    case Shape::Sphere: return size.at(0);
  }
  return 0;
}

double ObjectSpec::footprintRadius() const {
  switch (shape) {
    case Shape::Box: return std::hypot(size.at(0), size.at(1));
    case Shape::Cylinder: return lying ? std::hypot(size.at(0), size.at(1)) : size.at(0);
    case Shape::Sphere: return size.at(0);
  }
  return 0;
}

double CameraSpec::focalPx() const { return 0.5 * height / std::tan(fovy_deg * M_PI / 360); }

// The camera looks straight down from `above` with the image's up along the table's +x: a column is -y, a
// row is -x.
std::array<double, 2> CameraSpec::pixelOf(double x, double y, double z) const {
  const double depth = above - z;
  return {0.5 * width - focalPx() * y / depth, 0.5 * height - focalPx() * x / depth};
}

std::array<double, 2> CameraSpec::sceneOf(double x, double y, double z) const {
  const auto [u, v] = pixelOf(x, y, z);
  return {(u - 0.5) / width, (v - 0.5) / width};
}

std::array<double, 2> CameraSpec::tableAtPixel(double u, double v) const {
  return {(0.5 * height - v) * above / focalPx(), -(u - 0.5 * width) * above / focalPx()};
}

std::array<double, 2> CameraSpec::tableAt(double sx, double sy) const {
  return tableAtPixel(sx * width + 0.5, sy * width + 0.5);
}

}  // namespace afford::table

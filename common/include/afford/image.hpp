// Scene images (paper 2.2): size x size RGB, 8 bits per channel, values 0 or
// 255, black background. A position in scene units maps to a pixel index by
// round(u * size); a pixel index maps back by index / size.
#pragma once
#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "afford/config.hpp"

namespace afford {

struct Pixel {
  int col = 0, row = 0;
  bool operator==(const Pixel& o) const { return col == o.col && row == o.row; }
};

int toPixel(double u, int size_px);
double toUnit(int px, int size_px);
Pixel toPixel(double x, double y, int size_px);

// Round half away from zero, after clearing floating-point noise below 1e-9
// (150 x 0.1 is 15.000000000000002: a square's corners must not depend on it).
int roundHalfAway(double v);

// Pixel offsets covered by a shape centred on a pixel, the pixel world's
// footprint (docs/parameters.md: square 15 x 15 = 225 px; circle of radius
// 0.1/sqrt(pi) = 221 px; rectangle 10 wide by 22 tall = 220 px). The bounding
// box of every shape has its centre at offset (0, 0) with the rule
// centre = min + extent / 2.
std::vector<Pixel> shapeFootprint(Shape shape, const WorldConfig& world);

// The pixels a shape covers with its centre at (x, y), scene units (world.positions):
//  continuous: squares and rectangles fill the pixels between their corners,
//    each corner rounded half away from zero in pixel indices (x * size_px);
//    a circle covers the pixels whose index distance from the centre is below
//    its radius. Squares always look the same, rectangles (22.5 px tall) have
//    two phases, circles many.
//  pixel: shapeFootprint around the nearest pixel.
// Pixels outside the scene are included; painting clips them.
std::vector<Pixel> shapePixels(Shape shape, double x, double y, const WorldConfig& world);

// The first column and row of the side x side window around (x, y), scene
// units: round half away from zero of size_px x (centre - side / (2 size_px)).
// For a centre on a pixel it is centre - side / 2, the window cropFocus takes.
Pixel windowCorner(double x, double y, int side, int size_px);

// A blank (black) scene.
cv::Mat blankScene(int size_px);
// Paint pixels in a colour (clipped at the borders).
void paintPixels(cv::Mat& scene, const std::vector<Pixel>& pixels, Colour colour);
// Paint a shape of a colour centred at (x, y), scene units (shapePixels).
void paintObject(cv::Mat& scene, Shape shape, Colour colour, double x, double y, const WorldConfig& world);

// The scene of a scenario's initial or goal configuration.
cv::Mat renderScenario(const Scenario& s, bool goal, const WorldConfig& world);
// Goal and initial scenes side by side, enlarged, labelled, as BGR for imwrite.
cv::Mat scenarioPicture(const Scenario& s, const WorldConfig& world);

// The same size, type and pixels.
bool sameImage(const cv::Mat& a, const cv::Mat& b);

// Lossless scene transport: zlib of the raw RGB bytes (as Drake's lcmt_image).
std::vector<std::uint8_t> encodeScene(const cv::Mat& scene);
// Throws std::runtime_error naming the problem when the data does not decode to size x size x 3.
cv::Mat decodeScene(const std::vector<std::uint8_t>& data, int width, int height);

// The side x side x 3 window centred on a pixel, row-major RGB bytes; outside the scene is black.
std::vector<std::uint8_t> cropFocus(const cv::Mat& scene, Pixel centre, int side);

// L1(a - b) / n over bytes scaled to [0, 1]: the paper's image change measure.
double imageChange(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b);
// A place where the goal image and the scene differ (top-down attention,
// issue 12): what the eye finds and the planner remembers.
struct Difference {
  double x = 0, y = 0;              // the blob's place, scene units
  bool in_goal = false;             // a goal blob (a sub-goal) or a scene blob (an object to act on)
  std::vector<std::uint8_t> image;  // the window there on the image that shows the blob
};

// ||a - b||_2 / n for images in [0, 1] (bytes are value / 255): the planner's
// image distance (paper 2.4.3); 1 for images of different sizes.
double imageDistance(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b);
// The share of pixels on which two focus images disagree about an object
// being there (any channel above 0): 0 for the same silhouette.
// The byte image a predicted focus image (values in [0, 1]) stands for: round(clamp(v, 0, 1) * 255).
std::vector<std::uint8_t> quantiseImage(const std::vector<double>& what);
double silhouetteDistance(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b);

}  // namespace afford

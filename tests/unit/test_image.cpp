#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include <zlib.h>

#include "afford/image.hpp"
#include "afford/seal.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

// The shipped world, read once per test (the tests below draw shapes in thousands of places).
const WorldConfig& world() {
  static const WorldConfig w = test::shippedConfig().world;
  return w;
}
const WorldConfig& continuousWorld() {
  static const WorldConfig w = [] {
    WorldConfig c = world();
    c.positions = Positions::Continuous;
    return c;
  }();
  return w;
}

TEST(Image, ShapesCoverThePixelCountsOfTheAuthorsCode) {
  EXPECT_EQ(shapeFootprint(Shape::Square, world()).size(), 225u);
  EXPECT_EQ(shapeFootprint(Shape::Circle, world()).size(), 221u);
  EXPECT_EQ(shapeFootprint(Shape::Rectangle, world()).size(), 220u);
}

TEST(Image, EveryShapeHasItsBoundingBoxCentredOnTheCentrePixel) {
  for (Shape s : {Shape::Square, Shape::Circle, Shape::Rectangle}) {
    const auto fp = shapeFootprint(s, world());
    int c0 = 1000, c1 = -1000, r0 = 1000, r1 = -1000;
    for (const Pixel& p : fp) {
      c0 = std::min(c0, p.col), c1 = std::max(c1, p.col), r0 = std::min(r0, p.row), r1 = std::max(r1, p.row);
    }
    EXPECT_EQ(c0 + (c1 - c0 + 1) / 2, 0) << toString(s);
    EXPECT_EQ(r0 + (r1 - r0 + 1) / 2, 0) << toString(s);
  }
}

TEST(Image, RectangleIsTenWideAndTwentyTwoTall) {
  const auto fp = shapeFootprint(Shape::Rectangle, world());
  auto [cmin, cmax] = std::minmax_element(fp.begin(), fp.end(), [](auto a, auto b) { return a.col < b.col; });
  auto [rmin, rmax] = std::minmax_element(fp.begin(), fp.end(), [](auto a, auto b) { return a.row < b.row; });
  EXPECT_EQ(cmax->col - cmin->col + 1, 10);
  EXPECT_EQ(rmax->row - rmin->row + 1, 22);
}

// The continuous world (world.positions: continuous, the default): shapes
// rasterised from real-valued centres as the authors' code does.
std::vector<std::pair<double, double>> randomPlaces(int n) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.2, 0.8);
  std::vector<std::pair<double, double>> out;
  for (int i = 0; i < n; ++i) out.emplace_back(u(rng), u(rng));
  return out;
}
std::pair<int, int> extent(const std::vector<Pixel>& px) {
  auto [cmin, cmax] = std::minmax_element(px.begin(), px.end(), [](auto a, auto b) { return a.col < b.col; });
  auto [rmin, rmax] = std::minmax_element(px.begin(), px.end(), [](auto a, auto b) { return a.row < b.row; });
  return {cmax->col - cmin->col + 1, rmax->row - rmin->row + 1};
}
// The pattern of a shape's pixels relative to its first pixel.
std::vector<Pixel> pattern(std::vector<Pixel> px) {
  std::sort(px.begin(), px.end(), [](auto a, auto b) { return std::tie(a.row, a.col) < std::tie(b.row, b.col); });
  const Pixel o = px.front();
  for (Pixel& p : px) p = {p.col - o.col, p.row - o.row};
  return px;
}

TEST(Image, ContinuousSquaresLookTheSameEverywhere) {
  std::set<std::vector<std::pair<int, int>>> seen;
  for (auto [x, y] : randomPlaces(3000)) {
    const auto px = shapePixels(Shape::Square, x, y, continuousWorld());
    ASSERT_EQ(px.size(), 225u) << x << ", " << y;
    ASSERT_EQ(extent(px), std::make_pair(15, 15));
  }
}

TEST(Image, ContinuousRectanglesHaveTwoPhases) {
  std::set<int> heights;
  for (auto [x, y] : randomPlaces(3000)) {
    const auto px = shapePixels(Shape::Rectangle, x, y, continuousWorld());
    const auto [w, h] = extent(px);
    ASSERT_EQ(w, 10);
    ASSERT_EQ(px.size(), static_cast<std::size_t>(w * h));
    heights.insert(h);
  }
  EXPECT_EQ(heights, (std::set<int>{22, 23}));  // 0.15 x 150 = 22.5 pixels between rounded corners
}

TEST(Image, ContinuousCirclesTakeManyPatterns) {
  std::set<std::vector<std::pair<int, int>>> patterns;
  for (auto [x, y] : randomPlaces(3000)) {
    std::vector<std::pair<int, int>> key;
    for (const Pixel& p : pattern(shapePixels(Shape::Circle, x, y, continuousWorld()))) key.emplace_back(p.col, p.row);
    patterns.insert(key);
  }
  EXPECT_GT(patterns.size(), 100u);  // the authors' code: 575 over 3000 random places
}

// The eye centres its gaze on a blob's bounding box (left + width / 2): in the
// continuous world that must land within a pixel of the real centre, inside
// the planner's position match of 0.01 units (1.5 px).
TEST(Image, ContinuousShapesHaveTheirBoundingBoxWithinAPixelOfTheRealCentre) {
  for (Shape s : {Shape::Square, Shape::Circle, Shape::Rectangle})
    for (auto [x, y] : randomPlaces(1000)) {
      int c0 = 1000, c1 = -1000, r0 = 1000, r1 = -1000;
      for (const Pixel& p : shapePixels(s, x, y, continuousWorld())) {
        c0 = std::min(c0, p.col), c1 = std::max(c1, p.col), r0 = std::min(r0, p.row), r1 = std::max(r1, p.row);
      }
      EXPECT_LE(std::abs(c0 + (c1 - c0 + 1) / 2 - x * 150), 1.0) << toString(s) << " at " << x << "," << y;
      EXPECT_LE(std::abs(r0 + (r1 - r0 + 1) / 2 - y * 150), 1.0) << toString(s) << " at " << x << "," << y;
    }
}

TEST(Image, ACircleCoversThePixelsWithinItsRadiusOfTheRealCentre) {
  const WorldConfig w = continuousWorld();
  const double x = 0.4137, y = 0.6021, r = w.object_size / std::sqrt(M_PI) * w.size_px;
  const auto px = shapePixels(Shape::Circle, x, y, w);
  std::set<std::pair<int, int>> in;
  for (const Pixel& p : px) in.insert({p.col, p.row});
  for (int row = 70; row < 112; ++row)
    for (int col = 40; col < 84; ++col) {
      const double d = std::hypot(col - x * w.size_px, row - y * w.size_px);
      EXPECT_EQ(in.count({col, row}) == 1, d < r) << col << ", " << row;
    }
}

TEST(Image, TheFocusWindowOfAPixelCentreIsTheOneCropFocusTakes) {
  for (int c : {11, 30, 75, 121})  // centres in the scene's inner part (the table is [30, 120] px)
    EXPECT_EQ(windowCorner(toUnit(c, 150), toUnit(c + 3, 150), 21, 150), (Pixel{c - 10, c + 3 - 10}));
  EXPECT_EQ(windowCorner(74.6 / 150, 75.6 / 150, 21, 150), (Pixel{64, 65}));  // 64.1 and 65.1
}

TEST(Image, ThePixelWorldDrawsTheFootprintAroundTheNearestPixel) {
  WorldConfig w = world();
  w.positions = Positions::Pixel;
  for (Shape s : {Shape::Square, Shape::Circle, Shape::Rectangle}) {
    const auto px = shapePixels(s, 0.3012, 0.4, w);
    const auto fp = shapeFootprint(s, w);
    ASSERT_EQ(px.size(), fp.size());
    for (std::size_t i = 0; i < fp.size(); ++i) EXPECT_EQ(px[i], (Pixel{45 + fp[i].col, 60 + fp[i].row}));
  }
}

TEST(Image, PaintedObjectIsPureColourOnBlack) {
  cv::Mat scene = blankScene(150);
  paintObject(scene, Shape::Square, Colour::Green, 0.2, 0.5, world());
  EXPECT_EQ(scene.at<cv::Vec3b>(75, 30), cv::Vec3b(0, 255, 0));
  EXPECT_EQ(scene.at<cv::Vec3b>(75, 37), cv::Vec3b(0, 255, 0));
  EXPECT_EQ(scene.at<cv::Vec3b>(75, 38), cv::Vec3b(0, 0, 0));
}

TEST(Image, SceneEncodingIsLossless) {
  cv::Mat scene = blankScene(150);
  paintObject(scene, Shape::Circle, Colour::Blue, 0.5, 0.5, world());
  const auto bytes = encodeScene(scene);
  EXPECT_LT(bytes.size(), 2000u);  // 67.5 KB raw
  const cv::Mat back = decodeScene(bytes, 150, 150);
  EXPECT_EQ(cv::norm(scene, back, cv::NORM_L1), 0.0);
}

// The bytes of a scene message (and so of every log) are those zlib's
// compress2 at its fastest level writes, whatever scenes came before on the
// thread (the encoder keeps one deflate state per thread and resets it).
TEST(Image, SceneEncodingIsCompress2sOutputByteForByte) {
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> where(0.2, 0.8);
  for (int k = 0; k < 7; ++k) {
    cv::Mat scene = blankScene(150);
    if (k == 6) scene.setTo(cv::Scalar(255, 1, 128));  // no zeros (the Adler-32 takes words of zeros at once)
    for (int o = 0; o <= k; ++o)
      paintObject(scene, static_cast<Shape>(o % 3), static_cast<Colour>(o % 3), where(gen), where(gen), world());
    const uLong raw = static_cast<uLong>(scene.total() * 3);
    std::vector<std::uint8_t> expected(compressBound(raw));
    uLongf n = expected.size();
    ASSERT_EQ(compress2(expected.data(), &n, scene.data, raw, Z_BEST_SPEED), Z_OK);
    expected.resize(n);
    EXPECT_EQ(encodeScene(scene), expected) << "scene " << k;
  }
}

// An action that changes nothing shows the same scene again: the environment
// sends its bytes again and the eye keeps its maps (sameImage decides).
TEST(Image, SameImageComparesSizeTypeAndEveryPixel) {
  cv::Mat a = blankScene(150);
  paintObject(a, Shape::Square, Colour::Red, 0.3, 0.4, world());
  const cv::Mat b = a.clone();
  EXPECT_TRUE(sameImage(a, b));
  EXPECT_TRUE(sameImage(a, a));
  cv::Mat c = a.clone();
  c.at<cv::Vec3b>(149, 149)[2] = 1;  // the very last byte
  EXPECT_FALSE(sameImage(a, c));
  EXPECT_FALSE(sameImage(a, blankScene(100)));
  EXPECT_FALSE(sameImage(a, cv::Mat()));
  EXPECT_FALSE(sameImage(a, cv::Mat(150, 150, CV_8UC1, cv::Scalar(0))));
  EXPECT_TRUE(sameImage(a(cv::Rect(10, 10, 50, 50)), b(cv::Rect(10, 10, 50, 50))));  // views, rows apart
  EXPECT_FALSE(sameImage(a(cv::Rect(10, 10, 50, 50)), a(cv::Rect(11, 10, 50, 50))));
}

// The digest of messages and the weights checksum: FNV-1a 64 byte by byte,
// however the bytes run (words of zeros are taken eight bytes at once).
TEST(Seal, Fnv1aIsTheByteByByteHashWhateverTheRunsOfZeros) {
  auto reference = [](const std::vector<std::uint8_t>& v) {
    std::uint64_t h = 0xCBF29CE484222325ull;
    for (std::uint8_t b : v) {
      h ^= b;
      h *= 0x100000001B3ull;
    }
    return h;
  };
  std::mt19937 gen(3);
  for (int k = 0; k < 200; ++k) {
    std::vector<std::uint8_t> v(gen() % 100);
    for (auto& b : v) b = gen() % 3 == 0 ? static_cast<std::uint8_t>(gen()) : 0;
    EXPECT_EQ(fnv1a64(v.data(), v.size()), reference(v)) << "bytes " << v.size();
    const std::size_t cut = v.empty() ? 0 : gen() % v.size();  // continued, from any place
    EXPECT_EQ(fnv1a64(fnv1a64(v.data(), cut), v.data() + cut, v.size() - cut), reference(v));
  }
}

// The scene decoder inflates raw and checks the zlib header and Adler-32
// itself: it accepts what uncompress accepts, decoding to the same bytes, and
// refuses the rest, on scenes and on every kind of damage to them.
TEST(Image, SceneDecodingAcceptsExactlyWhatUncompressAccepts) {
  std::mt19937 gen(9);
  std::uniform_real_distribution<double> where(0.1, 0.9);
  for (int k = 0; k < 120; ++k) {
    cv::Mat scene = blankScene(150);
    if (k % 7 == 6) scene.setTo(cv::Scalar(255, 1, 128));  // no zeros at all
    for (int o = 0; o < k % 10; ++o)
      paintObject(scene, static_cast<Shape>(o % 3), static_cast<Colour>(gen() % 3), where(gen), where(gen), world());
    std::vector<std::uint8_t> bytes = encodeScene(scene);
    switch (k % 6) {  // 0: intact
      case 1: bytes[gen() % bytes.size()] ^= static_cast<std::uint8_t>(1 + gen() % 255); break;
      case 2: bytes.resize(gen() % bytes.size()); break;
      case 3: bytes[gen() % 2] = static_cast<std::uint8_t>(gen()); break;  // the header
      case 4: bytes[bytes.size() - 1 - gen() % 4] ^= 0x10; break;        // the Adler-32
      case 5: bytes.push_back(static_cast<std::uint8_t>(gen())); break;  // a byte after the end
    }
    std::vector<std::uint8_t> expected(scene.total() * 3);
    uLongf n = expected.size();
    const bool ok = uncompress(expected.data(), &n, bytes.data(), static_cast<uLong>(bytes.size())) == Z_OK &&
                    n == expected.size();
    if (!ok) {
      EXPECT_THROW(decodeScene(bytes, 150, 150), std::runtime_error) << "case " << k;
      continue;
    }
    const cv::Mat back = decodeScene(bytes, 150, 150);
    EXPECT_EQ(std::vector<std::uint8_t>(back.data, back.data + back.total() * 3), expected) << "case " << k;
  }
}

TEST(Image, CorruptOrMisSizedSceneDataIsRejected) {
  cv::Mat scene = blankScene(150);
  auto bytes = encodeScene(scene);
  EXPECT_THROW(decodeScene(bytes, 100, 100), std::runtime_error);
  std::vector<std::uint8_t> junk(50, 7);
  EXPECT_THROW(decodeScene(junk, 150, 150), std::runtime_error);
}

TEST(Image, FocusCropIsCentredAndBlackOutsideTheScene) {
  cv::Mat scene = blankScene(150);
  scene.at<cv::Vec3b>(0, 0) = cv::Vec3b(255, 0, 0);
  const auto f = cropFocus(scene, {0, 0}, 21);
  ASSERT_EQ(f.size(), 21u * 21u * 3u);
  const std::size_t centre = (10 * 21 + 10) * 3;
  EXPECT_EQ(f[centre], 255);
  EXPECT_EQ(f[0], 0);  // outside the scene
}

TEST(Image, ImageChangeIsMeanAbsoluteDifference) {
  std::vector<std::uint8_t> a(10, 0), b(10, 0);
  b[3] = 255;
  EXPECT_DOUBLE_EQ(imageChange(a, b), 0.1);
  EXPECT_DOUBLE_EQ(imageChange(a, a), 0.0);
}

}  // namespace
}  // namespace afford

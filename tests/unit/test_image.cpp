#include <gtest/gtest.h>

#include <algorithm>

#include "afford/image.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

WorldConfig world() { return test::shippedConfig().world; }

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

TEST(Image, PaintedObjectIsPureColourOnBlack) {
  cv::Mat scene = blankScene(150);
  paintObject(scene, Shape::Square, Colour::Green, {30, 75}, world());
  EXPECT_EQ(scene.at<cv::Vec3b>(75, 30), cv::Vec3b(0, 255, 0));
  EXPECT_EQ(scene.at<cv::Vec3b>(75, 37), cv::Vec3b(0, 255, 0));
  EXPECT_EQ(scene.at<cv::Vec3b>(75, 38), cv::Vec3b(0, 0, 0));
}

TEST(Image, SceneEncodingIsLossless) {
  cv::Mat scene = blankScene(150);
  paintObject(scene, Shape::Circle, Colour::Blue, {75, 75}, world());
  const auto bytes = encodeScene(scene);
  EXPECT_LT(bytes.size(), 2000u);  // 67.5 KB raw
  const cv::Mat back = decodeScene(bytes, 150, 150);
  EXPECT_EQ(cv::norm(scene, back, cv::NORM_L1), 0.0);
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

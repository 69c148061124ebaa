#include "afford/image.hpp"

#include <opencv2/imgproc.hpp>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace afford {

int toPixel(double u, int size_px) { return static_cast<int>(std::lround(u * size_px)); }
double toUnit(int px, int size_px) { return static_cast<double>(px) / size_px; }
Pixel toPixel(double x, double y, int size_px) { return {toPixel(x, size_px), toPixel(y, size_px)}; }

namespace {
// Whole pixels in a length of scene units (floor, tolerant of 0.1 * 150 = 15.000000000000002).
int pixels(double units, int size_px) { return static_cast<int>(std::floor(units * size_px + 1e-9)); }
}  // namespace

std::vector<Pixel> shapeFootprint(Shape shape, const WorldConfig& world) {
  std::vector<Pixel> out;
  auto box = [&out](int w, int h) {
    for (int dr = -(h / 2); dr < h - h / 2; ++dr)
      for (int dc = -(w / 2); dc < w - w / 2; ++dc) out.push_back({dc, dr});
  };
  switch (shape) {
    case Shape::Square: {
      const int side = pixels(world.object_size, world.size_px);
      box(side, side);
      break;
    }
    case Shape::Rectangle:
      box(pixels(world.object_size * 2.0 / 3.0, world.size_px), pixels(world.object_size * 1.5, world.size_px));
      break;
    case Shape::Circle: {
      const double r = world.object_size / std::sqrt(M_PI) * world.size_px;
      const int reach = static_cast<int>(std::ceil(r));
      for (int dr = -reach; dr <= reach; ++dr)
        for (int dc = -reach; dc <= reach; ++dc)
          if (dc * dc + dr * dr <= r * r) out.push_back({dc, dr});
      break;
    }
  }
  return out;
}

int roundHalfAway(double v) { return static_cast<int>(std::round(std::round(v * 1e9) / 1e9)); }

std::vector<Pixel> shapePixels(Shape shape, double x, double y, const WorldConfig& world) {
  std::vector<Pixel> out;
  if (world.positions == Positions::Pixel) {
    const Pixel c = toPixel(x, y, world.size_px);
    for (const Pixel& f : shapeFootprint(shape, world)) out.push_back({c.col + f.col, c.row + f.row});
    return out;
  }
  const double cx = x * world.size_px, cy = y * world.size_px, side = world.object_size * world.size_px;
  auto box = [&](double w, double h) {
    const int c0 = roundHalfAway(cx - w / 2), c1 = roundHalfAway(cx + w / 2);
    const int r0 = roundHalfAway(cy - h / 2), r1 = roundHalfAway(cy + h / 2);
    for (int r = r0; r < r1; ++r)
      for (int c = c0; c < c1; ++c) out.push_back({c, r});
  };
  switch (shape) {
    case Shape::Square:
      box(side, side);
      break;
    case Shape::Rectangle:
      box(side * 2.0 / 3.0, side * 1.5);
      break;
    case Shape::Circle: {
      const double radius = side / std::sqrt(M_PI);
      for (int r = static_cast<int>(std::floor(cy - radius)); r <= static_cast<int>(std::ceil(cy + radius)); ++r)
        for (int c = static_cast<int>(std::floor(cx - radius)); c <= static_cast<int>(std::ceil(cx + radius)); ++c)
          if ((c - cx) * (c - cx) + (r - cy) * (r - cy) < radius * radius) out.push_back({c, r});
      break;
    }
  }
  return out;
}

Pixel windowCorner(double x, double y, int side, int size_px) {
  const double half = side / 2.0;
  return {roundHalfAway(x * size_px - half), roundHalfAway(y * size_px - half)};
}

cv::Mat blankScene(int size_px) { return cv::Mat(size_px, size_px, CV_8UC3, cv::Scalar(0, 0, 0)); }

void paintPixels(cv::Mat& scene, const std::vector<Pixel>& pixels, Colour colour) {
  const int ch = colourChannel(colour);
  for (const Pixel& p : pixels) {
    if (p.row < 0 || p.col < 0 || p.row >= scene.rows || p.col >= scene.cols) continue;
    auto& px = scene.at<cv::Vec3b>(p.row, p.col);
    px = cv::Vec3b(0, 0, 0);
    px[ch] = 255;
  }
}

void paintObject(cv::Mat& scene, Shape shape, Colour colour, double x, double y, const WorldConfig& world) {
  paintPixels(scene, shapePixels(shape, x, y, world), colour);
}

cv::Mat renderScenario(const Scenario& s, bool goal, const WorldConfig& world) {
  cv::Mat scene = blankScene(world.size_px);
  for (const auto& o : s.objects) {
    const ObjectState& st = goal ? o.goal : o.initial;
    paintObject(scene, o.shape, st.colour, st.x, st.y, world);
  }
  return scene;
}

cv::Mat scenarioPicture(const Scenario& s, const WorldConfig& world) {
  const int scale = 3, pad = 12, label = 28;
  const int side = world.size_px * scale;
  cv::Mat out(side + 2 * pad + label, 2 * side + 3 * pad, CV_8UC3, cv::Scalar(90, 90, 90));
  const char* titles[2] = {"goal", "initial"};
  for (int k = 0; k < 2; ++k) {
    cv::Mat rgb = renderScenario(s, k == 0, world), bgr, big;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    cv::resize(bgr, big, cv::Size(side, side), 0, 0, cv::INTER_NEAREST);
    const int x = pad + k * (side + pad);
    big.copyTo(out(cv::Rect(x, pad + label, side, side)));
    // the table limits, where object centres may be
    const int t0 = static_cast<int>(world.table_min * side), t1 = static_cast<int>(world.table_max * side);
    cv::rectangle(out, cv::Rect(x + t0, pad + label + t0, t1 - t0, t1 - t0), cv::Scalar(200, 200, 200), 1);
    cv::putText(out, s.name + ": " + titles[k], cv::Point(x, pad + 20), cv::FONT_HERSHEY_SIMPLEX, 0.6,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  return out;
}

bool sameImage(const cv::Mat& a, const cv::Mat& b) {
  if (a.dims != 2 || b.dims != 2 || a.size() != b.size() || a.type() != b.type()) return false;
  if (a.data == b.data && a.step[0] == b.step[0]) return true;  // one image
  const std::size_t row = static_cast<std::size_t>(a.cols) * a.elemSize();
  for (int r = 0; r < a.rows; ++r)
    if (std::memcmp(a.ptr(r), b.ptr(r), row) != 0) return false;
  return true;
}

namespace {

// A scene travels as a zlib stream (RFC 1950): a two-byte header, the deflate
// stream, the Adler-32 of the raw bytes, big-endian. zlib's own Adler-32 takes
// a byte at a time, a sixth of a run's time in all, so the stream is deflated
// and inflated raw here and its two ends written and checked by this file:
// the bytes are those of compress2(..., Z_BEST_SPEED), and what uncompress
// refuses is refused.
constexpr std::uint8_t kZlibHeader[2] = {0x78, 0x01};  // deflate, 32 KB window, fastest level
constexpr int kWindowBits = 15;

// Adler-32 of n bytes, as zlib's adler32(1, p, n). A zero byte leaves the sum
// a alone and adds a to b, so a word of eight zeros (most of a black scene)
// adds 8a at once. Sums are reduced every MB, before they could overflow.
std::uint32_t adler32Of(const std::uint8_t* p, std::size_t n) {
  constexpr std::uint64_t kBase = 65521;
  std::uint64_t a = 1, b = 0;
  std::size_t i = 0;
  while (i < n) {
    const std::size_t end = std::min(n, i + (std::size_t{1} << 20));
    for (; i + 8 <= end; i += 8) {
      std::uint64_t word;
      std::memcpy(&word, p + i, sizeof word);
      if (word == 0) {
        b += 8 * a;
        continue;
      }
      for (std::size_t j = i; j < i + 8; ++j) {
        a += p[j];
        b += a;
      }
    }
    for (; i < end; ++i) {
      a += p[i];
      b += a;
    }
    a %= kBase;
    b %= kBase;
  }
  return static_cast<std::uint32_t>(b << 16 | a);
}

// One raw deflate (inflate) state per thread, reset for each scene rather than
// built afresh (a deflate state's ~300 KB of tables were allocated, zeroed and
// freed on every step).
struct Deflater {
  z_stream z{};
  bool ok = deflateInit2(&z, Z_BEST_SPEED, Z_DEFLATED, -kWindowBits, 8, Z_DEFAULT_STRATEGY) == Z_OK;
  ~Deflater() {
    if (ok) deflateEnd(&z);
  }
};
struct Inflater {
  z_stream z{};
  bool ok = inflateInit2(&z, -kWindowBits) == Z_OK;
  ~Inflater() {
    if (ok) inflateEnd(&z);
  }
};

// The zlib header checks inflate makes: deflate, a window of at most 32 KB,
// the check bits, no preset dictionary (uncompress has none to give).
bool zlibHeaderValid(std::uint8_t cmf, std::uint8_t flg) {
  return (cmf & 0x0f) == Z_DEFLATED && (cmf >> 4) + 8 <= kWindowBits && (cmf * 256 + flg) % 31 == 0 &&
         (flg & 0x20) == 0;
}

}  // namespace

std::vector<std::uint8_t> encodeScene(const cv::Mat& scene) {
  CV_Assert(scene.type() == CV_8UC3 && scene.isContinuous());
  const uLong raw = static_cast<uLong>(scene.total() * 3);
  thread_local Deflater d;
  if (!d.ok || deflateReset(&d.z) != Z_OK) throw std::runtime_error("zlib compression of the scene failed (no deflate state)");
  std::vector<std::uint8_t> out(sizeof kZlibHeader + deflateBound(&d.z, raw) + 4);
  std::memcpy(out.data(), kZlibHeader, sizeof kZlibHeader);
  d.z.next_in = scene.data;
  d.z.avail_in = static_cast<uInt>(raw);
  d.z.next_out = out.data() + sizeof kZlibHeader;
  d.z.avail_out = static_cast<uInt>(out.size() - sizeof kZlibHeader - 4);
  if (deflate(&d.z, Z_FINISH) != Z_STREAM_END) throw std::runtime_error("zlib compression of the scene failed");
  const std::size_t end = sizeof kZlibHeader + d.z.total_out;
  const std::uint32_t check = adler32Of(scene.data, raw);
  for (int k = 0; k < 4; ++k) out[end + k] = static_cast<std::uint8_t>(check >> (24 - 8 * k));
  out.resize(end + 4);
  return out;
}

cv::Mat decodeScene(const std::vector<std::uint8_t>& data, int width, int height) {
  if (width <= 0 || height <= 0 || width > 4096 || height > 4096)
    throw std::runtime_error("scene size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range");
  cv::Mat scene(height, width, CV_8UC3);
  const std::size_t want = scene.total() * 3;
  const std::runtime_error invalid("scene data is not a valid zlib stream of the declared size");
  if (data.size() < sizeof kZlibHeader || !zlibHeaderValid(data[0], data[1])) throw invalid;
  thread_local Inflater f;
  if (!f.ok || inflateReset(&f.z) != Z_OK) throw std::runtime_error("zlib decompression of the scene failed (no inflate state)");
  f.z.next_in = const_cast<Bytef*>(data.data() + sizeof kZlibHeader);
  f.z.avail_in = static_cast<uInt>(data.size() - sizeof kZlibHeader);
  f.z.next_out = scene.data;
  f.z.avail_out = static_cast<uInt>(want);
  if (inflate(&f.z, Z_FINISH) != Z_STREAM_END || f.z.avail_in < 4) throw invalid;
  const std::size_t n = f.z.total_out;
  std::uint32_t check = 0;
  for (int k = 0; k < 4; ++k) check = check << 8 | f.z.next_in[k];
  if (check != adler32Of(scene.data, n)) throw invalid;
  if (n != want)
    throw std::runtime_error("scene data decodes to " + std::to_string(n) + " bytes, expected " + std::to_string(want));
  return scene;
}

std::vector<std::uint8_t> cropFocus(const cv::Mat& scene, Pixel centre, int side) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(side) * side * 3, 0);
  const int half = side / 2;
  for (int r = 0; r < side; ++r) {
    const int sr = centre.row - half + r;
    if (sr < 0 || sr >= scene.rows) continue;
    for (int c = 0; c < side; ++c) {
      const int sc = centre.col - half + c;
      if (sc < 0 || sc >= scene.cols) continue;
      const auto& px = scene.at<cv::Vec3b>(sr, sc);
      std::uint8_t* o = &out[(static_cast<std::size_t>(r) * side + c) * 3];
      o[0] = px[0];
      o[1] = px[1];
      o[2] = px[2];
    }
  }
  return out;
}

double imageDistance(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  if (a.size() != b.size() || a.empty()) return 1.0;
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = (static_cast<int>(a[i]) - static_cast<int>(b[i])) / 255.0;
    sum += d * d;
  }
  return std::sqrt(sum) / static_cast<double>(a.size());
}

std::vector<std::uint8_t> quantiseImage(const std::vector<double>& what) {
  std::vector<std::uint8_t> out(what.size());
  for (std::size_t i = 0; i < what.size(); ++i)
    out[i] = static_cast<std::uint8_t>(std::lround(std::clamp(what[i], 0.0, 1.0) * 255.0));
  return out;
}

double silhouetteDistance(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  if (a.size() != b.size() || a.size() < 3) return 1.0;
  std::size_t differ = 0;
  for (std::size_t i = 0; i + 2 < a.size(); i += 3) {
    const bool in_a = a[i] || a[i + 1] || a[i + 2], in_b = b[i] || b[i + 1] || b[i + 2];
    differ += in_a != in_b;
  }
  return static_cast<double>(differ) / static_cast<double>(a.size() / 3);
}

double imageChange(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  if (a.size() != b.size() || a.empty()) return 1.0;
  long sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i]));
  return static_cast<double>(sum) / 255.0 / static_cast<double>(a.size());
}

}  // namespace afford

#include "experiment/export/foxglove.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <utility>

#include "afford/json_messages.hpp"

namespace afford::foxglove {

namespace {

using Json = nlohmann::ordered_json;

constexpr const char* kDraft = "https://json-schema.org/draft/2020-12/schema";
constexpr std::uint64_t kNanoseconds = 1000000000;

std::string text(const Json& j) { return j.dump(-1, ' ', false, Json::error_handler_t::replace); }

Json typed(const char* type, const char* description) { return Json{{"type", type}, {"description", description}}; }

Json object(const char* title, const char* description, Json properties) {
  Json required = Json::array();
  for (const auto& [name, schema] : properties.items()) required.push_back(name);
  return Json{{"title", title}, {"description", description}, {"type", "object"},
              {"properties", std::move(properties)}, {"required", std::move(required)}};
}

Json array(const char* description, Json items) {
  return Json{{"type", "array"}, {"description", description}, {"items", std::move(items)}};
}

// Foxglove's `time`: seconds and nanoseconds.
Json timeSchema(const char* description) {
  Json sec = typed("integer", "seconds");
  sec["minimum"] = 0;
  Json nsec = typed("integer", "nanoseconds");
  nsec["minimum"] = 0;
  nsec["maximum"] = kNanoseconds - 1;
  Json t = object("time", description, Json{{"sec", sec}, {"nsec", nsec}});
  return t;
}

Json colourSchema(const char* description) {
  Json channel = typed("number", "in [0, 1]");
  channel["minimum"] = 0;
  channel["maximum"] = 1;
  return object("foxglove.Color", description, Json{{"r", channel}, {"g", channel}, {"b", channel}, {"a", channel}});
}

Json point2Schema(const char* description) {
  return object("foxglove.Point2", description,
                Json{{"x", typed("number", "x coordinate position")}, {"y", typed("number", "y coordinate position")}});
}

// A top schema: its draft first.
Json withDraft(Json schema) {
  Json top = {{"$schema", kDraft}};
  top.update(schema);
  return top;
}

Json stamp(std::uint64_t time_ns) {
  return Json{{"sec", time_ns / kNanoseconds}, {"nsec", time_ns % kNanoseconds}};
}

Json colour(const Colour& c) { return Json{{"r", c.r}, {"g", c.g}, {"b", c.b}, {"a", c.a}}; }

// The bytes of an image, for base64.
struct ByteView {
  const std::uint8_t* p;
  std::size_t n;
  const std::uint8_t* data() const { return p; }
  std::size_t size() const { return n; }
};

Json compressedImageSchemaJson() {
  Json data = typed("string", "Compressed image data");
  data["contentEncoding"] = "base64";
  Json schema = object(kCompressedImage, "A compressed image",
                       Json{{"timestamp", timeSchema("Timestamp of image")},
                            {"frame_id", typed("string", "Frame of reference for the image")},
                            {"data", data},
                            {"format", typed("string", "Image format: webp, jpeg or png")}});
  return withDraft(std::move(schema));
}

Json imageAnnotationsSchemaJson() {
  Json type = typed("integer", "1 POINTS, 2 LINE_LOOP, 3 LINE_STRIP, 4 LINE_LIST (0 UNKNOWN)");
  type["minimum"] = 0;
  type["maximum"] = 4;
  Json circle = object(
      "foxglove.CircleAnnotation", "A circle annotation on a 2D image",
      Json{{"timestamp", timeSchema("Timestamp of circle")},
           {"position", point2Schema("Center of the circle in 2D image coordinates (pixels)")},
           {"diameter", typed("number", "Circle diameter in pixels")},
           {"thickness", typed("number", "Line thickness in pixels")},
           {"fill_color", colourSchema("Fill color")},
           {"outline_color", colourSchema("Outline color")}});
  Json points = object(
      "foxglove.PointsAnnotation", "An array of points on a 2D image",
      Json{{"timestamp", timeSchema("Timestamp of annotation")},
           {"type", type},
           {"points", array("Points in 2D image coordinates (pixels)", point2Schema("A point"))},
           {"outline_color", colourSchema("Outline color")},
           {"outline_colors", array("Per-point or per-segment colors", colourSchema("A color"))},
           {"fill_color", colourSchema("Fill color")},
           {"thickness", typed("number", "Stroke thickness in pixels")}});
  Json label = object("foxglove.TextAnnotation", "A text label on a 2D image",
                      Json{{"timestamp", timeSchema("Timestamp of annotation")},
                           {"position", point2Schema("Bottom-left origin of the text label in 2D image coordinates")},
                           {"text", typed("string", "Text to display")},
                           {"font_size", typed("number", "Font size in pixels")},
                           {"text_color", colourSchema("Text color")},
                           {"background_color", colourSchema("Background fill color")}});
  Json schema = object(kImageAnnotations, "Array of annotations for a 2D image",
                       Json{{"circles", array("Circle annotations", circle)},
                            {"points", array("Points annotations", points)},
                            {"texts", array("Text annotations", label)}});
  return withDraft(std::move(schema));
}

}  // namespace

namespace {
// An image message's opening, as text (an image's base64 is most of a file, and needs no escaping):
// {"timestamp":{...},"frame_id":"..."
std::string imageHead(std::uint64_t time_ns, const std::string& frame_id) {
  std::string o = R"({"timestamp":{"sec":)";
  json_messages::integer(o, static_cast<std::int64_t>(time_ns / kNanoseconds));
  o += R"(,"nsec":)";
  json_messages::integer(o, static_cast<std::int64_t>(time_ns % kNanoseconds));
  o += R"(},"frame_id":)";
  json_messages::text(o, frame_id);
  return o;
}
}  // namespace

const std::string& compressedImageSchema() {
  static const std::string kText = text(compressedImageSchemaJson());
  return kText;
}

const std::string& imageAnnotationsSchema() {
  static const std::string kText = text(imageAnnotationsSchemaJson());
  return kText;
}

std::string compressedImage(std::uint64_t time_ns, const std::string& frame_id, const std::string& format,
                            const std::vector<std::uint8_t>& bytes) {
  std::string o = imageHead(time_ns, frame_id);
  o += R"(,"data":)";
  json_messages::base64(o, ByteView{bytes.data(), bytes.size()}, static_cast<std::int64_t>(bytes.size()));
  o += R"(,"format":)";
  json_messages::text(o, format);
  o += '}';
  return o;
}

std::string box(std::uint64_t time_ns, double left, double top, double side, const Colour& c) {
  Json corners = Json::array();
  const std::array<std::pair<double, double>, 4> loop_corners = {
      {{left, top}, {left + side, top}, {left + side, top + side}, {left, top + side}}};
  for (const auto& [x, y] : loop_corners) corners.push_back(Json{{"x", x}, {"y", y}});
  Json loop = {{"timestamp", stamp(time_ns)},
               {"type", 2},  // LINE_LOOP
               {"points", std::move(corners)},
               {"outline_color", colour(c)},
               {"outline_colors", Json::array()},
               {"fill_color", colour({0, 0, 0, 0})},
               {"thickness", 1.0}};
  Json j = {{"circles", Json::array()}, {"points", Json::array({std::move(loop)})}, {"texts", Json::array()}};
  return text(j);
}

}  // namespace afford::foxglove

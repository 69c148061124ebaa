#include "experiment/export/image_fields.hpp"

#include <zlib.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace afford::image_fields {

namespace {

using Json = nlohmann::ordered_json;

// A PNG image's schema: a base64 string of media type image/png ("" for none).
Json pngSchema(const std::string& description) {
  return Json{{"description", description},
              {"type", "string"},
              {"contentEncoding", "base64"},
              {"contentMediaType", "image/png"}};
}

void bigEndian(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

// A PNG chunk: its length, type and data, and the CRC-32 of its type and data.
void chunk(std::vector<std::uint8_t>& out, const char* type, const std::uint8_t* data, std::size_t n) {
  bigEndian(out, static_cast<std::uint32_t>(n));
  const std::size_t at = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data, data + n);
  bigEndian(out, static_cast<std::uint32_t>(crc32(0, out.data() + at, static_cast<uInt>(n + 4))));
}

void appendPng(std::string& o, const std::vector<std::uint8_t>& png) {
  json_messages::base64(o, png, static_cast<std::int64_t>(png.size()));
}

}  // namespace

int squareSide(std::int64_t bytes) {
  if (bytes <= 0 || bytes % 3 != 0) return bytes == 0 ? 0 : -1;
  const auto side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(bytes / 3))));
  return std::int64_t{side} * side * 3 == bytes ? side : -1;
}

std::vector<std::uint8_t> png(const std::uint8_t* rgb, int width, int height) {
  // Each row after filter type 0 (none): the images are flat shapes (or smooth predictions), which deflate
  // takes best unfiltered (a third smaller than libpng's adaptive filters, and a tenth of its time).
  const std::size_t row = static_cast<std::size_t>(width) * 3;
  std::vector<std::uint8_t> raw((row + 1) * static_cast<std::size_t>(height), 0);
  for (int y = 0; y < height; ++y) std::copy_n(rgb + y * row, row, raw.begin() + y * (row + 1) + 1);
  // A window and a hash no larger than the image needs (zlib clears its hash table for every stream). A
  // focus-sized image at zlib's default level; a scene (67 KB of pixels) at level 3, a third of the time
  // for twice the bytes (about 0.9 KB; level 6 made 0.4 KB in 0.36 ms a scene).
  int bits = 9;
  while ((std::size_t{1} << bits) < raw.size() && bits < 15) ++bits;
  z_stream z{};
  if (deflateInit2(&z, bits < 15 ? 6 : 3, Z_DEFLATED, bits, bits < 15 ? 4 : 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("zlib cannot start a PNG's stream");
  std::vector<std::uint8_t> idat(deflateBound(&z, static_cast<uLong>(raw.size())));
  z.next_in = raw.data();
  z.avail_in = static_cast<uInt>(raw.size());
  z.next_out = idat.data();
  z.avail_out = static_cast<uInt>(idat.size());
  const int done = deflate(&z, Z_FINISH);
  idat.resize(z.total_out);
  deflateEnd(&z);
  if (done != Z_STREAM_END) throw std::runtime_error("zlib cannot deflate a PNG's pixels");
  static const std::uint8_t kSignature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<std::uint8_t> out(kSignature, kSignature + 8);
  std::vector<std::uint8_t> header;
  bigEndian(header, static_cast<std::uint32_t>(width));
  bigEndian(header, static_cast<std::uint32_t>(height));
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8 bits, truecolour (RGB), deflate, no filter set, no interlace
  chunk(out, "IHDR", header.data(), header.size());
  chunk(out, "IDAT", idat.data(), idat.size());
  chunk(out, "IEND", nullptr, 0);
  return out;
}

std::vector<std::uint8_t> squarePng(const std::vector<std::uint8_t>& rgb, const char* field) {
  const int side = squareSide(static_cast<std::int64_t>(rgb.size()));
  if (side < 0)
    throw std::runtime_error(std::string("field ") + field + ": " + std::to_string(rgb.size()) +
                             " bytes are not a square RGB image");
  return side == 0 ? std::vector<std::uint8_t>{} : png(rgb.data(), side, side);
}

std::vector<std::uint8_t> bytesOf(const std::vector<float>& values) {
  std::vector<std::uint8_t> out(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    const float v = values[i] > 0 ? std::min(values[i], 1.0f) : 0.0f;  // (NaN: 0; the edge refuses it anyway)
    out[i] = static_cast<std::uint8_t>(std::lround(v * 255.0f));
  }
  return out;
}

std::string schemaWithImages(const char* generated, const std::vector<std::string>& images,
                             const std::vector<MovedField>& moved) {
  Json schema = Json::parse(generated);
  for (const std::string& name : images) {
    Json& field = schema.at("properties").at(name);
    const std::string declared = field.at("description").get<std::string>();
    // A byte array of one dimension is a string; of two, an array of rows.
    const bool rows = field.at("type") == "array";
    Json image = pngSchema(rows ? "a square RGB image" : declared + ", as PNG");
    if (!rows) {
      field = std::move(image);
      continue;
    }
    Json list = {{"description", declared + ", as PNG"}, {"type", "array"}, {"items", std::move(image)}};
    if (field.contains("minItems")) list["minItems"] = field["minItems"], list["maxItems"] = field["maxItems"];
    field = std::move(list);
  }
  for (const MovedField& m : moved) {
    Json& field = schema.at("properties").at(m.name);
    const std::string declared = field.at("description").get<std::string>();
    const bool floats = declared.rfind("float", 0) == 0;
    const std::string pixels = floats ? "its images as PNG of round(255 v), side by side in the order of actions,"
                                      : "its pixels as PNG";
    field = Json{{"description", declared + ": " + pixels + " on " + m.topic + " at this message's log time (\"\": none)"},
                 {"type", "string"},
                 {"enum", Json::array({m.topic, ""})}};
  }
  return schema.dump(-1, ' ', false, Json::error_handler_t::replace);
}

void replaceField(std::string& json, const std::string& name, const char* blank, const std::string& value) {
  // (A string's quotes are escaped in JSON text, so this can only be a key and its value.)
  const std::string key = "\"" + name + "\":" + blank;
  const std::size_t at = json.find(key);
  if (at == std::string::npos || json.find(key, at + 1) != std::string::npos)
    throw std::logic_error("image_fields::replaceField: field " + name + " is not once in the message's JSON");
  json.replace(at + name.size() + 3, std::char_traits<char>::length(blank), value);
}

std::string pngJson(const std::vector<std::uint8_t>& rgb, const char* field) {
  std::string o;
  appendPng(o, squarePng(rgb, field));
  return o;
}

std::string pngJson(const std::vector<std::vector<std::uint8_t>>& rows, const char* field) {
  std::string o = "[";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (i) o += ',';
    appendPng(o, squarePng(rows[i], field));
  }
  return o + ']';
}

}  // namespace afford::image_fields

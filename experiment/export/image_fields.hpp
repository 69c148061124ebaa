// The image fields of afford's messages as `afford export` writes them (export.hpp): images, not numbers, and
// each image once. Each focus-sized image of the protocol, side x side RGB bytes (FOCUS.diff_image,
// EFFECT.image, FORWARD_QUERY.image, GOAL.image, PROBE.images), is written as a PNG in base64, the same
// pixels, in place of its raw bytes in base64. A field whose pixels the file holds on an image topic at the
// message's log time (SCENE.data on /SCENE/image, FOCUS.image on /FOCUS/image, FORWARD_PREDICTION.what, as
// PNGs of round(255 v), on /FORWARD_PREDICTION/what) holds that topic's name in place of a second copy. A
// message's JSON is the generated one (afford/json_messages.hpp) with these fields so written; its JSON
// Schema is the generated one with theirs a base64 string of contentMediaType image/png (an array of them
// for two dimensions), or the one topic's name.
#pragma once
#include <cstdint>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "afford/effect_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/goal_t.hpp"
#include "afford/json_messages.hpp"
#include "afford/object_probe_t.hpp"
#include "afford/scene_t.hpp"
#include "experiment/export/export.hpp"

namespace afford::image_fields {

// The side of a square RGB image of `bytes` bytes (0: none), or -1 when no square has that many.
int squareSide(std::int64_t bytes);

// A width x height RGB image (rows of width * 3 bytes) as PNG: 8-bit RGB, rows unfiltered, deflated by zlib
// (at its default level; a scene-sized image at level 3).
std::vector<std::uint8_t> png(const std::uint8_t* rgb, int width, int height);

// A square RGB image as PNG, or none for no bytes. Throws std::runtime_error naming `field` when the bytes are
// not a square RGB image (the edge refuses such a message: none is exported).
std::vector<std::uint8_t> squarePng(const std::vector<std::uint8_t>& rgb, const char* field);

// A predicted image (floats in [0, 1]) as bytes: round(255 v), clamped.
std::vector<std::uint8_t> bytesOf(const std::vector<float>& values);

// A field whose pixels are on an image topic: its name and the topic's.
struct MovedField {
  std::string name, topic;
};

// The generated JSON Schema of a type with the fields `images` as PNG images and the fields `moved` as the
// name of their topic, or "" (no image).
std::string schemaWithImages(const char* generated, const std::vector<std::string>& images,
                             const std::vector<MovedField>& moved);

// Calls f(field, name) for each image field written as PNG in the message (none in most types).
template <class Msg, class F>
void forImageFields(Msg& m, F&& f) {
  if constexpr (std::is_same_v<Msg, focus_t>) {
    f(m.diff_image, "diff_image");
  } else if constexpr (std::is_same_v<Msg, effect_t> || std::is_same_v<Msg, forward_query_t> ||
                       std::is_same_v<Msg, goal_t>) {
    f(m.image, "image");
  } else if constexpr (std::is_same_v<Msg, object_probe_t>) {
    f(m.images, "images");
  }
}

// Calls f(field, name, topic) for the field whose pixels are on an image topic (none in most types).
template <class Msg, class F>
void forMovedField(Msg& m, F&& f) {
  if constexpr (std::is_same_v<Msg, scene_t>) {
    f(m.data, "data", kSceneImageTopic);
  } else if constexpr (std::is_same_v<Msg, focus_t>) {
    f(m.image, "image", kFocusImageTopic);
  } else if constexpr (std::is_same_v<Msg, forward_prediction_t>) {
    f(m.what, "what", kPredictionImageTopic);
  }
}

// A type's JSON Schema as the export writes it, made once.
template <class Msg>
const std::string& schemaText() {
  static const std::string kText = [] {
    Msg m{};
    std::vector<std::string> images;
    std::vector<MovedField> moved;
    forImageFields(m, [&](const auto&, const char* name) { images.emplace_back(name); });
    forMovedField(m, [&](const auto&, const char* name, const char* topic) { moved.push_back({name, topic}); });
    return images.empty() && moved.empty() ? std::string(json_messages::Schema<Msg>::kText)
                                           : schemaWithImages(json_messages::Schema<Msg>::kText, images, moved);
  }();
  return kText;
}

// The text `json` with the value of its top-level field `name`, now `blank` ("" or []), replaced by `value`.
// Throws std::logic_error when the field is not there once (the generated JSON names each field once).
void replaceField(std::string& json, const std::string& name, const char* blank, const std::string& value);

// One field's images as JSON: a base64 string of a PNG, or an array of them.
std::string pngJson(const std::vector<std::uint8_t>& rgb, const char* field);
std::string pngJson(const std::vector<std::vector<std::uint8_t>>& rows, const char* field);

// An emptied field in the generated JSON: a byte array's "", another array's [].
template <class Field>
const char* blankOf(const Field&) {
  return std::is_same_v<Field, std::vector<std::uint8_t>> ? "\"\"" : "[]";
}

// A message as JSON with its image fields as PNG and its moved field as its topic's name ("" when empty: no
// image on the topic). Throws std::runtime_error naming a field that does not hold square RGB images.
template <class Msg>
std::string messageJson(Msg m) {
  std::vector<std::tuple<const char*, const char*, std::string>> values;  // name, blank, JSON
  forImageFields(m, [&](auto& field, const char* name) {
    values.emplace_back(name, blankOf(field), pngJson(field, name));
    field.clear();  // emptied for the generated JSON
  });
  forMovedField(m, [&](auto& field, const char* name, const char* topic) {
    values.emplace_back(name, blankOf(field), field.empty() ? "\"\"" : "\"" + std::string(topic) + "\"");
    field.clear();
  });
  std::string json = json_messages::jsonText(m);
  for (const auto& [name, blank, value] : values) replaceField(json, name, blank, value);
  return json;
}

}  // namespace afford::image_fields

// Foxglove's own message schemas for images (https://docs.foxglove.dev/docs/visualization/message-schemas),
// written here as JSON Schemas from their documented definitions, and the
// messages `afford export` writes with them (export.hpp): an image (a scene, a
// focus image, predicted images) as foxglove.CompressedImage (PNG), the eye's
// gaze as foxglove.ImageAnnotations (a LINE_LOOP box over the scene image, in
// its pixels). Foxglove recognises a schema by its name (kCompressedImage,
// kImageAnnotations) and message encoding "json".
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace afford::foxglove {

inline constexpr const char* kCompressedImage = "foxglove.CompressedImage";
inline constexpr const char* kImageAnnotations = "foxglove.ImageAnnotations";

// The JSON Schema texts (draft 2020-12), made once.
const std::string& compressedImageSchema();
const std::string& imageAnnotationsSchema();

struct Colour {
  double r = 0, g = 0, b = 0, a = 1;  // each in [0, 1]
};

// An encoded image (`format`: "png", "jpeg", ...) as foxglove.CompressedImage JSON, stamped time_ns.
std::string compressedImage(std::uint64_t time_ns, const std::string& frame_id, const std::string& format,
                            const std::vector<std::uint8_t>& bytes);

// A square of `side` pixels with its top-left corner at (left, top), in image
// pixels (the origin the top-left corner of the top-left pixel), as
// foxglove.ImageAnnotations JSON: one LINE_LOOP of four points, stamped time_ns.
std::string box(std::uint64_t time_ns, double left, double top, double side, const Colour& colour);

}  // namespace afford::foxglove

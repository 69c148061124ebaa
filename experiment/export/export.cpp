#include "experiment/export/export.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string_view>
#include <type_traits>
#include <utility>

#include "afford/auth.hpp"
#include "afford/bounds.hpp"
#include "afford/config.hpp"
#include "afford/decode.hpp"
#include "afford/file_lock.hpp"
#include "afford/image.hpp"
#include "afford/json_messages.hpp"
#include "afford/protocol.hpp"
#include "afford/process_main.hpp"
#include "afford/version.hpp"
#include "experiment/export/foxglove.hpp"
#include "experiment/export/image_fields.hpp"
#include "experiment/export/mcap.hpp"
#include "experiment/replay/replay.hpp"
#include "viewer/step_order.hpp"

namespace afford {
namespace fs = std::filesystem;

namespace {

// The most skipped events warned of one by one (all are counted).
constexpr std::int64_t kMostWarnings = 10;

// The gaze's colours.
const foxglove::Colour kFocusGaze{1, 1, 0, 1};   // yellow: a FOCUS
const foxglove::Colour kEffectGaze{0, 1, 1, 1};  // cyan: an EFFECT's gaze after the action

// A message's time in the file, from its place in the run: the time the log
// gives the run's RUN_CONFIG, a millisecond a step, a microsecond a message
// within its step (the messages come in step order).
class StepClock {
 public:
  static constexpr std::uint64_t kStep = 1'000'000, kPlace = 1'000, kMostPlaces = 999;  // nanoseconds

  // False if the time would be beyond MCAP's (a step out of any run's range: the edge refuses it anyway).
  bool timeOf(const LogEvent& e, const StepKey& key, std::uint64_t& time) {
    if (!started_) {  // the run's RUN_CONFIG, first
      started_ = true;
      const auto most = std::numeric_limits<std::uint64_t>::max() / 1000 / 2;
      start_ = e.utime > 0 && static_cast<std::uint64_t>(e.utime) < most ? static_cast<std::uint64_t>(e.utime) * 1000 : 0;
    }
    // Before the first step: -1; STOP: after the last.
    const std::int64_t step = key.step == StepKey::kAfter ? last_ + 1 : std::max<std::int64_t>(key.step, -1);
    if (step != at_) at_ = step, place_ = 0;
    const std::uint64_t steps = static_cast<std::uint64_t>(step + 1);
    if (steps > (std::numeric_limits<std::uint64_t>::max() - start_) / kStep - 1) return false;
    time = start_ + steps * kStep + std::min(place_++, kMostPlaces) * kPlace;
    last_ = std::max(last_, step);
    return true;
  }

 private:
  bool started_ = false;
  std::uint64_t start_ = 0, place_ = 0;
  std::int64_t at_ = -2, last_ = -1;
};

// Writes the run's messages into the MCAP file, one event at a time.
class Exporter {
 public:
  Exporter(McapWriter& mcap, ExportResult& result, std::string source, spdlog::logger& log)
      : mcap_(mcap), result_(result), source_(std::move(source)), log_(log) {}

  // The run's configuration: the Metadata record, and the scene's size until a SCENE says it.
  void start(const run_config_t& rc, const RunConfig& config) {
    scene_width_ = scene_height_ = config.world.size_px;
    mcap_.addMetadata("afford", {{"afford_version", affordVersion()},
                                 {"run_id", rc.run_id},
                                 {"experiment", rc.experiment},
                                 {"system", rc.system},
                                 {"seed", std::to_string(rc.seed)},
                                 {"config_yaml", rc.config_yaml},
                                 {"log", source_}});
  }

  // The run's next message in step order, and its key.
  void event(const LogEvent& e, const StepKey& key, const BoundsContext& ctx) {
    ++result_.events;
    std::uint64_t time = 0;
    if (!clock_.timeOf(e, key, time)) {
      skip(topic(e.channel, ""), e, "its step " + std::to_string(key.step) + " is beyond MCAP's times");
      return;
    }
    const bool known = withChannel(e.channel, [&](const auto& c) {
      using Msg = typename std::decay_t<decltype(c)>::Message;
      ExportedTopic& t = topic(e.channel, json_messages::Schema<Msg>::kName);
      Msg m;
      std::string why;
      if (!decodeChecked(e.data.data(), e.data.size(), ctx, m, why)) {
        skip(t, e, why);
        return;
      }
      std::string json;
      Picture picture;
      try {  // (before anything of the message is written)
        picture = pictureOf(m);
        json = image_fields::messageJson(m);
      } catch (const std::runtime_error& ex) {  // an image that is not one: a scene that does not decode
        skip(t, e, ex.what());
        return;
      }
      put(t, channel(e.channel, json_messages::Schema<Msg>::kName, image_fields::schemaText<Msg>()), time, json);
      if (!picture.png.empty()) image(picture.topic, picture.frame_id, time, picture.png);
      marks(m, time);
    });
    if (!known) skip(topic(e.channel, ""), e, "not a channel of afford's protocol (afford/protocol.hpp)");
  }

 private:
  // A topic's figures (its schema "" until it is known).
  ExportedTopic& topic(const std::string& name, const std::string& schema) {
    const auto [it, fresh] = topic_index_.emplace(name, result_.topics.size());
    if (fresh) result_.topics.push_back({name, schema, 0, 0, ""});
    ExportedTopic& t = result_.topics[it->second];
    if (t.schema.empty()) t.schema = schema;
    return t;
  }

  // The MCAP channel of a topic, made with its schema at its first message.
  std::uint16_t channel(const std::string& name, std::string_view schema, std::string_view text) {
    if (const auto it = channels_.find(name); it != channels_.end()) return it->second;
    auto s = schemas_.find(std::string(schema));
    if (s == schemas_.end())
      s = schemas_.emplace(schema, mcap_.addSchema(std::string(schema), "jsonschema", std::string(text))).first;
    return channels_[name] = mcap_.addChannel(s->second, name, "json");
  }

  void put(ExportedTopic& t, std::uint16_t id, std::uint64_t time, const std::string& json) {
    mcap_.write(id, time, time, json.data(), json.size());
    ++t.messages;
    ++result_.messages;
  }

  void skip(ExportedTopic& t, const LogEvent& e, const std::string& why) {
    if (t.skipped++ == 0) t.first_skipped = why;
    if (result_.skipped++ < kMostWarnings)
      log_.warn("{}: the {} event at offset {} is skipped: {}", source_, e.channel, e.offset, why);
  }

  // The image a message puts on an image topic, made before the message is written: none for most types.
  // Throws std::runtime_error when its pixels are not an image (the message is then skipped).
  struct Picture {
    const char* topic = nullptr;
    const char* frame_id = nullptr;
    std::vector<std::uint8_t> png;  // none: no image
  };

  template <class Msg>
  static Picture pictureOf(const Msg&) {
    return {};
  }

  // As PNG, lossless: a scene is a few flat shapes (about 1 kB, where its pixels are 67 kB).
  static Picture pictureOf(const scene_t& m) {
    if (m.encoding != scene_t::ENCODING_ZLIB_RGB8)
      throw std::runtime_error("the scene's encoding " + std::to_string(m.encoding) + " is not ENCODING_ZLIB_RGB8");
    const cv::Mat rgb = decodeScene(m.data, m.width, m.height);
    return {kSceneImageTopic, "scene", image_fields::png(rgb.data, rgb.cols, rgb.rows)};
  }

  static Picture pictureOf(const focus_t& m) {
    if (m.image.empty()) return {};
    if (std::int64_t{m.side} * m.side * 3 != static_cast<std::int64_t>(m.image.size()))  // (the edge checks it)
      throw std::runtime_error("field image: " + std::to_string(m.image.size()) + " bytes are not " +
                               std::to_string(m.side) + " x " + std::to_string(m.side) + " RGB");
    return {kFocusImageTopic, "focus", image_fields::png(m.image.data(), m.side, m.side)};
  }

  // The predicted images side by side, in the order of the message's actions.
  static Picture pictureOf(const forward_prediction_t& m) {
    if (m.what.empty()) return {};
    const int side = image_fields::squareSide(m.size);  // (each row holds m.size values: the encoding's)
    if (side <= 0)
      throw std::runtime_error("field what: rows of " + std::to_string(m.size) + " values are not square RGB images");
    std::vector<std::uint8_t> strip(m.what.size() * m.what.front().size());
    for (std::size_t a = 0; a < m.what.size(); ++a) {
      const std::vector<std::uint8_t> bytes = image_fields::bytesOf(m.what[a]);
      for (int row = 0; row < side; ++row)
        std::copy_n(bytes.begin() + row * side * 3, side * 3, strip.begin() + (row * m.what.size() + a) * side * 3);
    }
    return {kPredictionImageTopic, "forward_prediction",
            image_fields::png(strip.data(), side * static_cast<int>(m.what.size()), side)};
  }

  // A PNG on an image topic, as foxglove.CompressedImage.
  void image(const char* name, const char* frame_id, std::uint64_t time, const std::vector<std::uint8_t>& png) {
    put(topic(name, foxglove::kCompressedImage),
        channel(name, foxglove::kCompressedImage, foxglove::compressedImageSchema()), time,
        foxglove::compressedImage(time, frame_id, "png", png));
  }

  // After a message is written: the scene's size from a SCENE, the gaze from a FOCUS and an EFFECT.
  template <class Msg>
  void marks(const Msg&, std::uint64_t) {}

  void marks(const scene_t& m, std::uint64_t) {
    scene_width_ = m.width;
    scene_height_ = m.height;
  }

  void marks(const focus_t& m, std::uint64_t time) { gaze(m.x, m.y, m.side, time, kFocusGaze); }

  void marks(const effect_t& m, std::uint64_t time) { gaze(m.after_x, m.after_y, m.side, time, kEffectGaze); }

  // The gaze's square: the eye's focus window around (x, y), scene units, in the
  // scene's pixels (as afford/image.hpp's windowCorner places it, per axis).
  void gaze(double x, double y, int side, std::uint64_t time, const foxglove::Colour& colour) {
    ExportedTopic& t = topic(kGazeTopic, foxglove::kImageAnnotations);
    const double left = roundHalfAway(x * scene_width_ - side / 2.0);
    const double top = roundHalfAway(y * scene_height_ - side / 2.0);
    put(t, channel(kGazeTopic, foxglove::kImageAnnotations, foxglove::imageAnnotationsSchema()), time,
        foxglove::box(time, left, top, side, colour));
  }

  StepClock clock_;
  McapWriter& mcap_;
  ExportResult& result_;
  std::string source_;  // the log, as given
  spdlog::logger& log_;
  std::map<std::string, std::size_t> topic_index_;
  std::map<std::string, std::uint16_t> channels_, schemas_;
  int scene_width_ = 0, scene_height_ = 0;
};

// The run's channels in the order they came, then the image topics.
void orderTopics(ExportResult& r) {
  std::stable_partition(r.topics.begin(), r.topics.end(), [](const ExportedTopic& t) { return t.topic[0] != '/'; });
}

}  // namespace

ExportResult exportMcap(const ExportOptions& o, spdlog::logger& log) {
  ExportResult result;
  result.file = o.mcap;
  if (o.mcap.empty()) throw std::runtime_error("no MCAP file to write (--mcap FILE)");
  // Before any work: the file's name, its folder, and no file there already (McapWriter checks it again).
  prepareOutput(o.mcap, "--mcap", {".mcap"});
  if (std::error_code ec; fs::exists(fs::symlink_status(o.mcap, ec)))
    throw std::runtime_error(o.mcap + " exists: afford export writes a new file, never over one");
  const std::shared_ptr<const BusKey> key = o.bus_key.empty() ? nullptr : busKeyFrom(o.bus_key);
  // The run's messages in step order (throws when there is no log): the file is the same however the log
  // interleaves its channels.
  StepOrderedLog<RecordedLogStream, RunSelector> in(
      [&](spdlog::logger& l) { return std::make_unique<RecordedLogStream>(o.log, l, key.get()); },
      [&](spdlog::logger& l) { return std::make_unique<RunSelector>(o.run_id, o.log, l); },
      loadProtocol(defaultConfigDir()), log);
  std::vector<LogGap> manifest_missing;
  result.incomplete = manifestIncomplete(o.log, manifest_missing);
  result.cut = in.cut();  // (warned of as the log was opened)
  McapWriter mcap(o.mcap, McapOptions{"", std::string("afford ") + affordVersion(), o.chunk_bytes, o.compression});
  Exporter exporter(mcap, result, o.log, log);
  const RunSelector& select = in.selector();
  std::unique_ptr<RunConfig> config;
  BoundsContext ctx{nullptr, nullptr};
  LogEvent e;
  StepKey at;
  while (in.next(e, at)) {
    // Ctrl-C (when the command installed the stop handlers): the partial file goes with the writer.
    if (stopRequested()) throw std::runtime_error("interrupted: " + o.mcap + " not written");
    if (!config) {
      config = std::make_unique<RunConfig>(parseRunConfigText(select.config().config_yaml));
      ctx = BoundsContext{&config->protocol, config.get()};
      result.run_id = select.config().run_id;
      result.phase = config->phase;
      exporter.start(select.config(), *config);
    }
    exporter.event(e, at, ctx);
  }
  result.left_out = in.order().leftOut();
  result.torn_bytes = in.stream().counts().torn_bytes;
  result.malformed = in.stream().counts().malformed;
  result.untagged = in.stream().counts().untagged;
  result.refused_configs = select.refusedConfigs();
  result.left_out -= result.refused_configs;  // (counted apart)
  select.check(result.cut, in.stream().counts().key);  // (the partial file goes with the writer)
  mcap.close();
  result.bytes = mcap.bytes();
  result.chunks = mcap.chunks();
  result.compression = o.compression;
  result.record_bytes = mcap.chunkRecordBytes();
  orderTopics(result);
  return result;
}

}  // namespace afford

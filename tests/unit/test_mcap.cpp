// afford export (experiment/export): a stored run log written as an MCAP file
// holds one JSON message per log message that the edge takes, beside the
// images and the gaze; a corrupted or forged event is skipped and counted; an
// existing output file is refused and left as it was; a truncated log exports
// what it holds; a keyed recording exports with its key; a log whose channels
// are interleaved anew exports the same messages at the same times, each at
// its step's place in the run; and the writer leaves
// nothing behind when it fails. The file is read back here by a small reader
// of the spec's records that checks the CRCs and the indexes (the independent
// check with Foxglove's reader is tests/mcap/test_mcap.sh).
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sodium.h>
#include <spdlog/sinks/null_sink.h>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "afford/auth.hpp"
#include "afford/decode.hpp"
#include "afford/image.hpp"
#include "afford/json_messages.hpp"
#include "afford/logfile.hpp"
#include "afford/protocol.hpp"
#include "afford/seal.hpp"
#include "experiment/export/export.hpp"
#include "experiment/export/mcap.hpp"
#include "experiment/replay/replay.hpp"
#include "tests/logorder/shuffle.hpp"
#include "tests/mcap/read_mcap.hpp"
#include "tests/support.hpp"

namespace afford {
namespace {

namespace fs = std::filesystem;

spdlog::logger& quiet() {
  static auto log = std::make_shared<spdlog::logger>("mcap-test", std::make_shared<spdlog::sinks::null_sink_mt>());
  return *log;
}

using testing::ReadMcap;
using testing::ReadMessage;
using testing::readMcap;

std::string fileText(const fs::path& f) { return testing::fileBytes(f); }

// ---- the image fields ----------------------------------------------------------------------
// Written as PNG (base64): these fields of these channels.
const std::map<std::string, std::vector<std::string>> kImageFields = {
    {"FOCUS", {"diff_image"}}, {"EFFECT", {"image"}}, {"FORWARD_QUERY", {"image"}}, {"GOAL", {"image"}},
    {"PROBE", {"images"}}};
// Written once, on an image topic at the message's time, which the field names: channel, field, topic.
struct Moved {
  std::string field, topic;
};
const std::map<std::string, Moved> kMovedFields = {{"SCENE", {"data", kSceneImageTopic}},
                                                   {"FOCUS", {"image", kFocusImageTopic}},
                                                   {"FORWARD_PREDICTION", {"what", kPredictionImageTopic}}};

std::string base64Of(const std::vector<std::uint8_t>& bytes) {
  std::string out(sodium_base64_encoded_len(bytes.size(), sodium_base64_VARIANT_ORIGINAL), '\0');
  sodium_bin2base64(out.data(), out.size(), bytes.data(), bytes.size(), sodium_base64_VARIANT_ORIGINAL);
  out.resize(out.size() - 1);  // (its terminating zero)
  return out;
}

std::vector<std::uint8_t> unbase64(const std::string& b64) {
  std::vector<std::uint8_t> bytes(b64.size());
  std::size_t n = 0;
  EXPECT_EQ(sodium_base642bin(bytes.data(), bytes.size(), b64.data(), b64.size(), nullptr, &n, nullptr,
                              sodium_base64_VARIANT_ORIGINAL), 0);
  bytes.resize(n);
  return bytes;
}

// A base64 PNG's pixels, RGB (empty for "").
cv::Mat pngPixels(const std::string& b64) {
  if (b64.empty()) return {};
  const std::vector<std::uint8_t> png = unbase64(b64);
  EXPECT_TRUE(png.size() > 8 && png[1] == 'P' && png[2] == 'N' && png[3] == 'G') << "not a PNG";
  cv::Mat bgr = cv::imdecode(png, cv::IMREAD_UNCHANGED), rgb;
  if (bgr.empty()) return bgr;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

std::vector<std::uint8_t> bytesOf(const cv::Mat& rgb) {
  if (rgb.empty()) return {};
  const cv::Mat whole = rgb.clone();  // (a column range of a strip is not continuous)
  return std::vector<std::uint8_t>(whole.data, whole.data + whole.total() * 3);
}

// A predicted pixel as the export writes it.
std::uint8_t predictedByte(double v) { return static_cast<std::uint8_t>(std::lround(static_cast<float>(v) * 255.0f)); }

// A message of the file with its images as base64 of their pixels: its PNGs, and its moved field's image from
// the image topic it names (FORWARD_PREDICTION.what's strip cut into one image per action).
nlohmann::json filePixels(const ReadMcap& file, const ReadMessage& msg) {
  nlohmann::json j = nlohmann::json::parse(msg.data);
  if (const auto fields = kImageFields.find(msg.topic); fields != kImageFields.end())
    for (const std::string& name : fields->second) {
      auto one = [](nlohmann::json& v) { v = base64Of(bytesOf(pngPixels(v.get<std::string>()))); };
      nlohmann::json& f = j.at(name);
      if (f.is_array())
        for (auto& v : f) one(v);
      else
        one(f);
    }
  if (const auto moved = kMovedFields.find(msg.topic); moved != kMovedFields.end()) {
    nlohmann::json& f = j.at(moved->second.field);
    if (f == "" && msg.topic == "FORWARD_PREDICTION") f = nlohmann::json::array();  // (no action: no image)
    if (f != moved->second.topic) return j;
    const ReadMessage* image = file.at(moved->second.topic, msg.log_time);
    if (!image) return j;  // (left naming the topic: not the log's)
    const cv::Mat pixels = pngPixels(nlohmann::json::parse(image->data).at("data").get<std::string>());
    if (msg.topic != "FORWARD_PREDICTION") {
      f = base64Of(bytesOf(pixels));
      return j;
    }
    f = nlohmann::json::array();
    for (int x = 0; x + pixels.rows <= pixels.cols; x += pixels.rows)
      f.push_back(base64Of(bytesOf(pixels.colRange(x, x + pixels.rows))));
  }
  return j;
}

// A message as the generated JSON has it with its images as base64 of their pixels: the scene's data decoded,
// the predictions (floats) as the export's bytes. The same JSON as filePixels' when the file holds the
// message's fields and pixels.
nlohmann::json logPixels(const std::string& channel, const std::string& text) {
  nlohmann::json j = nlohmann::json::parse(text);
  if (channel == "SCENE") {
    const cv::Mat rgb = decodeScene(unbase64(j.at("data").get<std::string>()), j.at("width"), j.at("height"));
    j["data"] = base64Of(bytesOf(rgb));
  }
  if (channel == "FORWARD_PREDICTION")
    for (auto& row : j.at("what")) {
      std::vector<std::uint8_t> bytes;
      for (const auto& x : row) bytes.push_back(predictedByte(x.get<double>()));
      row = base64Of(bytes);
    }
  return j;
}

// ---- the stored logs -------------------------------------------------------------------------

class Export : public ::testing::Test {
 protected:
  fs::path dir_ = test::tempDir("mcap");

  // A stored extrinsic test's log (tests/data/explain), unzipped.
  fs::path storedLog(const std::string& name = "base-scenario3") {
    const fs::path log = dir_ / (name + ".lcm");
    const fs::path gz = fs::path(AFFORD_SOURCE_DIR) / "tests" / "data" / "explain" / (name + ".lcm.gz");
    const auto unzip = test::runCommand("gzip -dc '" + gz.string() + "' > '" + log.string() + "'");
    EXPECT_EQ(unzip.exit_code, 0) << unzip.output;
    return log;
  }

  ExportResult exportLog(const fs::path& log, const std::string& name, const std::string& key = "") {
    ExportOptions o;
    o.log = log.string();
    o.mcap = (dir_ / name).string();
    o.bus_key = key;
    o.chunk_bytes = 64 << 10;  // several chunks of a small log
    return exportMcap(o, quiet());
  }

  // The messages of the log's run that the edge takes, decoded here, per channel: their JSON.
  static std::map<std::string, std::vector<std::string>> takenMessages(const fs::path& log) {
    RecordedLogStream in(log, quiet());
    RunSelector select("", log.string(), quiet());
    std::unique_ptr<RunConfig> config;
    std::map<std::string, std::vector<std::string>> out;
    for (LogEvent e; in.next(e);) {
      if (!select.take(e)) continue;
      if (!config) config = std::make_unique<RunConfig>(parseRunConfigText(select.config().config_yaml));
      withChannel(e.channel, [&](const auto& c) {
        typename std::decay_t<decltype(c)>::Message m;
        std::string why;
        if (decodeChecked(e.data.data(), e.data.size(), BoundsContext{&config->protocol, config.get()}, m, why))
          out[e.channel].push_back(json_messages::jsonText(m));
      });
    }
    return out;
  }
};

TEST_F(Export, AStoredLogHasOneMessagePerLogMessageTheEdgeTakesWithItsImagesAndGaze) {
  const fs::path log = storedLog();
  const ExportResult r = exportLog(log, "run.mcap");
  EXPECT_EQ(r.skipped, 0);
  EXPECT_EQ(r.malformed, 0);
  const ReadMcap m = readMcap(dir_ / "run.mcap");
  EXPECT_GT(m.chunks, 1);
  EXPECT_EQ(m.indexed, static_cast<std::int64_t>(m.messages.size()));
  EXPECT_EQ(m.statistics_messages, static_cast<std::int64_t>(m.messages.size()));
  EXPECT_EQ(r.messages, static_cast<std::int64_t>(m.messages.size()));
  EXPECT_EQ(m.library.rfind("afford ", 0), 0u) << m.library;
  EXPECT_NE(m.metadata_yaml.find("planner:"), std::string::npos);

  // Each channel's messages, in order, as the edge decodes them (their images' pixels); their times the log's.
  const auto taken = takenMessages(log);
  std::map<std::string, std::vector<nlohmann::json>> got, want;
  for (const ReadMessage& msg : m.messages) {
    EXPECT_EQ(msg.log_time, msg.publish_time);
    if (msg.topic[0] != '/') got[msg.topic].push_back(filePixels(m, msg));
  }
  for (const auto& [channel, messages] : taken)
    for (const std::string& text : messages) want[channel].push_back(logPixels(channel, text));
  EXPECT_EQ(got, want);
  for (const auto& [channel, messages] : taken) {
    SCOPED_TRACE(channel);
    const auto* info = channelNamed(channel);
    ASSERT_NE(info, nullptr);
    EXPECT_EQ(m.schema_of.at(channel), std::string("afford.") + info->type);
    // Every message is JSON of the fields of its type's schema.
    withChannel(channel, [&](const auto& c) {
      using Msg = typename std::decay_t<decltype(c)>::Message;
      const auto schema = nlohmann::json::parse(json_messages::Schema<Msg>::kText);
      const auto first = nlohmann::json::parse(messages.front());
      for (const auto& [field, s] : schema["properties"].items()) EXPECT_TRUE(first.contains(field)) << field;
      EXPECT_EQ(first.size(), schema["properties"].size());
    });
  }
  // A SCENE image per SCENE, a FOCUS image per FOCUS, a gaze per FOCUS and EFFECT (an extrinsic test has none).
  auto count = [&](const std::string& channel) {
    const auto it = taken.find(channel);
    return it == taken.end() ? std::int64_t{0} : static_cast<std::int64_t>(it->second.size());
  };
  EXPECT_EQ(m.per_topic.at(kSceneImageTopic), count("SCENE"));
  EXPECT_EQ(m.per_topic.at(kFocusImageTopic), count("FOCUS"));
  EXPECT_EQ(m.per_topic.at(kGazeTopic), count("FOCUS") + count("EFFECT"));
  EXPECT_EQ(m.schema_of.at(kSceneImageTopic), "foxglove.CompressedImage");
  EXPECT_EQ(m.schema_of.at(kGazeTopic), "foxglove.ImageAnnotations");
  for (const ReadMessage& msg : m.messages)
    if (msg.topic == kSceneImageTopic) {  // (its pixels are the scene's: compared above)
      const auto image = nlohmann::json::parse(msg.data);
      EXPECT_EQ(image["format"], "png");
      EXPECT_EQ(image["timestamp"]["sec"].get<std::uint64_t>() * 1000000000 + image["timestamp"]["nsec"].get<std::uint64_t>(),
                msg.log_time);
      break;
    }
}

// Each image once: a message whose image is on an image topic (SCENE, FOCUS, FORWARD_PREDICTION) names that
// topic, where an image of the same time is, in place of a copy of it (the scene's zlib stream, the focus
// image's PNG and the predictions' PNGs were all written beside the topics' PNGs); the chunks are compressed
// by zstd, and the file is a fraction of their records.
TEST_F(Export, EachImageIsWrittenOnceAndTheChunksAreCompressed) {
  const fs::path log = storedLog("multi-step-top-down-budget");
  const ExportResult r = exportLog(log, "once.mcap");
  const ReadMcap m = readMcap(dir_ / "once.mcap");
  EXPECT_EQ(m.compressions, std::set<std::string>{"zstd"});
  EXPECT_EQ(r.compression, "zstd");
  EXPECT_EQ(r.record_bytes, m.record_bytes);
  EXPECT_LT(r.bytes * 3, r.record_bytes);  // (this log: about a fifth)
  const auto taken = takenMessages(log);
  std::map<std::string, std::size_t> named, seen;
  for (const ReadMessage& msg : m.messages) {
    const auto moved = kMovedFields.find(msg.topic);
    if (moved == kMovedFields.end()) continue;
    SCOPED_TRACE(msg.topic + " " + std::to_string(seen[msg.topic]));
    const auto logged = nlohmann::json::parse(taken.at(msg.topic).at(seen[msg.topic]++));
    const nlohmann::json field = nlohmann::json::parse(msg.data).at(moved->second.field);
    const ReadMessage* image = m.at(moved->second.topic, msg.log_time);
    if (logged.at(moved->second.field).empty()) {  // (a prediction of no action: no image)
      EXPECT_EQ(field, "");
      EXPECT_EQ(image, nullptr);
      continue;
    }
    EXPECT_EQ(field, moved->second.topic);
    ASSERT_NE(image, nullptr);
    if (msg.topic == "SCENE") {
      EXPECT_EQ(msg.data.find(logged.at("data").get<std::string>()), std::string::npos) << "the zlib stream";
    }
    ++named[msg.topic];
  }
  EXPECT_GT(named["SCENE"], 0u);
  EXPECT_GT(named["FOCUS"], 0u);
  EXPECT_GT(named["FORWARD_PREDICTION"], 0u);
  // The schemas say where the images are.
  for (const auto& [channel, moved] : kMovedFields) {
    const auto schema = nlohmann::json::parse(m.schema_text.at(m.schema_of.at(channel)));
    EXPECT_EQ(schema["properties"][moved.field]["enum"], nlohmann::json::array({moved.topic, ""})) << channel;
  }
}

// The chunks left uncompressed on request (--compression none): the same messages at the same times; a
// compression the writer does not know is refused, naming it, before any file is made.
TEST_F(Export, TheChunksAreCompressedByZstdOrNotAtAll) {
  const fs::path log = storedLog("multi-step-top-down-budget");
  const ExportResult zstd = exportLog(log, "zstd.mcap");
  ExportOptions o;
  o.log = log.string();
  o.mcap = (dir_ / "none.mcap").string();
  o.chunk_bytes = 64 << 10;
  o.compression = "";
  const ExportResult none = exportMcap(o, quiet());
  const ReadMcap a = readMcap(dir_ / "zstd.mcap"), b = readMcap(dir_ / "none.mcap");
  EXPECT_EQ(b.compressions, std::set<std::string>{""});
  EXPECT_EQ(none.record_bytes, b.record_bytes);
  EXPECT_EQ(zstd.record_bytes, none.record_bytes);
  EXPECT_GT(none.bytes, none.record_bytes);
  ASSERT_EQ(a.messages.size(), b.messages.size());
  for (std::size_t i = 0; i < a.messages.size(); ++i) {
    EXPECT_EQ(a.messages[i].topic, b.messages[i].topic) << i;
    EXPECT_EQ(a.messages[i].log_time, b.messages[i].log_time) << i;
    EXPECT_EQ(a.messages[i].data, b.messages[i].data) << i;
  }
  try {
    McapWriter w(dir_ / "lz4.mcap", McapOptions{"", "afford test", 1 << 20, "lz4"});
    ADD_FAILURE() << "an unknown compression was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'lz4'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "lz4.mcap.partial"));
}

// The images of a test that imagines several steps ahead: every image field a PNG in its schema and in each
// message, a FORWARD_PREDICTION smaller than its predictions' floats, and its predicted images side by side on
// their own topic. (They were JSON numbers: a FORWARD_PREDICTION of three actions took about 60 KB.)
TEST_F(Export, ImageFieldsAreWrittenAsPngsAndThePredictionsAsAnImage) {
  const fs::path log = storedLog("multi-step-top-down-budget");
  exportLog(log, "images.mcap");
  const ReadMcap m = readMcap(dir_ / "images.mcap");
  for (const auto& [channel, names] : kImageFields) {
    if (!m.schema_of.count(channel)) continue;
    SCOPED_TRACE(channel);
    for (const ReadMessage& msg : m.messages)
      if (msg.topic == channel) {
        const auto j = nlohmann::json::parse(msg.data);
        for (const std::string& name : names)
          for (const auto& v : j.at(name).is_array() ? j.at(name) : nlohmann::json::array({j.at(name)}))
            EXPECT_TRUE(v.is_string() && (v == "" || pngPixels(v.get<std::string>()).cols == 21)) << name;
      }
  }
  const auto taken = takenMessages(log);
  const auto& predictions = taken.at("FORWARD_PREDICTION");
  ASSERT_EQ(m.per_topic.at(kPredictionImageTopic), static_cast<std::int64_t>(predictions.size()));
  EXPECT_EQ(m.schema_of.at(kPredictionImageTopic), "foxglove.CompressedImage");
  EXPECT_EQ(m.schema_of.at(kFocusImageTopic), "foxglove.CompressedImage");
  std::size_t k = 0, diffs = 0;
  for (const ReadMessage& msg : m.messages) {
    if (msg.topic == "FOCUS") diffs += nlohmann::json::parse(msg.data)["diff_image"].size();
    if (msg.topic == "FORWARD_PREDICTION") {
      const auto what = nlohmann::json::parse(predictions.at(k))["what"];
      EXPECT_LT(msg.data.size(), what.size() * what[0].size() * sizeof(float)) << "FORWARD_PREDICTION " << k;
    }
    if (msg.topic != kPredictionImageTopic) continue;
    const auto image = nlohmann::json::parse(msg.data);
    EXPECT_EQ(image["format"], "png");
    const cv::Mat strip = pngPixels(image["data"].get<std::string>());
    const auto what = nlohmann::json::parse(predictions.at(k++))["what"];
    ASSERT_EQ(strip.cols, 21 * static_cast<int>(what.size()));
    ASSERT_EQ(strip.rows, 21);
    std::size_t differ = 0;
    for (std::size_t a = 0; a < what.size(); ++a)  // action a's image in columns 21a to 21a + 20
      for (int i = 0; i < 21 * 21 * 3; ++i)
        differ += strip.at<cv::Vec3b>(i / 63, static_cast<int>(a) * 21 + i % 63 / 3)[i % 3] !=
                  predictedByte(what[a][static_cast<std::size_t>(i)].get<double>());
    EXPECT_EQ(differ, 0u) << "prediction image " << k;
  }
  EXPECT_GT(diffs, 0u);  // (the test's GOAL_DIFF looks: their images too)
}

// The log's channels interleaved anew, as the protocol allows a logger to record them, in two segments: the
// same messages in the same order at the same times, each in its step's millisecond after the run's RUN_CONFIG.
TEST_F(Export, AShuffledLogExportsTheSameMessagesEachAtItsStepsPlace) {
  const fs::path log = storedLog("multi-step-top-down-budget");
  const auto report = testing::shuffleLog(log, dir_ / "shuffled", {1000, 1, 2});
  EXPECT_GT(report.most_ahead, 50);
  exportLog(log, "recorded.mcap");
  exportLog(dir_ / "shuffled", "shuffled.mcap");
  const ReadMcap a = readMcap(dir_ / "recorded.mcap"), b = readMcap(dir_ / "shuffled.mcap");
  ASSERT_EQ(a.messages.size(), b.messages.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.messages.size(); ++i) {
    const ReadMessage &x = a.messages[i], &y = b.messages[i];
    differ += x.topic != y.topic || x.log_time != y.log_time || x.publish_time != y.publish_time || x.data != y.data;
  }
  EXPECT_EQ(differ, 0u) << "of " << a.messages.size();
  const std::uint64_t start = a.messages.front().log_time;  // the run's RUN_CONFIG
  std::uint64_t before = 0;
  for (const ReadMessage& m : a.messages) {
    EXPECT_GE(m.log_time, before) << m.topic;  // in step order
    before = m.log_time;
    if (m.topic[0] == '/' || m.topic == "RUN_CONFIG" || m.topic == "RUN_CONTROL") continue;
    const std::int64_t step = nlohmann::json::parse(m.data)["step"];
    EXPECT_EQ(static_cast<std::int64_t>((m.log_time - start) / 1000000) - 1, step) << m.topic;
  }
}

// Events of the run changed or made up in the log: each is skipped and counted, the rest exported. A scene
// whose pixels do not decode (its digest made anew: the edge takes it) is skipped whole: its message would
// name an image that is not there.
TEST_F(Export, ACorruptedOrForgedEventIsSkippedAndCounted) {
  const fs::path log = storedLog();
  const LogFileContents c = readLogFile(log, LogLimits{});
  const fs::path bad = dir_ / "bad.lcm";
  int focus = 0, scenes = 0;
  for (const LogEvent& e : c.events) scenes += e.channel == "SCENE";
  bool forged = false;
  {
    LogWriter w(bad);
    for (const LogEvent& e : c.events) {
      std::vector<std::uint8_t> data = e.data;
      if (e.channel == "FOCUS" && ++focus == 3) data[data.size() / 2] ^= 0x40;  // a changed byte: its digest fails
      if (e.channel == "SCENE" && --scenes == 0) {  // the last scene: a zlib stream that does not inflate
        scene_t s;
        ASSERT_GT(s.decode(data.data(), 0, static_cast<int>(data.size())), 0);
        std::fill(s.data.begin() + 2, s.data.end(), 0xff);
        data = sealed(s);
      }
      w.write(e.channel, data.data(), data.size(), e.utime);
      if (e.channel == "DECISION" && focus >= 3 && !forged) {  // a run message on a channel of no one's
        w.write("NOT_A_CHANNEL", e.data.data(), e.data.size(), e.utime);
        forged = true;
      }
    }
    w.close();
  }
  const ExportResult r = exportLog(bad, "bad.mcap");
  std::map<std::string, ExportedTopic> t;
  for (const ExportedTopic& x : r.topics) t[x.topic] = x;
  EXPECT_EQ(t.at("FOCUS").skipped, 1);
  EXPECT_NE(t.at("FOCUS").first_skipped.find("digest"), std::string::npos) << t.at("FOCUS").first_skipped;
  EXPECT_EQ(t.at("SCENE").skipped, 1);
  EXPECT_NE(t.at("SCENE").first_skipped.find("not a valid zlib stream"), std::string::npos)
      << t.at("SCENE").first_skipped;
  EXPECT_EQ(t.at("NOT_A_CHANNEL").skipped, 1);
  EXPECT_EQ(t.at("NOT_A_CHANNEL").messages, 0);
  EXPECT_EQ(r.skipped, 3);
  const ReadMcap m = readMcap(dir_ / "bad.mcap");
  const auto taken = takenMessages(log);
  EXPECT_EQ(m.per_topic.at("FOCUS"), static_cast<std::int64_t>(taken.at("FOCUS").size()) - 1);
  EXPECT_EQ(m.per_topic.at(kFocusImageTopic), static_cast<std::int64_t>(taken.at("FOCUS").size()) - 1);
  EXPECT_EQ(m.per_topic.at("SCENE"), static_cast<std::int64_t>(taken.at("SCENE").size()) - 1);
  EXPECT_EQ(m.per_topic.at(kSceneImageTopic), static_cast<std::int64_t>(taken.at("SCENE").size()) - 1);
  EXPECT_EQ(m.per_topic.count("NOT_A_CHANNEL"), 0u);
}

TEST_F(Export, AnExistingFileIsRefusedAndLeftAsItWas) {
  const fs::path log = storedLog();
  std::ofstream(dir_ / "taken.mcap") << "someone's file";
  try {
    exportLog(log, "taken.mcap");
    FAIL() << "an existing file was not refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("exists"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fileText(dir_ / "taken.mcap"), "someone's file");
  EXPECT_FALSE(fs::exists(dir_ / "taken.mcap.partial"));
  // A log with no run in it: nothing is left, neither the file nor its partial one.
  std::ofstream(dir_ / "empty.lcm") << "not a log";
  EXPECT_THROW(exportLog(dir_ / "empty.lcm", "none.mcap"), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir_ / "none.mcap"));
  EXPECT_FALSE(fs::exists(dir_ / "none.mcap.partial"));
}

TEST_F(Export, ATruncatedLogExportsWhatItHolds) {
  const fs::path log = storedLog("utility-goal-attempts");
  const auto size = fs::file_size(log);
  fs::resize_file(log, size * 2 / 3 + 7);  // in the middle of an event
  const ExportResult r = exportLog(log, "cut.mcap");
  EXPECT_GT(r.torn_bytes, 0);
  const ReadMcap m = readMcap(dir_ / "cut.mcap");
  std::int64_t taken = 0;
  for (const auto& [channel, messages] : takenMessages(log)) {
    taken += static_cast<std::int64_t>(messages.size());
    EXPECT_EQ(m.per_topic.at(channel), static_cast<std::int64_t>(messages.size())) << channel;
  }
  EXPECT_EQ(r.events, taken);
}

// An lcm-logger recording of a keyed bus: with its key, every tagged event; with another, none of them.
TEST_F(Export, AKeyedRecordingExportsWithItsKey) {
  const LogFileContents c = readLogFile(storedLog("utility-goal-attempts"), LogLimits{});
  BusKey::writeNew(dir_ / "bus.key");
  BusKey::writeNew(dir_ / "other.key");
  const BusKey key = BusKey::fromFile(dir_ / "bus.key");
  {
    LogWriter w(dir_ / "keyed.lcm");
    std::uint64_t n = 0;
    for (const LogEvent& e : c.events) {
      const auto tagged = key.tagged(e.channel, e.data.data(), e.data.size(), Stamp{7, n++, 0});
      w.write(e.channel, tagged.data(), tagged.size(), e.utime);
    }
    w.close();
  }
  const ExportResult r = exportLog(dir_ / "keyed.lcm", "keyed.mcap", (dir_ / "bus.key").string());
  EXPECT_EQ(r.events, static_cast<std::int64_t>(c.events.size()));
  EXPECT_EQ(r.skipped, 0);
  EXPECT_EQ(r.untagged, 0);
  EXPECT_THROW(exportLog(dir_ / "keyed.lcm", "other.mcap", (dir_ / "other.key").string()), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir_ / "other.mcap"));
}

// The writer alone: an empty file is valid; one destroyed unclosed leaves nothing.
TEST_F(Export, TheWriterLeavesNothingUnlessClosed) {
  {
    McapWriter w(dir_ / "empty.mcap", McapOptions{"", "afford test"});
    w.close();
  }
  const ReadMcap m = readMcap(dir_ / "empty.mcap");
  EXPECT_TRUE(m.messages.empty());
  EXPECT_EQ(m.statistics_messages, 0);
  {
    McapWriter w(dir_ / "unclosed.mcap", McapOptions{"", "afford test"});
    const auto ch = w.addChannel(w.addSchema("s", "jsonschema", "{}"), "t", "json");
    w.write(ch, 1, 1, "{}", 2);
    EXPECT_TRUE(fs::exists(dir_ / "unclosed.mcap.partial"));
  }
  EXPECT_FALSE(fs::exists(dir_ / "unclosed.mcap.partial"));
  EXPECT_FALSE(fs::exists(dir_ / "unclosed.mcap"));
  EXPECT_THROW(McapWriter(dir_ / "no-such-folder" / "x.mcap", McapOptions{}), std::runtime_error);
}

// What an export killed half-way left (FILE.partial, no writer holding it) is taken over by the next export of
// FILE; a partial file another writer holds (a live export) is refused, naming it. (The partial file was made
// with O_EXCL: one left by a killed export refused every later one until someone removed it.)
TEST_F(Export, APartialFileOfAWriterGoneIsTakenOverAndOneInUseIsRefused) {
  const fs::path log = storedLog();
  std::ofstream(dir_ / "killed.mcap.partial") << "half an export";  // its writer killed: nobody holds it
  const ExportResult r = exportLog(log, "killed.mcap");
  EXPECT_GT(r.events, 0);
  EXPECT_FALSE(fs::exists(dir_ / "killed.mcap.partial"));
  EXPECT_GT(readMcap(dir_ / "killed.mcap").messages.size(), 0u);
  {
    McapWriter live(dir_ / "busy.mcap", McapOptions{"", "afford test"});  // a writer at work on busy.mcap
    try {
      exportLog(log, "busy.mcap");
      ADD_FAILURE() << "a second export of a file being written was not refused";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("busy.mcap.partial is being written by another afford export"),
                std::string::npos)
          << e.what();
    }
    EXPECT_TRUE(fs::exists(dir_ / "busy.mcap.partial"));  // the live writer's file is left to it
  }
}

// The generated conversion: int64_t exact at its extremes, bytes as base64, a value that is not finite as null.
TEST(JsonMessages, IntegersAreExactBytesBase64AndNoInvalidJson) {
  scene_t s{};
  s.digest = INT64_MIN;
  s.serial = INT64_MAX;
  s.size = 4;
  s.data = {0xff, 0x00, 0x10, 0x80};
  s.goal_distance = std::numeric_limits<double>::infinity();
  s.run_id = "r\xff";
  const std::string text = json_messages::jsonText(s);
  EXPECT_NE(text.find("\"digest\":-9223372036854775808"), std::string::npos) << text;
  EXPECT_NE(text.find("\"serial\":9223372036854775807"), std::string::npos) << text;
  EXPECT_NE(text.find("\"data\":\"/wAQgA==\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"goal_distance\":null"), std::string::npos) << text;
  EXPECT_NE(text.find("\"run_id\":\"r\xef\xbf\xbd\""), std::string::npos) << text;  // U+FFFD
  EXPECT_NO_THROW(nlohmann::json::parse(text));
  const std::vector<std::uint8_t> abcd = {'a', 'b', 'c', 'd'};
  const char* want[] = {"\"\"", "\"YQ==\"", "\"YWI=\"", "\"YWJj\"", "\"YWJjZA==\"", "\"YWJjZA==\""};
  for (int n = 0; n < 6; ++n) {  // (no more than it holds)
    std::string o;
    json_messages::base64(o, abcd, n);
    EXPECT_EQ(o, want[n]) << n;
  }
  const auto schema = nlohmann::json::parse(json_messages::Schema<scene_t>::kText);
  EXPECT_EQ(schema["properties"]["data"]["contentEncoding"], "base64");
  EXPECT_EQ(schema["properties"]["digest"]["type"], "integer");
  EXPECT_EQ(schema["properties"]["object_x"]["type"], "array");
  EXPECT_EQ(schema["required"].size(), schema["properties"].size());
}

}  // namespace
}  // namespace afford

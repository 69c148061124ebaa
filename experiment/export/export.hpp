// `afford export LOG --mcap FILE`: a recorded run as an MCAP file
// (https://mcap.dev/spec) that Foxglove, PlotJuggler and Rerun open. The log is
// read as replay reads it (experiment/replay/replay.hpp: the project's log
// reader, the run's RUN_CONFIG first, then that run's events; with a bus key,
// only events with a valid tag), its messages taken in step order
// (viewer/step_order.hpp), and each message is decoded and checked as the edge
// does (afford/decode.hpp) with the run's own configuration: one that does not
// decode or that the edge refuses is skipped and counted per channel, and so
// is a malformed part of the file. The file is a function of the log's
// messages, not of how the log interleaves its channels.
//
// Every channel of the run becomes an MCAP channel of its own name, message
// encoding "json", its schema the type's JSON Schema ("afford.<type>",
// encoding "jsonschema"), generated from the .lcm files by afford-lcmwire
// (afford/json_messages.hpp), its image fields as PNG, each image once: a field
// whose pixels are on an image topic names that topic (image_fields.hpp). A
// message's log_time and publish_time are both its place in the run: the log's
// time of the run's RUN_CONFIG, plus a millisecond a step and a microsecond for
// each message of its step before it.
// Beside them, in Foxglove's own schemas (foxglove.hpp), as
// foxglove.CompressedImage (PNG): each SCENE's image on /SCENE/image, each FOCUS
// image on /FOCUS/image, each FORWARD_PREDICTION's predicted images side by side
// on /FORWARD_PREDICTION/what; and the eye's gaze on /SCENE/gaze
// (foxglove.ImageAnnotations: the focus window's square over the scene, from
// each FOCUS, and from each EFFECT's gaze after the action). A Metadata record "afford" holds the run's configuration
// and afford's version. The chunks are compressed by zstd (or not, on request);
// the file is written whole or not at all (mcap.hpp).
#pragma once
#include <spdlog/spdlog.h>

#include <cstdint>
#include <string>
#include <vector>

#include "afford/phase.hpp"

namespace afford {

struct ExportOptions {
  std::string log;                      // a run's log folder (logs/<run-id>) or one .lcm file
  std::string mcap;                     // the file to write: a new one
  std::string run_id;                   // the run to export in a log of several (default: the first)
  std::string bus_key;                  // key file: the log is a recording of a keyed bus (tags checked, taken off)
  std::uint64_t chunk_bytes = 1 << 20;  // MCAP chunks of about this size (of records, uncompressed)
  std::string compression = "zstd";     // the chunks' compression: "zstd" or "" (none; mcap.hpp)
};

// The image topics written beside the channels.
inline constexpr const char* kSceneImageTopic = "/SCENE/image";
inline constexpr const char* kFocusImageTopic = "/FOCUS/image";
inline constexpr const char* kPredictionImageTopic = "/FORWARD_PREDICTION/what";
inline constexpr const char* kGazeTopic = "/SCENE/gaze";

struct ExportedTopic {
  std::string topic;          // an LCM channel of the run, or one of the image topics
  std::string schema;         // "afford.scene_t", "foxglove.CompressedImage", ... ("" for a channel not in the protocol)
  std::int64_t messages = 0;  // written
  std::int64_t skipped = 0;   // events that do not decode or that the edge refuses, not written
  std::string first_skipped;  // why the first was skipped
};

struct ExportResult {
  std::string run_id;
  Phase phase = Phase::Intrinsic;
  std::string file;                  // the MCAP file written
  std::vector<ExportedTopic> topics;  // the run's channels in the order they first come, then the image topics
  std::int64_t events = 0;           // the run's events in the log
  std::int64_t messages = 0;         // written, the images' included
  std::int64_t skipped = 0;          // events skipped (the topics' counts summed)
  std::int64_t left_out = 0;         // events before the run's RUN_CONFIG or of other runs (not the run's)
  std::int64_t torn_bytes = 0;       // an incomplete last event (a writer killed mid-write)
  std::int64_t malformed = 0;        // malformed parts of the log file skipped (named with their offsets)
  std::int64_t refused_configs = 0;  // RUN_CONFIG events the edge refuses, skipped
  std::int64_t untagged = 0;         // with a bus key: events without a valid tag of it, skipped
  std::string incomplete;            // the manifest's reason, when it says the log is incomplete
  std::vector<std::string> cut;      // what the log lacks of the run, when it is cut short (replay/log_cut.hpp)
  std::uint64_t bytes = 0, chunks = 0;
  std::string compression;         // the chunks' ("" none)
  std::uint64_t record_bytes = 0;  // the chunks' records, uncompressed
};

// Throws std::runtime_error naming what is wrong (no log, no run in it, FILE
// exists, a write that fails); nothing is then left under FILE's name.
ExportResult exportMcap(const ExportOptions& options, spdlog::logger& log);

}  // namespace afford

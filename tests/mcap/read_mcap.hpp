// A small reader of the MCAP records afford export writes (https://mcap.dev/spec), for the unit tests
// (tests/unit/test_mcap.cpp): every record of the data section and the summary, the chunks decompressed (zstd)
// and their CRCs, the data section's and the summary's CRCs checked, the messages in file order. (The
// independent check with Foxglove's reader is tools/mcapcheck, run by tests/mcap/test_mcap.sh.)
#pragma once
#include <gtest/gtest.h>
#include <zlib.h>
#include <zstd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace afford::testing {

struct ReadMessage {
  std::string topic;
  std::uint64_t log_time = 0, publish_time = 0;
  std::string data;
};

struct ReadMcap {
  std::vector<ReadMessage> messages;  // in file order
  std::map<std::string, std::int64_t> per_topic;
  std::map<std::string, std::string> schema_of;  // topic: schema name
  std::map<std::string, std::string> schema_text;  // schema name: its JSON Schema
  std::string library, metadata_yaml;
  std::int64_t chunks = 0, indexed = 0, statistics_messages = -1;
  std::set<std::string> compressions;  // the chunks' ("" none)
  std::uint64_t record_bytes = 0;      // the chunks' records, uncompressed
  std::map<std::pair<std::string, std::uint64_t>, std::size_t> placed;  // (topic, log time): its message

  // The message on `topic` at `log_time` (an image topic's at its channel message's time), or null.
  const ReadMessage* at(const std::string& topic, std::uint64_t log_time) const {
    const auto it = placed.find({topic, log_time});
    return it == placed.end() ? nullptr : &messages[it->second];
  }
};

inline std::string fileBytes(const std::filesystem::path& f) {
  std::ifstream in(f, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline std::uint64_t le(const std::string& b, std::size_t at, int n) {
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = (v << 8) | static_cast<std::uint8_t>(b.at(at + i));
  return v;
}

inline std::string str(const std::string& b, std::size_t& at) {
  const std::size_t n = le(b, at, 4);
  std::string s = b.substr(at + 4, n);
  at += 4 + n;
  return s;
}

inline std::uint32_t crcOf(const std::string& b, std::size_t from, std::size_t to) {
  return static_cast<std::uint32_t>(
      crc32(0, reinterpret_cast<const Bytef*>(b.data() + from), static_cast<uInt>(to - from)));
}

// A chunk's records (at `at`, `size` bytes in the file) as they were before `compression`.
inline std::string chunkRecords(const std::string& b, std::size_t at, std::size_t size, const std::string& compression,
                                std::size_t uncompressed) {
  if (compression.empty()) return b.substr(at, size);
  EXPECT_EQ(compression, "zstd");
  std::string out(uncompressed, '\0');
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), b.data() + at, size);
  EXPECT_FALSE(ZSTD_isError(n)) << ZSTD_getErrorName(n);
  EXPECT_EQ(n, uncompressed) << "a chunk's uncompressed_size";
  return out;
}

// The records of b[from, to): schemas, channels and messages (a chunk's too, its CRC checked).
inline void readRecords(const std::string& b, std::size_t from, std::size_t to, ReadMcap& out,
                        std::map<std::uint64_t, std::string>& schemas, std::map<std::uint64_t, std::string>& topics) {
  for (std::size_t at = from; at < to;) {
    const int op = static_cast<std::uint8_t>(b.at(at));
    const std::size_t len = le(b, at + 1, 8), c = at + 9;
    std::size_t p = c;
    if (op == 0x03) {
      const std::uint64_t id = le(b, p, 2);
      p += 2;
      schemas[id] = str(b, p);
      str(b, p);  // (its encoding)
      out.schema_text[schemas[id]] = str(b, p);
    } else if (op == 0x04) {
      const std::uint64_t id = le(b, p, 2), schema = le(b, p + 2, 2);
      p += 4;
      topics[id] = str(b, p);
      out.schema_of[topics[id]] = schemas.at(schema);
    } else if (op == 0x05) {
      ReadMessage m{topics.at(le(b, c, 2)), le(b, c + 6, 8), le(b, c + 14, 8), b.substr(c + 22, len - 22)};
      ++out.per_topic[m.topic];
      out.placed[{m.topic, m.log_time}] = out.messages.size();
      out.messages.push_back(std::move(m));
    } else if (op == 0x06) {
      p += 8 + 8;
      const std::size_t size = le(b, p, 8);
      const std::uint32_t crc = le(b, p + 8, 4);
      p += 12;
      const std::string compression = str(b, p);
      out.compressions.insert(compression);
      const std::string records = chunkRecords(b, p + 8, le(b, p, 8), compression, size);
      EXPECT_EQ(crcOf(records, 0, records.size()), crc) << "chunk CRC";
      out.record_bytes += records.size();
      readRecords(records, 0, records.size(), out, schemas, topics);
      ++out.chunks;
    } else if (op == 0x07) {
      out.indexed += le(b, c + 2, 4) / 16;
    } else if (op == 0x0C) {
      EXPECT_EQ(str(b, p), "afford");
      const std::size_t end = p + 4 + le(b, p, 4);
      for (p += 4; p < end;) {
        const std::string k = str(b, p), v = str(b, p);
        if (k == "config_yaml") out.metadata_yaml = v;
      }
    } else if (op == 0x0B) {
      out.statistics_messages = static_cast<std::int64_t>(le(b, c, 8));
    } else if (op == 0x01) {
      str(b, p);
      out.library = str(b, p);
    }
    at = c + len;
  }
}

inline ReadMcap readMcap(const std::filesystem::path& f) {
  const std::string b = fileBytes(f);
  const std::string magic("\x89MCAP0\r\n", 8);
  EXPECT_EQ(b.substr(0, 8), magic);
  EXPECT_EQ(b.substr(b.size() - 8), magic);
  const std::size_t footer = b.size() - 8 - 29;
  EXPECT_EQ(b.at(footer), '\x02');
  const std::size_t summary = le(b, footer + 9, 8), data_end = summary - 13;
  EXPECT_EQ(b.at(data_end), '\x0f');
  EXPECT_EQ(crcOf(b, 0, data_end), le(b, data_end + 9, 4)) << "data section CRC";
  EXPECT_EQ(crcOf(b, summary, footer + 25), le(b, footer + 25, 4)) << "summary CRC";
  ReadMcap out;
  std::map<std::uint64_t, std::string> schemas, topics;
  readRecords(b, 8, data_end, out, schemas, topics);
  std::map<std::uint64_t, std::string> summary_schemas, summary_topics;
  ReadMcap summary_part;
  readRecords(b, summary, footer, summary_part, summary_schemas, summary_topics);
  out.statistics_messages = summary_part.statistics_messages;
  EXPECT_EQ(summary_topics, topics);
  return out;
}

}  // namespace afford::testing

// An MCAP file (https://mcap.dev/spec, major version 0) written from start to
// end, for `afford export` (export.hpp): the magic, the Header, then the data
// section: the Metadata records, and the Schema, Channel and Message records in
// Chunks of about `chunk_bytes` of records each (a schema and a channel go into
// the chunk of their first use), compressed by zstd or not at all, each Chunk
// with the CRC of its uncompressed records and followed by
// one MessageIndex record per channel it holds; then DataEnd with the CRC of
// the data section (every byte before DataEnd, the magic and the Header
// included, as Foxglove's own writers count it). Then the summary section:
// the Schemas, the Channels, the Statistics, the MetadataIndexes and the
// ChunkIndexes, each group with its SummaryOffset record after the summary;
// the Footer with the summary's CRC, and the magic again. Little-endian, as the
// spec says; the CRCs are zlib's CRC-32.
//
// The file is written as FILE.partial and renamed to FILE when it is whole: a
// reader never sees half a file under FILE's name. An existing FILE (or
// FILE.partial) is refused, never overwritten; a writer destroyed before
// close() (an error on the way) removes its partial file.
#pragma once
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "afford/file_lock.hpp"

struct ZSTD_CCtx_s;  // zstd.h's compression context

namespace afford {

struct McapOptions {
  std::string profile;                       // the Header's profile ("": none of the well-known ones)
  std::string library;                       // the Header's library ("afford <version>")
  std::uint64_t chunk_bytes = 1 << 20;       // a chunk is closed once its records reach this many bytes
  std::string compression = "zstd";          // the chunks' compression: "zstd" or "" (none)
};

// The chunk compressions McapWriter writes (McapOptions::compression).
inline constexpr const char* kMcapCompressions[] = {"zstd", ""};

// A Map<string, string> of the spec, in key order.
using McapMap = std::map<std::string, std::string>;

class McapWriter {
 public:
  // Throws std::runtime_error naming the file when it exists, or when FILE.partial cannot be created;
  // std::invalid_argument naming a compression not in kMcapCompressions.
  McapWriter(const std::filesystem::path& file, McapOptions options);
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // A schema (its id, from 1); written with the first channel that uses it.
  std::uint16_t addSchema(const std::string& name, const std::string& encoding, const std::string& data);
  // A channel (its id, from 0) of a schema given by addSchema; written into the open chunk.
  std::uint16_t addChannel(std::uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                           const McapMap& metadata = {});
  // A Metadata record, written at once (between chunks).
  void addMetadata(const std::string& name, const McapMap& entries);
  // A message of a channel; its sequence is the count of the channel's earlier messages. Times in nanoseconds.
  void write(std::uint16_t channel_id, std::uint64_t log_time, std::uint64_t publish_time, const void* data,
             std::size_t size);
  // The rest of the file, then FILE.partial renamed to FILE (refused if FILE appeared meanwhile).
  // Throws std::runtime_error naming the file and why; the partial file is then removed.
  void close();

  const std::filesystem::path& file() const { return file_; }
  std::uint64_t messages() const { return message_count_; }
  std::uint64_t chunks() const { return chunk_indexes_.size(); }
  std::uint64_t chunkRecordBytes() const { return chunk_record_bytes_; }  // the chunks' records, uncompressed
  std::uint64_t bytes() const { return offset_; }  // written so far (all of it, once closed)
  static std::filesystem::path partialOf(const std::filesystem::path& file);

 private:
  struct Schema {
    std::string name, encoding, data;
    bool written = false;
  };
  struct Channel {
    std::uint16_t schema_id = 0;
    std::string topic, encoding;
    McapMap metadata;
    std::uint64_t messages = 0;
  };
  struct ChunkIndex {
    std::uint64_t start_time = 0, end_time = 0, offset = 0, length = 0, index_length = 0;
    std::uint64_t compressed = 0, uncompressed = 0;  // the records' bytes
    std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;  // channel -> its MessageIndex
  };
  struct MetadataIndex {
    std::uint64_t offset = 0, length = 0;
    std::string name;
  };

  struct FreeZstd {
    void operator()(ZSTD_CCtx_s* context) const;
  };

  void emit(const std::string& bytes);  // to the file, counted in the open section's CRC
  void flushChunk();
  void writeSummary();
  void fail(const std::string& what) const;  // throws, naming the partial file and errno

  std::filesystem::path file_, partial_;
  McapOptions options_;
  HeldFile held_;  // the partial file's lock, while it is written
  std::FILE* f_ = nullptr;
  bool closed_ = false;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;  // of the data section so far
  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  // The open chunk: its records, their times, and each channel's (log time, offset) entries.
  std::string chunk_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0, chunk_messages_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_entries_;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<MetadataIndex> metadata_indexes_;
  std::uint64_t message_count_ = 0, start_time_ = 0, end_time_ = 0, chunk_record_bytes_ = 0;
  std::unique_ptr<ZSTD_CCtx_s, FreeZstd> zstd_;  // the compression context, kept from chunk to chunk
  std::string compressed_;            // a chunk's records compressed
};

}  // namespace afford

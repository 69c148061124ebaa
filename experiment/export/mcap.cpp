#include "experiment/export/mcap.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <stdexcept>

namespace afford {
namespace fs = std::filesystem;

namespace {

constexpr char kMagic[] = "\x89MCAP0\r\n";  // 8 bytes (the terminating zero aside)
constexpr std::size_t kMagicBytes = 8;

// The opcodes of the records written.
enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Little-endian fields appended to a byte string.
struct Bytes {
  std::string b;
  Bytes& u8(std::uint8_t v) {
    b += static_cast<char>(v);
    return *this;
  }
  Bytes& le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i, v >>= 8) b += static_cast<char>(v & 0xff);
    return *this;
  }
  Bytes& u16(std::uint64_t v) { return le(v, 2); }
  Bytes& u32(std::uint64_t v) { return le(v, 4); }
  Bytes& u64(std::uint64_t v) { return le(v, 8); }
  Bytes& raw(const std::string& s) {
    b += s;
    return *this;
  }
  Bytes& str(const std::string& s) { return u32(s.size()).raw(s); }  // String (and uint32-prefixed Bytes)
  Bytes& map(const McapMap& m) {
    Bytes entries;
    for (const auto& [k, v] : m) entries.str(k).str(v);
    return u32(entries.b.size()).raw(entries.b);
  }
};

// <opcode><uint64 length><content>
std::string record(Op op, const Bytes& content) {
  Bytes r;
  r.u8(op).u64(content.b.size()).raw(content.b);
  return std::move(r.b);
}

std::uint32_t crc(std::uint32_t so_far, const std::string& bytes) {
  // (zlib takes at most 4 GB at a time; a record is far smaller)
  return static_cast<std::uint32_t>(
      crc32(so_far, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

// zstd's level for the chunks: its default, about 190 MB/s here (docs/performance.md, "Each image once, and
// zstd chunks").
constexpr int kZstdLevel = 3;

}  // namespace

void McapWriter::FreeZstd::operator()(ZSTD_CCtx_s* context) const { ZSTD_freeCCtx(context); }

fs::path McapWriter::partialOf(const fs::path& file) { return fs::path(file.string() + ".partial"); }

McapWriter::McapWriter(const fs::path& file, McapOptions options)
    : file_(file), partial_(partialOf(file)), options_(std::move(options)) {
  if (std::find(std::begin(kMcapCompressions), std::end(kMcapCompressions), options_.compression) ==
      std::end(kMcapCompressions))
    throw std::invalid_argument("MCAP chunk compression '" + options_.compression + "' is not one of zstd, none");
  if (options_.compression == "zstd") {
    zstd_.reset(ZSTD_createCCtx());
    if (!zstd_ || ZSTD_isError(ZSTD_CCtx_setParameter(zstd_.get(), ZSTD_c_compressionLevel, kZstdLevel)))
      throw std::runtime_error("zstd cannot start a compression context");
  }
  std::error_code ec;
  if (fs::exists(fs::symlink_status(file_, ec)))
    throw std::runtime_error(file_.string() + " exists: afford export writes a new file, never over one");
  // Held while it is written (a kernel lock): an export killed half-way leaves a partial file the next one takes
  // over, and two exports of one file at once are refused, naming it.
  holdPartial(held_, partial_.string(), "afford export");
  const int fd = ::dup(held_.fd());
  f_ = fd < 0 ? nullptr : ::fdopen(fd, "wb");
  if (!f_) {
    ::close(fd);
    ::unlink(partial_.c_str());
    throw std::runtime_error("cannot open " + partial_.string() + ": " + std::strerror(errno));
  }
  std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
  Bytes header;
  header.str(options_.profile).str(options_.library);
  emit(std::string(kMagic, kMagicBytes) + record(kHeader, header));
}

McapWriter::~McapWriter() {
  if (f_) std::fclose(f_);
  if (!closed_) ::unlink(partial_.c_str());
}

void McapWriter::fail(const std::string& what) const {
  throw std::runtime_error("cannot " + what + " " + partial_.string() + ": " + std::strerror(errno));
}

void McapWriter::emit(const std::string& bytes) {
  if (!f_) throw std::runtime_error(partial_.string() + " is closed");
  if (std::fwrite(bytes.data(), 1, bytes.size(), f_) != bytes.size()) fail("write to");
  data_crc_ = crc(data_crc_, bytes);
  offset_ += bytes.size();
}

std::uint16_t McapWriter::addSchema(const std::string& name, const std::string& encoding, const std::string& data) {
  if (schemas_.size() >= 0xffff) throw std::runtime_error(file_.string() + ": more schemas than MCAP numbers");
  schemas_.push_back({name, encoding, data});
  return static_cast<std::uint16_t>(schemas_.size());
}

std::uint16_t McapWriter::addChannel(std::uint16_t schema_id, const std::string& topic,
                                     const std::string& message_encoding, const McapMap& metadata) {
  if (schema_id == 0 || schema_id > schemas_.size())
    throw std::logic_error("McapWriter::addChannel: no schema " + std::to_string(schema_id));
  if (channels_.size() >= 0xffff) throw std::runtime_error(file_.string() + ": more channels than MCAP numbers");
  Schema& s = schemas_[schema_id - 1];
  if (!s.written) {
    Bytes b;
    b.u16(schema_id).str(s.name).str(s.encoding).str(s.data);
    chunk_ += record(kSchema, b);
    s.written = true;
  }
  const auto id = static_cast<std::uint16_t>(channels_.size());
  channels_.push_back({schema_id, topic, message_encoding, metadata});
  Bytes b;
  b.u16(id).u16(schema_id).str(topic).str(message_encoding).map(metadata);
  chunk_ += record(kChannel, b);
  return id;
}

void McapWriter::addMetadata(const std::string& name, const McapMap& entries) {
  Bytes b;
  b.str(name).map(entries);
  const std::string r = record(kMetadata, b);
  metadata_indexes_.push_back({offset_, r.size(), name});
  emit(r);
}

void McapWriter::write(std::uint16_t channel_id, std::uint64_t log_time, std::uint64_t publish_time,
                       const void* data, std::size_t size) {
  if (channel_id >= channels_.size())
    throw std::logic_error("McapWriter::write: no channel " + std::to_string(channel_id));
  Channel& c = channels_[channel_id];
  chunk_entries_[channel_id].emplace_back(log_time, chunk_.size());
  Bytes head;  // the record up to its data, which is appended as it is
  head.u8(kMessage).u64(2 + 4 + 8 + 8 + size);
  head.u16(channel_id).u32(c.messages & 0xffffffffu).u64(log_time).u64(publish_time);
  chunk_ += head.b;
  chunk_.append(static_cast<const char*>(data), size);
  ++c.messages;
  chunk_start_ = chunk_messages_ ? std::min(chunk_start_, log_time) : log_time;
  chunk_end_ = chunk_messages_ ? std::max(chunk_end_, log_time) : log_time;
  ++chunk_messages_;
  start_time_ = message_count_ ? std::min(start_time_, log_time) : log_time;
  end_time_ = message_count_ ? std::max(end_time_, log_time) : log_time;
  ++message_count_;
  if (chunk_.size() >= options_.chunk_bytes) flushChunk();
}

void McapWriter::flushChunk() {
  if (chunk_messages_ == 0) return;
  ChunkIndex index;
  index.start_time = chunk_start_;
  index.end_time = chunk_end_;
  index.offset = offset_;
  index.uncompressed = chunk_.size();
  const std::string* records = &chunk_;
  if (zstd_) {
    compressed_.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t n = ZSTD_compress2(zstd_.get(), compressed_.data(), compressed_.size(), chunk_.data(), chunk_.size());
    if (ZSTD_isError(n)) throw std::runtime_error("zstd cannot compress a chunk of " + partial_.string() + ": " +
                                                  ZSTD_getErrorName(n));
    compressed_.resize(n);
    records = &compressed_;
  }
  index.compressed = records->size();
  chunk_record_bytes_ += chunk_.size();
  Bytes chunk;
  chunk.u64(chunk_start_).u64(chunk_end_).u64(chunk_.size()).u32(crc(0, chunk_)).str(options_.compression);
  chunk.u64(records->size()).raw(*records);
  const std::string r = record(kChunk, chunk);
  index.length = r.size();
  emit(r);
  // One MessageIndex per channel of the chunk, its entries by log time (in record order at equal times).
  const std::uint64_t indexes_start = offset_;
  for (auto& [channel, entries] : chunk_entries_) {
    std::stable_sort(entries.begin(), entries.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    Bytes b;
    b.u16(channel).u32(entries.size() * 16);
    for (const auto& [time, at] : entries) b.u64(time).u64(at);
    index.index_offsets.emplace_back(channel, offset_);
    emit(record(kMessageIndex, b));
  }
  index.index_length = offset_ - indexes_start;
  chunk_indexes_.push_back(std::move(index));
  chunk_.clear();
  chunk_entries_.clear();
  chunk_messages_ = 0;
}

void McapWriter::writeSummary() {
  const std::uint64_t summary_start = offset_;
  data_crc_ = 0;  // from here on: the summary's CRC
  std::vector<std::pair<Op, std::pair<std::uint64_t, std::uint64_t>>> groups;  // opcode: start, length
  auto group = [&](Op op, const std::vector<std::string>& records) {
    if (records.empty()) return;
    const std::uint64_t start = offset_;
    for (const std::string& r : records) emit(r);
    groups.push_back({op, {start, offset_ - start}});
  };
  std::vector<std::string> records;
  for (std::size_t i = 0; i < schemas_.size(); ++i)
    if (schemas_[i].written)
      records.push_back(record(kSchema, Bytes().u16(i + 1).str(schemas_[i].name).str(schemas_[i].encoding)
                                            .str(schemas_[i].data)));
  group(kSchema, std::exchange(records, {}));
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    const Channel& c = channels_[i];
    records.push_back(record(kChannel, Bytes().u16(i).u16(c.schema_id).str(c.topic).str(c.encoding).map(c.metadata)));
  }
  group(kChannel, std::exchange(records, {}));
  Bytes stats;
  const auto written = std::count_if(schemas_.begin(), schemas_.end(), [](const Schema& s) { return s.written; });
  stats.u64(message_count_).u16(written).u32(channels_.size()).u32(0).u32(metadata_indexes_.size());
  stats.u32(chunk_indexes_.size()).u64(start_time_).u64(end_time_);
  Bytes counts;
  for (std::size_t i = 0; i < channels_.size(); ++i) counts.u16(i).u64(channels_[i].messages);
  stats.u32(counts.b.size()).raw(counts.b);
  group(kStatistics, {record(kStatistics, stats)});
  for (const MetadataIndex& m : metadata_indexes_)
    records.push_back(record(kMetadataIndex, Bytes().u64(m.offset).u64(m.length).str(m.name)));
  group(kMetadataIndex, std::exchange(records, {}));
  for (const ChunkIndex& c : chunk_indexes_) {
    Bytes b, offsets;
    for (const auto& [channel, at] : c.index_offsets) offsets.u16(channel).u64(at);
    b.u64(c.start_time).u64(c.end_time).u64(c.offset).u64(c.length).u32(offsets.b.size()).raw(offsets.b);
    b.u64(c.index_length).str(options_.compression).u64(c.compressed).u64(c.uncompressed);
    records.push_back(record(kChunkIndex, b));
  }
  group(kChunkIndex, std::exchange(records, {}));
  const std::uint64_t offsets_start = offset_;
  for (const auto& [op, where] : groups)
    emit(record(kSummaryOffset, Bytes().u8(op).u64(where.first).u64(where.second)));
  // The Footer: its CRC covers the summary and the footer up to the CRC itself.
  Bytes footer;
  footer.u8(kFooter).u64(8 + 8 + 4).u64(summary_start).u64(offsets_start);
  const std::uint32_t summary_crc = crc(data_crc_, footer.b);
  footer.u32(summary_crc);
  emit(footer.b + std::string(kMagic, kMagicBytes));
}

void McapWriter::close() {
  if (closed_) return;
  // The open chunk; a chunk of schemas and channels alone (no message came on them) as bare records.
  if (chunk_messages_) flushChunk();
  if (!chunk_.empty()) emit(std::exchange(chunk_, {}));
  emit(record(kDataEnd, Bytes().u32(data_crc_)));
  writeSummary();
  if (std::fflush(f_) != 0 || ::fsync(::fileno(f_)) != 0) fail("write to");
  const int closed = std::fclose(f_);
  f_ = nullptr;
  if (closed != 0) fail("close");
  held_.release();
  int renamed = ::renameat2(AT_FDCWD, partial_.c_str(), AT_FDCWD, file_.c_str(), RENAME_NOREPLACE);
  if (renamed != 0 && (errno == EINVAL || errno == ENOSYS)) {
    // A file system without RENAME_NOREPLACE: look, then rename.
    std::error_code ec;
    errno = EEXIST;
    renamed = fs::exists(fs::symlink_status(file_, ec)) ? -1 : std::rename(partial_.c_str(), file_.c_str());
  }
  if (renamed != 0) {
    const int err = errno;
    if (err == EEXIST)
      throw std::runtime_error(file_.string() + " appeared while it was written: left as it is (" +
                               partial_.string() + " removed)");
    throw std::runtime_error("cannot rename " + partial_.string() + " to " + file_.string() + ": " +
                             std::strerror(err));
  }
  closed_ = true;
}

}  // namespace afford

#include "afford/logfile.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace afford {

namespace {

constexpr std::uint32_t kSync = 0xEDA1DA01u;
constexpr std::int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;

std::uint64_t bigEndian(const std::uint8_t* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}
void putBigEndian(std::uint8_t* p, std::uint64_t v, int n) {
  for (int i = n - 1; i >= 0; --i, v >>= 8) p[i] = static_cast<std::uint8_t>(v);
}

}  // namespace

LogReader::LogReader(const std::filesystem::path& file, LogLimits limits) : file_(file), limits_(limits) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw std::runtime_error("cannot read the log " + file.string() + ": not a regular file");
  f_ = std::fopen(file.c_str(), "rb");
  if (!f_) throw std::runtime_error("cannot open the log " + file.string() + ": " + std::strerror(errno));
  if (std::fseek(f_, 0, SEEK_END) != 0 || (size_ = std::ftell(f_)) < 0 || std::fseek(f_, 0, SEEK_SET) != 0) {
    std::fclose(f_);
    throw std::runtime_error("cannot read the log " + file.string() + ": it cannot be sought");
  }
}

LogReader::LogReader(std::FILE* stream, const std::string& name, LogLimits limits)
    : file_(name), limits_(limits), f_(stream) {
  if (!f_ || std::fseek(f_, 0, SEEK_END) != 0 || (size_ = std::ftell(f_)) < 0 || std::fseek(f_, 0, SEEK_SET) != 0) {
    if (f_) std::fclose(f_);
    f_ = nullptr;
    throw std::runtime_error("cannot read the log " + name + ": it cannot be sought");
  }
}

LogReader::~LogReader() {
  if (f_) std::fclose(f_);
}

void LogReader::problem(std::int64_t offset, std::string what) {
  ++problem_count_;
  if (problems_.size() < kMostProblems) problems_.push_back({offset, std::move(what)});
}

bool LogReader::resync(std::int64_t from) {
  if (std::fseek(f_, from, SEEK_SET) != 0) return false;
  std::uint32_t window = 0;
  std::int64_t read = 0;
  for (int c; (c = std::fgetc(f_)) != EOF;) {
    window = (window << 8) | static_cast<std::uint32_t>(c);
    if (++read >= 4 && window == kSync) {
      pos_ = from + read - 4;
      std::fseek(f_, pos_, SEEK_SET);
      return true;
    }
  }
  pos_ = size_;
  return false;
}

bool LogReader::wholeEventAt(std::int64_t at) {
  std::uint8_t h[kHeaderBytes];
  if (size_ - at < kHeaderBytes || std::fseek(f_, at, SEEK_SET) != 0 ||
      std::fread(h, 1, kHeaderBytes, f_) != static_cast<std::size_t>(kHeaderBytes))
    return false;
  const auto channel_len = static_cast<std::int32_t>(bigEndian(h + 20, 4));
  const auto data_len = static_cast<std::int32_t>(bigEndian(h + 24, 4));
  return bigEndian(h, 4) == kSync && channel_len >= 1 && channel_len <= limits_.channel_bytes && data_len >= 0 &&
         data_len <= limits_.event_bytes && at + kHeaderBytes + channel_len + data_len <= size_;
}

bool LogReader::next(LogEvent& out) {
  while (pos_ < size_) {
    const std::int64_t at = pos_;
    std::uint8_t h[kHeaderBytes];
    if (size_ - at < kHeaderBytes) {
      // Too short for an event header: a torn event if it starts like one (or like its sync word).
      std::uint8_t tail[4] = {};
      const auto n = static_cast<std::size_t>(std::min<std::int64_t>(4, size_ - at));
      const bool read = std::fread(tail, 1, n, f_) == n;
      const std::uint8_t sync[4] = {0xED, 0xA1, 0xDA, 0x01};
      const bool starts = read && std::equal(tail, tail + n, sync);
      if (starts) {
        torn_bytes_ += size_ - at;
      } else {
        problem(at, "no event header in the last " + std::to_string(size_ - at) + " bytes");
        skipped_bytes_ += size_ - at;
      }
      pos_ = size_;
      return false;
    }
    if (std::fread(h, 1, kHeaderBytes, f_) != static_cast<std::size_t>(kHeaderBytes))
      throw std::runtime_error("cannot read the log " + file_.string() + " at offset " + std::to_string(at));
    if (bigEndian(h, 4) != kSync) {
      const bool found = resync(at + 1);
      const std::int64_t skipped = (found ? pos_ : size_) - at;
      skipped_bytes_ += skipped;
      problem(at, "no event begins here: " + std::to_string(skipped) + " bytes skipped" +
                      (found ? " to the next sync word" : " to the end of the file"));
      continue;
    }
    const auto channel_len = static_cast<std::int32_t>(bigEndian(h + 20, 4));
    const auto data_len = static_cast<std::int32_t>(bigEndian(h + 24, 4));
    std::string bad;
    if (channel_len < 1 || channel_len > limits_.channel_bytes)
      bad = "channel length " + std::to_string(channel_len) + " is outside [1, " + std::to_string(limits_.channel_bytes) + "]";
    else if (data_len < 0 || data_len > limits_.event_bytes)
      bad = "data length " + std::to_string(data_len) + " is outside [0, " + std::to_string(limits_.event_bytes) + "]";
    if (!bad.empty()) {
      problem(at, bad);
      const bool found = resync(at + 1);
      skipped_bytes_ += (found ? pos_ : size_) - at;
      continue;
    }
    const std::int64_t end = at + kHeaderBytes + channel_len + data_len;
    if (end > size_) {
      // Cut short: the writer stopped in the middle of it (torn), unless a whole event follows it
      // (then its lengths lie). Sync words in the torn event's own data do not count.
      std::int64_t from = at + 1;
      bool found = false;
      while (!found && resync(from)) {
        found = wholeEventAt(pos_);
        from = pos_ + 1;
      }
      if (!found) {
        torn_bytes_ += size_ - at;
        pos_ = size_;
        return false;
      }
      problem(at, "the event's " + std::to_string(channel_len + data_len) + " bytes run past the end of the file");
      skipped_bytes_ += pos_ - at;
      std::fseek(f_, pos_, SEEK_SET);
      continue;
    }
    // The channel first: a header that is no event's costs its channel's bytes, not its data's.
    std::string channel(static_cast<std::size_t>(channel_len), '\0');
    if (std::fread(channel.data(), 1, channel.size(), f_) != channel.size())
      throw std::runtime_error("cannot read the log " + file_.string() + " at offset " + std::to_string(at));
    bool printable = true;
    for (unsigned char c : channel) printable = printable && c >= 0x20 && c < 0x7f;
    if (!printable) {
      problem(at, "the channel name has bytes that are not printable ASCII");
      const bool found = resync(at + 1);
      skipped_bytes_ += (found ? pos_ : size_) - at;
      continue;
    }
    std::vector<std::uint8_t> data(static_cast<std::size_t>(data_len));
    if (std::fread(data.data(), 1, data.size(), f_) != data.size())
      throw std::runtime_error("cannot read the log " + file_.string() + " at offset " + std::to_string(at));
    pos_ = end;
    out.channel = std::move(channel);
    out.data = std::move(data);
    out.utime = static_cast<std::int64_t>(bigEndian(h + 12, 8));
    out.offset = at;
    return true;
  }
  return false;
}

LogFileContents readLogFile(const std::filesystem::path& file, LogLimits limits) {
  LogReader in(file, limits);
  LogFileContents out;
  for (LogEvent e; in.next(e);) out.events.push_back(std::move(e));
  out.problems = in.problems();
  out.problem_count = in.problemCount();
  out.skipped_bytes = in.skippedBytes();
  out.torn_bytes = in.tornBytes();
  return out;
}

LogWriter::LogWriter(const std::filesystem::path& file) : file_(file) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot create the log " + file.string() + ": " + std::strerror(errno));
  f_ = ::fdopen(fd, "wb");
  if (!f_) {
    ::close(fd);
    throw std::runtime_error("cannot open the log " + file.string() + ": " + std::strerror(errno));
  }
}

LogWriter::~LogWriter() {
  if (f_) std::fclose(f_);
}

void LogWriter::write(const std::string& channel, const void* data, std::size_t size, std::int64_t utime) {
  if (!f_) throw std::runtime_error("the log " + file_.string() + " is closed");
  std::uint8_t h[kHeaderBytes];
  putBigEndian(h, kSync, 4);
  putBigEndian(h + 4, static_cast<std::uint64_t>(events_), 8);
  putBigEndian(h + 12, static_cast<std::uint64_t>(utime), 8);
  putBigEndian(h + 20, channel.size(), 4);
  putBigEndian(h + 24, size, 4);
  if (std::fwrite(h, 1, sizeof h, f_) != sizeof h || std::fwrite(channel.data(), 1, channel.size(), f_) != channel.size() ||
      std::fwrite(data, 1, size, f_) != size || std::fflush(f_) != 0)
    throw std::runtime_error("cannot write to log file " + file_.string() + ": " + std::strerror(errno));
  ++events_;
}

void LogWriter::close() {
  if (!f_) return;
  const bool ok = std::fflush(f_) == 0;
  const int err = errno;
  std::fclose(f_);
  f_ = nullptr;
  if (!ok) throw std::runtime_error("cannot write to log file " + file_.string() + ": " + std::strerror(err));
}

}  // namespace afford

// The project's one reader (and writer) of LCM log files: the run logs the
// logger writes, and any recording of a bus (lcm-logger's). Replay, explain and
// a restarted logger read logs through it; nothing else parses one.
//
// The format is LCM's: each event is a sync word 0xEDA1DA01, the event number
// and the time (int64, microseconds), the channel's length and the data's
// length (int32), the channel, the data; all big-endian. A log is a file given
// to a tool, so nothing in it is trusted: every length is checked against a cap
// and against the bytes the file still holds before anything is allocated. A
// malformed event is skipped and reported with its file offset; the reader then
// looks for the next sync word. An event cut short at the end of the file (a
// writer killed mid-write) is reported as torn.
#pragma once
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace afford {

struct LogLimits {
  int channel_bytes = 63;            // LCM's longest channel name
  std::int64_t event_bytes = 1 << 20;  // the largest event's data (protocol.bus.max_message_bytes)
};

struct LogEvent {
  std::string channel;
  std::vector<std::uint8_t> data;
  std::int64_t utime = 0;     // when it was recorded, microseconds
  std::int64_t offset = -1;   // of its sync word in its file (-1: not read from a file)
};

// A malformed part of a log: where it begins, and what is wrong with it.
struct LogProblem {
  std::int64_t offset = 0;
  std::string what;
};

class LogReader {
 public:
  // Throws std::runtime_error naming the file if it cannot be opened.
  LogReader(const std::filesystem::path& file, LogLimits limits);
  // An open stream that can be sought (e.g. fmemopen's), read as `name`; the reader closes it.
  LogReader(std::FILE* stream, const std::string& name, LogLimits limits);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  // The next well-formed event; false at the end of the file.
  bool next(LogEvent& out);

  const std::filesystem::path& file() const { return file_; }
  // What was skipped, in file order (the first kMostProblems; problemCount() counts all).
  const std::vector<LogProblem>& problems() const { return problems_; }
  std::int64_t problemCount() const { return problem_count_; }
  std::int64_t skippedBytes() const { return skipped_bytes_; }
  // The bytes of an event cut short at the end of the file (0 if none).
  std::int64_t tornBytes() const { return torn_bytes_; }
  static constexpr std::size_t kMostProblems = 100;

 private:
  void problem(std::int64_t offset, std::string what);
  // Moves to the next sync word at or after `from`; false if there is none.
  bool resync(std::int64_t from);
  // Does a well-formed event that ends within the file begin at `at`? (Moves the stream.)
  bool wholeEventAt(std::int64_t at);

  std::filesystem::path file_;
  LogLimits limits_;
  std::FILE* f_ = nullptr;
  std::int64_t size_ = 0, pos_ = 0;
  std::vector<LogProblem> problems_;
  std::int64_t problem_count_ = 0, skipped_bytes_ = 0, torn_bytes_ = 0;
};

// Every well-formed event of one file, in order.
struct LogFileContents {
  std::vector<LogEvent> events;
  std::vector<LogProblem> problems;  // the first LogReader::kMostProblems
  std::int64_t problem_count = 0, skipped_bytes = 0, torn_bytes = 0;
};
LogFileContents readLogFile(const std::filesystem::path& file, LogLimits limits);

// Appends events to a log file; flushed after each, so a killed writer loses
// at most the event it was writing (which a reader reports as torn).
class LogWriter {
 public:
  // Throws std::runtime_error naming the file if it cannot be created; never
  // overwrites: an existing file is refused.
  explicit LogWriter(const std::filesystem::path& file);
  ~LogWriter();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;
  // Throws std::runtime_error naming the file and the reason (a full disk).
  void write(const std::string& channel, const void* data, std::size_t size, std::int64_t utime);
  void close();
  std::int64_t events() const { return events_; }

 private:
  std::filesystem::path file_;
  std::FILE* f_ = nullptr;
  std::int64_t events_ = 0;
};

}  // namespace afford

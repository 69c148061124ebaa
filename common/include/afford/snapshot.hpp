// A process's snapshot of its state in a run (docs/processes-and-channels.md,
// "Runs of any length"): what it needs to go on after a restart from where the
// snapshot was taken instead of from the run's first step, so that its peers
// can let go of what they published before it.
//
// The file: a magic line, the format version, the release that wrote it (afford --version; from format 2,
// 0.2.0), the fields in the order the
// process wrote them (each section named, so a reader out of step with its
// writer stops at the section, naming it), and the FNV-1a 64 of everything
// before it. It is written to `<path>.tmp`, flushed to the disk, and renamed
// over `<path>`: a process killed while it writes leaves the earlier snapshot
// whole. A reader checks the size against a bound and the checksum over the
// whole file before it gives out a single field, and every count it reads
// against a bound and against the bytes left, so a damaged or foreign file is
// refused (SnapshotError, naming the file and the field) and never allocates
// more than the file holds.
#pragma once
#include <sys/types.h>

#include <cstdint>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace afford {

struct SnapshotError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class SnapshotWriter {
 public:
  // Opens `path`.tmp (its folder is created); throws SnapshotError if it cannot.
  explicit SnapshotWriter(std::string path);
  ~SnapshotWriter();  // not committed: the temporary file is removed
  SnapshotWriter(const SnapshotWriter&) = delete;
  SnapshotWriter& operator=(const SnapshotWriter&) = delete;

  void section(const char* name);
  void i64(std::int64_t v);
  void f64(double v);
  void str(const std::string& s);
  void bytes(const void* data, std::size_t size);  // raw: the reader knows the size
  void blob(const std::vector<std::uint8_t>& b);   // size, then bytes
  template <class T>
  void doubles(const std::vector<T>& v) {
    static_assert(sizeof(T) == sizeof(double), "doubles() writes 8-byte values");
    i64(static_cast<std::int64_t>(v.size()));
    bytes(v.data(), v.size() * sizeof(T));
  }
  // The checksum written and everything handed to the kernel (fast: no wait for the disk). Throws SnapshotError.
  void finish();
  // fsync, rename over the path, fsync of the folder (finish() first if not done): the slow part, which may run
  // on another thread while the process goes on. Throws SnapshotError.
  void commit();
  std::uint64_t size() const { return size_; }

 private:
  void put(const void* data, std::size_t size);
  std::string path_, tmp_;
  std::FILE* file_ = nullptr;
  std::uint64_t hash_;
  std::uint64_t size_ = 0;
  bool finished_ = false, committed_ = false;
};

// A snapshot written by a forked copy of the process (copy-on-write, as
// Redis writes its snapshots): the process goes on at once while the copy
// runs `write` (which writes, flushes and renames the file) and ends. The copy
// holds only the calling thread, so `write` must not wait on another one (a
// node finishes its workers' business first), and it neither logs nor flushes
// what the process buffered: it ends with _exit, its error (an exception's
// text) sent back through a pipe. It dies with the process (PR_SET_PDEATHSIG):
// a process killed while its snapshot is written leaves the earlier one whole.
class SnapshotChild {
 public:
  explicit SnapshotChild(const std::function<void()>& write);  // throws SnapshotError if it cannot fork
  ~SnapshotChild();                                             // waits for the copy to end
  SnapshotChild(const SnapshotChild&) = delete;
  SnapshotChild& operator=(const SnapshotChild&) = delete;
  // Has the copy ended? wait: until it has. Once it has, error() says why it failed ("": it did not).
  bool ended(bool wait);
  const std::string& error() const { return error_; }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int reply_ = -1;  // the pipe's end the copy's error comes through
  bool ended_ = false;
  std::string error_;
};

class SnapshotReader {
 public:
  // Opens `path` and checks it whole (size at most `max_bytes`, magic, version, checksum). Throws SnapshotError.
  SnapshotReader(std::string path, std::uint64_t max_bytes);
  ~SnapshotReader();
  SnapshotReader(const SnapshotReader&) = delete;
  SnapshotReader& operator=(const SnapshotReader&) = delete;

  void section(const char* name);
  std::int64_t i64(const char* field);
  // An integer in [lo, hi], else refused naming the field.
  std::int64_t within(const char* field, std::int64_t lo, std::int64_t hi);
  double f64(const char* field);
  std::string str(const char* field, std::size_t max_bytes);
  void bytes(const char* field, void* data, std::size_t size);
  std::vector<std::uint8_t> blob(const char* field, std::size_t max_bytes);
  template <class T>
  void doubles(const char* field, std::vector<T>& v, std::size_t expected) {
    static_assert(sizeof(T) == sizeof(double), "doubles() reads 8-byte values");
    const auto n = within(field, static_cast<std::int64_t>(expected), static_cast<std::int64_t>(expected));
    v.resize(static_cast<std::size_t>(n));
    bytes(field, v.data(), v.size() * sizeof(T));
  }
  // Every field read: nothing is left before the checksum.
  void end();
  const std::string& path() const { return path_; }
  // The release that wrote it (afford --version; "0.1.0" for format 1, which did not say).
  const std::string& writtenBy() const { return written_by_; }
  [[noreturn]] void refuse(const std::string& field, const std::string& why) const;

 private:
  void take(const char* field, void* data, std::size_t size);
  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t left_ = 0;  // bytes of fields not read yet
  std::string written_by_;
};

}  // namespace afford

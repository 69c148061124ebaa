#include "afford/snapshot.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>

#include "afford/names.hpp"
#include "afford/seal.hpp"
#include "afford/version.hpp"

namespace afford {

namespace fs = std::filesystem;

namespace {
constexpr char kMagic[] = "afford snapshot\n";  // 16 bytes
// 1: the fields; 2: the build that wrote it (afford --version) after the format, then the fields (0.2.0 on).
constexpr std::int64_t kVersion = 2;
constexpr std::uint64_t kFnvBasis = 0xCBF29CE484222325ull;

std::string sectionMark(const char* name) { return std::string("[") + name + "]"; }

void syncFolder(const fs::path& folder) {
  const int fd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}
}  // namespace

SnapshotWriter::SnapshotWriter(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp"), hash_(kFnvBasis) {
  std::error_code ec;
  const fs::path folder = fs::path(path_).parent_path();
  if (!folder.empty()) fs::create_directories(folder, ec);
  file_ = std::fopen(tmp_.c_str(), "wb");
  if (!file_) throw SnapshotError("snapshot " + tmp_ + ": cannot be written (" + std::strerror(errno) + ")");
  put(kMagic, sizeof kMagic - 1);
  i64(kVersion);
  str(affordVersion());
}

SnapshotWriter::~SnapshotWriter() {
  if (file_) std::fclose(file_);
  if (!committed_) {
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
}

void SnapshotWriter::put(const void* data, std::size_t size) {
  if (size == 0) return;
  hash_ = fnv1a64(hash_, data, size);
  if (std::fwrite(data, 1, size, file_) != size)
    throw SnapshotError("snapshot " + tmp_ + ": write failed (" + std::strerror(errno) + ")");
  size_ += size;
}

void SnapshotWriter::section(const char* name) { str(sectionMark(name)); }
void SnapshotWriter::i64(std::int64_t v) { put(&v, sizeof v); }
void SnapshotWriter::f64(double v) { put(&v, sizeof v); }
void SnapshotWriter::str(const std::string& s) {
  i64(static_cast<std::int64_t>(s.size()));
  put(s.data(), s.size());
}
void SnapshotWriter::bytes(const void* data, std::size_t size) { put(data, size); }
void SnapshotWriter::blob(const std::vector<std::uint8_t>& b) {
  i64(static_cast<std::int64_t>(b.size()));
  put(b.data(), b.size());
}

void SnapshotWriter::finish() {
  if (finished_) return;
  const std::uint64_t sum = hash_;
  if (std::fwrite(&sum, 1, sizeof sum, file_) != sizeof sum || std::fflush(file_) != 0)
    throw SnapshotError("snapshot " + tmp_ + ": write failed (" + std::strerror(errno) + ")");
  finished_ = true;
}

void SnapshotWriter::commit() {
  finish();
  if (::fsync(fileno(file_)) != 0)
    throw SnapshotError("snapshot " + tmp_ + ": write failed (" + std::strerror(errno) + ")");
  std::fclose(file_);
  file_ = nullptr;
  std::error_code ec;
  fs::rename(tmp_, path_, ec);
  if (ec) throw SnapshotError("snapshot " + path_ + ": cannot be put in place (" + ec.message() + ")");
  committed_ = true;
  syncFolder(fs::path(path_).parent_path());
}

SnapshotChild::SnapshotChild(const std::function<void()>& write) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0)
    throw SnapshotError(std::string("snapshot: no pipe for its writer (") + std::strerror(errno) + ")");
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ < 0) {
    const int e = errno;
    ::close(ends[0]);
    ::close(ends[1]);
    throw SnapshotError(std::string("snapshot: cannot fork its writer (") + std::strerror(e) + ")");
  }
  if (pid_ == 0) {
    ::close(ends[0]);
    // Dies with the process; if it is gone already, there is no one to write for.
    if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) ::_exit(3);
    std::string why;
    try {
      write();
    } catch (const std::exception& e) {
      why = e.what();
    } catch (...) {
      why = "snapshot: its writer failed";
    }
    if (why.empty()) ::_exit(0);
    const std::size_t n = std::min<std::size_t>(why.size(), 4000);  // within the pipe's atomic write
    const ssize_t sent = ::write(ends[1], why.data(), n);
    ::_exit(sent == static_cast<ssize_t>(n) ? 1 : 2);
  }
  ::close(ends[1]);
  reply_ = ends[0];
}

SnapshotChild::~SnapshotChild() {
  ended(/*wait=*/true);
  if (reply_ >= 0) ::close(reply_);
}

bool SnapshotChild::ended(bool wait) {
  if (ended_) return true;
  int status = 0;
  pid_t got;
  do got = ::waitpid(pid_, &status, wait ? 0 : WNOHANG);
  while (got < 0 && errno == EINTR);
  if (got == 0) return false;
  ended_ = true;
  if (got < 0) {
    error_ = std::string("snapshot: its writer was lost (") + std::strerror(errno) + ")";
  } else if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    error_.clear();
  } else {
    char text[4096];
    ssize_t n;
    do n = ::read(reply_, text, sizeof text);
    while (n < 0 && errno == EINTR);
    if (n > 0)
      error_.assign(text, static_cast<std::size_t>(n));
    else if (WIFSIGNALED(status))
      error_ = "snapshot: its writer was ended by signal " + std::to_string(WTERMSIG(status));
    else
      error_ = "snapshot: its writer failed (exit " + std::to_string(WEXITSTATUS(status)) + ")";
  }
  ::close(reply_);
  reply_ = -1;
  return true;
}

SnapshotReader::SnapshotReader(std::string path, std::uint64_t max_bytes) : path_(std::move(path)) {
  std::error_code ec;
  if (!fs::is_regular_file(path_, ec)) throw SnapshotError("snapshot " + path_ + ": not a file");
  const std::uint64_t size = fs::file_size(path_, ec);
  if (ec) throw SnapshotError("snapshot " + path_ + ": cannot be read (" + ec.message() + ")");
  if (size > max_bytes)
    throw SnapshotError("snapshot " + path_ + ": " + std::to_string(size) + " bytes, more than the " +
                        std::to_string(max_bytes) + " a snapshot of this run can hold");
  const std::uint64_t head = sizeof kMagic - 1 + 8;
  if (size < head + 8) throw SnapshotError("snapshot " + path_ + ": too short to be a snapshot");
  file_ = std::fopen(path_.c_str(), "rb");
  if (!file_) throw SnapshotError("snapshot " + path_ + ": cannot be read (" + std::strerror(errno) + ")");
  // The checksum over the whole file first: nothing is given out of a damaged one.
  std::uint64_t hash = kFnvBasis, left = size - 8;
  std::vector<char> buffer(1 << 16);
  while (left > 0) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, buffer.size()));
    if (std::fread(buffer.data(), 1, n, file_) != n) refuse("checksum", "the file is shorter than it was");
    hash = fnv1a64(hash, buffer.data(), n);
    left -= n;
  }
  std::uint64_t stored = 0;
  if (std::fread(&stored, 1, sizeof stored, file_) != sizeof stored || stored != hash)
    refuse("checksum", "does not match its content (a damaged or cut file)");
  std::rewind(file_);
  left_ = size - 8;
  char magic[sizeof kMagic - 1];
  take("magic", magic, sizeof magic);
  if (std::memcmp(magic, kMagic, sizeof magic) != 0) refuse("magic", "not an afford snapshot");
  const std::int64_t v = i64("version");
  if (v < 1 || v > kVersion)
    refuse("version", "format " + std::to_string(v) + ", this build reads formats 1 to " + std::to_string(kVersion) +
                          " (written by a later release: restart the process with that release)");
  written_by_ = v >= 2 ? str("written by", 64) : "0.1.0 or earlier";
}

SnapshotReader::~SnapshotReader() {
  if (file_) std::fclose(file_);
}

void SnapshotReader::refuse(const std::string& field, const std::string& why) const {
  throw SnapshotError("snapshot " + path_ + ": " + field + ": " + why);
}

void SnapshotReader::take(const char* field, void* data, std::size_t size) {
  if (size > left_) refuse(field, "the file ends before it");
  if (size > 0 && std::fread(data, 1, size, file_) != size) refuse(field, "cannot be read");
  left_ -= size;
}

void SnapshotReader::section(const char* name) {
  const std::string want = sectionMark(name);
  const std::string got = str("section", 64);
  if (got != want) refuse(want, "expected here, found '" + printable(got, 40) + "' (written by another version)");
}

std::int64_t SnapshotReader::i64(const char* field) {
  std::int64_t v = 0;
  take(field, &v, sizeof v);
  return v;
}

std::int64_t SnapshotReader::within(const char* field, std::int64_t lo, std::int64_t hi) {
  const std::int64_t v = i64(field);
  if (v < lo || v > hi)
    refuse(field, std::to_string(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

double SnapshotReader::f64(const char* field) {
  double v = 0;
  take(field, &v, sizeof v);
  return v;
}

std::string SnapshotReader::str(const char* field, std::size_t max_bytes) {
  const auto n = static_cast<std::size_t>(
      within(field, 0, static_cast<std::int64_t>(std::min<std::uint64_t>(max_bytes, left_))));
  std::string s(n, '\0');
  take(field, s.data(), n);
  return s;
}

void SnapshotReader::bytes(const char* field, void* data, std::size_t size) { take(field, data, size); }

std::vector<std::uint8_t> SnapshotReader::blob(const char* field, std::size_t max_bytes) {
  const auto n = static_cast<std::size_t>(
      within(field, 0, static_cast<std::int64_t>(std::min<std::uint64_t>(max_bytes, left_))));
  std::vector<std::uint8_t> b(n);
  take(field, b.data(), n);
  return b;
}

void SnapshotReader::end() {
  if (left_ != 0) refuse("end", std::to_string(left_) + " bytes follow the last field (written by another version)");
}

}  // namespace afford

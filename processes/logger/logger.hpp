// Logger core: one run's events into a standard LCM log file
// (logs/<run-id>/log.00.lcm, readable by lcm-logplayer and afford/logfile.hpp) and
// a manifest (logs/<run-id>/manifest.json) with the effective config, seed,
// version, the processes that took part, and whether the log is complete
// (`complete`; else `incomplete` says why and `missing` lists what is missing).
// Every event is flushed as it is written, so a killed logger loses nothing
// it had received. While a log is written, its folder is held (a shared
// flock, the kernel's: let go when the logger closes the log or dies), so
// `afford clean` never offers it.
#pragma once
#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "afford/edge.hpp"
#include "afford/logfile.hpp"

namespace afford {


// What earlier segments of a run's log hold (for a restarted logger).
struct RecordedSoFar {
  std::map<std::string, std::int64_t> next_serial;          // serial channels
  std::map<std::string, std::int64_t> last_digest;          // ... the digest of the last one recorded
  std::map<std::string, std::set<std::string>> untracked;   // the others: contents
  std::int64_t events = 0;
  std::optional<std::int64_t> request;  // the digest of the RUN_CONFIG they record (the request they are of)
  bool ended = false;  // the run's end (RESULT or EXTRINSIC_RESULT) is in them
  std::vector<LogProblem> problems;  // malformed parts of them, skipped (a file's name in `what`)
};
// Read with the project's log reader (afford/logfile.hpp) and its caps.
RecordedSoFar readRecorded(const std::string& dir, const LogLimits& limits);
// Does the manifest in `dir` say the logger process of `session` wrote it (its "logger_session")?
bool wroteLog(const std::string& dir, std::int64_t session);
// Does the manifest in `dir` say its log is complete and of the request `config_digest` (an earlier logger
// process closed it)?
bool closedLog(const std::string& dir, std::int64_t config_digest);
// The log in `dir` (its segments and manifest) moved, whole, into dir/other-request-<k>/ (k the first free);
// returns that folder. Throws std::runtime_error naming what could not be moved.
std::string setAsideLog(const std::string& dir);

// A folder held by a shared flock until release() or the end of this object (or of the process).
class HeldFolder {
 public:
  HeldFolder() = default;
  ~HeldFolder() { release(); }
  HeldFolder(const HeldFolder&) = delete;
  HeldFolder& operator=(const HeldFolder&) = delete;
  void hold(const std::string& dir);
  void release();

 private:
  int fd_ = -1;
};

class RunLog {
 public:
  // Opens a new segment in `dir` (created if missing); never overwrites:
  // an existing log.NN.lcm makes this the next segment of the same run.
  // Throws if `dir` holds the complete log of a run already.
  RunLog(const std::string& dir, nlohmann::json manifest);
  ~RunLog();
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;

  void write(const std::string& channel, const void* data, std::uint32_t size, std::int64_t utime);
  // A process seen on the bus (name -> pid), recorded in the manifest.
  void sawProcess(const std::string& name, int pid);
  // Set a count the manifest reports (e.g. "control_dropped"); written with the next manifest.
  void count(const std::string& key, std::int64_t value) { manifest_[key] = value; }
  // A count the manifest holds (carried from the run's earlier segments), or 0.
  std::int64_t count(const std::string& key) const {
    return manifest_.contains(key) && manifest_[key].is_number_integer() ? manifest_[key].get<std::int64_t>() : 0;
  }
  // Flush and write the final manifest: complete when `incomplete` is empty,
  // else that reason and the serials still missing per channel.
  void close(const std::string& incomplete = "", const nlohmann::json& missing = nlohmann::json::object());

  const std::string& dir() const { return dir_; }
  const std::string& path() const { return path_; }
  std::int64_t events() const { return events_; }

 private:
  void writeManifest();

  std::string dir_, path_;
  std::unique_ptr<LogWriter> file_;
  nlohmann::json manifest_;
  std::map<std::string, int> processes_;
  std::int64_t events_ = 0, bytes_ = 0;
  bool closed_ = false;
  HeldFolder folder_;  // from before the segment's first byte to the final manifest
};

}  // namespace afford

#include "logger/logger.hpp"

#include "afford/protocol.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace afford {

namespace fs = std::filesystem;

namespace {
std::uint64_t bigEndian(const unsigned char* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}
}  // namespace



// Only a test of the lock takes it exclusively, for an instant (afford clean): a few tries get past one.
void HeldFolder::hold(const std::string& dir) {
  release();
  fd_ = open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  for (int tries = 0; fd_ >= 0 && tries < 100 && flock(fd_, LOCK_SH | LOCK_NB) != 0; ++tries) usleep(1000);
}

void HeldFolder::release() {
  if (fd_ >= 0) ::close(fd_);  // (which lets go of the lock)
  fd_ = -1;
}

RecordedSoFar readRecorded(const std::string& dir, const LogLimits& limits) {
  RecordedSoFar r;
  for (int segment = 0;; ++segment) {
    char name[32];
    std::snprintf(name, sizeof name, "log.%02d.lcm", segment);
    const fs::path path = fs::path(dir) / name;
    if (!fs::exists(path)) break;
    LogReader in(path, limits);
    for (LogEvent ev; in.next(ev);) {
      ++r.events;
      RunHeader h;
      const auto size = static_cast<std::uint32_t>(ev.data.size());
      if (isSerialChannel(ev.channel) && peekRunHeader(ev.data.data(), size, h)) {
        // (next_serial and last_digest have an entry for a channel together, or none)
        const auto it = r.next_serial.find(ev.channel);
        if (h.serial >= (it == r.next_serial.end() ? 0 : it->second) && h.serial < INT64_MAX && size >= 8) {
          r.next_serial[ev.channel] = h.serial + 1;
          r.last_digest[ev.channel] = static_cast<std::int64_t>(bigEndian(ev.data.data() + size - 8, 8));
        }
        if (ev.channel == ch::result.name || ev.channel == ch::extrinsicResult.name) r.ended = true;
      } else {
        r.untracked[ev.channel].insert(std::string(reinterpret_cast<const char*>(ev.data.data()), ev.data.size()));
        if (ev.channel == ch::runConfig.name && !r.request && size >= 8)
          r.request = static_cast<std::int64_t>(bigEndian(ev.data.data() + size - 8, 8));
      }
    }
    for (const LogProblem& p : in.problems()) r.problems.push_back({p.offset, path.string() + ": " + p.what});
    if (in.tornBytes() > 0)
      r.problems.push_back({static_cast<std::int64_t>(fs::file_size(path) - in.tornBytes()),
                            path.string() + ": an incomplete last event of " + std::to_string(in.tornBytes()) + " bytes"});
  }
  return r;
}

namespace {
// The manifest in `dir` as JSON (discarded if there is none, or it does not parse).
nlohmann::json manifestIn(const std::string& dir) {
  std::ifstream in(fs::path(dir) / "manifest.json");
  return nlohmann::json::parse(in, nullptr, false);
}
bool says(const nlohmann::json& m, const char* key, std::int64_t value) {
  return !m.is_discarded() && m.is_object() && m.contains(key) && m[key].is_number_integer() &&
         m[key].get<std::int64_t>() == value;
}
}  // namespace

bool wroteLog(const std::string& dir, std::int64_t session) { return says(manifestIn(dir), "logger_session", session); }

bool closedLog(const std::string& dir, std::int64_t config_digest) {
  const nlohmann::json m = manifestIn(dir);
  return says(m, "config_digest", config_digest) && m.value("complete", false);
}

std::string setAsideLog(const std::string& dir) {
  fs::path aside;
  std::error_code ec;
  for (int k = 1;; ++k) {
    aside = fs::path(dir) / ("other-request-" + std::to_string(k));
    if (fs::create_directory(aside, ec)) break;
    if (ec) throw std::runtime_error("cannot make " + aside.string() + ": " + ec.message());
  }
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name != "manifest.json" && !(name.rfind("log.", 0) == 0 && e.path().extension() == ".lcm")) continue;
    fs::rename(e.path(), aside / name, ec);
    if (ec) throw std::runtime_error("cannot move " + e.path().string() + " into " + aside.string() + ": " + ec.message());
  }
  return aside.string();
}

RunLog::RunLog(const std::string& dir, nlohmann::json manifest) : dir_(dir), manifest_(std::move(manifest)) {
  const fs::path old_manifest = fs::path(dir_) / "manifest.json";
  if (fs::exists(old_manifest)) {
    std::ifstream in(old_manifest);
    const nlohmann::json old = nlohmann::json::parse(in, nullptr, false);
    if (!old.is_discarded() && old.value("complete", false))
      throw std::runtime_error(dir_ + " already holds the complete log of run '" + old.value("run_id", "?") +
                               "': refusing to mix runs (use another run id)");
  }
  fs::create_directories(dir_);
  folder_.hold(dir_);
  if (fs::exists(old_manifest)) {  // a later segment of the same run: keep the list
    std::ifstream in(old_manifest);
    const nlohmann::json old = nlohmann::json::parse(in, nullptr, false);
    if (!old.is_discarded() && old.contains("segments")) manifest_["segments"] = old["segments"];
    if (!old.is_discarded() && old.contains("control_dropped") && old["control_dropped"].is_number_integer())
      manifest_["control_dropped"] = old["control_dropped"];
    // ... and the processes seen in them (a logger started again after the others left the run sees none).
    if (!old.is_discarded() && old.contains("processes") && old["processes"].is_array())
      for (const nlohmann::json& p : old["processes"])
        if (p.is_object() && p.contains("process") && p["process"].is_string() && p.contains("pid") &&
            p["pid"].is_number_integer())
          processes_[p["process"].get<std::string>()] = p["pid"].get<int>();
  }
  int segment = 0;
  char name[32];
  do {
    std::snprintf(name, sizeof name, "log.%02d.lcm", segment++);
  } while (fs::exists(fs::path(dir_) / name));
  path_ = (fs::path(dir_) / name).string();
  file_ = std::make_unique<LogWriter>(path_);  // throws naming the file
  manifest_["segments"].push_back(name);
  writeManifest();
}

RunLog::~RunLog() {
  try {
    close("the logger stopped before the run ended");
  } catch (...) {
  }
}

void RunLog::write(const std::string& channel, const void* data, std::uint32_t size, std::int64_t utime) {
  if (closed_) return;
  file_->write(channel, data, size, utime);  // flushed; throws naming the file (a full disk)
  ++events_;
  bytes_ += size;
}

void RunLog::sawProcess(const std::string& name, int pid) {
  auto [it, fresh] = processes_.emplace(name, pid);
  if (!fresh && it->second == pid) return;
  it->second = pid;
  writeManifest();
}

void RunLog::close(const std::string& incomplete, const nlohmann::json& missing) {
  if (closed_) return;
  closed_ = true;
  std::string close_error;
  try {
    file_->close();
  } catch (const std::exception& e) {
    close_error = e.what();
  }
  file_.reset();
  const std::string why = incomplete.empty() && !close_error.empty() ? "a write failed: " + close_error : incomplete;
  manifest_["complete"] = why.empty();
  if (!why.empty()) {
    manifest_["incomplete"] = why;
    manifest_["missing"] = missing;
  }
  writeManifest();
  folder_.release();
  if (!close_error.empty()) throw std::runtime_error(close_error);
}

void RunLog::writeManifest() {
  nlohmann::json procs = nlohmann::json::array();
  for (const auto& [name, pid] : processes_) procs.push_back({{"process", name}, {"pid", pid}});
  manifest_["processes"] = procs;
  manifest_["events"] = events_;
  manifest_["payload_bytes"] = bytes_;
  const fs::path tmp = fs::path(dir_) / "manifest.json.tmp";
  {
    std::ofstream out(tmp);
    out << manifest_.dump(2) << "\n";
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + tmp.string() + ": " + std::strerror(errno));
  }
  fs::rename(tmp, fs::path(dir_) / "manifest.json");
}

}  // namespace afford

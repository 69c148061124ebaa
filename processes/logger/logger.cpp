#include "logger/logger.hpp"

#include "afford/channels.hpp"

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

bool isSerialChannel(const std::string& channel) {
  for (const char* c : channel::kWithSerial)
    if (channel == c) return true;
  return false;
}

bool peekRunHeader(const void* data, std::uint32_t size, RunHeader& out) {
  const auto* p = static_cast<const unsigned char*>(data);
  if (size < 12) return false;
  const std::uint64_t len = bigEndian(p + 8, 4);  // string length, with its NUL
  if (len < 1 || 12 + len + 16 > size) return false;
  out.run_id.assign(reinterpret_cast<const char*>(p + 12), len - 1);
  out.step = static_cast<std::int64_t>(bigEndian(p + 12 + len, 8));
  out.serial = static_cast<std::int64_t>(bigEndian(p + 12 + len + 8, 8));
  return true;
}

RecordedSoFar readRecorded(const std::string& dir) {
  RecordedSoFar r;
  for (int segment = 0;; ++segment) {
    char name[32];
    std::snprintf(name, sizeof name, "log.%02d.lcm", segment);
    const fs::path path = fs::path(dir) / name;
    if (!fs::exists(path)) break;
    lcm::LogFile in(path.string(), "r");
    if (!in.good()) throw std::runtime_error("cannot read " + path.string());
    while (const lcm::LogEvent* ev = in.readNextEvent()) {
      ++r.events;
      RunHeader h;
      if (isSerialChannel(ev->channel) && peekRunHeader(ev->data, static_cast<std::uint32_t>(ev->datalen), h)) {
        std::int64_t& next = r.next_serial[ev->channel];
        if (h.serial + 1 > next && ev->datalen >= 8) {
          next = h.serial + 1;
          r.last_digest[ev->channel] = static_cast<std::int64_t>(
              bigEndian(static_cast<const unsigned char*>(ev->data) + ev->datalen - 8, 8));
        }
        if (ev->channel == channel::kResult || ev->channel == channel::kExtrinsicResult) r.ended = true;
      } else {
        r.untracked[ev->channel].insert(std::string(static_cast<const char*>(ev->data), ev->datalen));
      }
    }
  }
  return r;
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
  if (fs::exists(old_manifest)) {  // a later segment of the same run: keep the list
    std::ifstream in(old_manifest);
    const nlohmann::json old = nlohmann::json::parse(in, nullptr, false);
    if (!old.is_discarded() && old.contains("segments")) manifest_["segments"] = old["segments"];
  }
  int segment = 0;
  char name[32];
  do {
    std::snprintf(name, sizeof name, "log.%02d.lcm", segment++);
  } while (fs::exists(fs::path(dir_) / name));
  path_ = (fs::path(dir_) / name).string();
  file_ = std::make_unique<lcm::LogFile>(path_, "w");
  if (!file_->good()) throw std::runtime_error("cannot open log file " + path_ + " for writing");
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
  lcm::LogEvent ev;
  ev.eventnum = events_;
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(size);
  ev.data = const_cast<void*>(data);
  if (file_->writeEvent(&ev) != 0 || std::fflush(file_->getFilePtr()) != 0)
    throw std::runtime_error("cannot write to log file " + path_ + ": " + std::strerror(errno));
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
  std::fflush(file_->getFilePtr());
  file_.reset();
  manifest_["complete"] = incomplete.empty();
  if (!incomplete.empty()) {
    manifest_["incomplete"] = incomplete;
    manifest_["missing"] = missing;
  }
  writeManifest();
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

#include "logger/logger.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace afford {

namespace fs = std::filesystem;

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
    close();
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
  if (file_->writeEvent(&ev) != 0) throw std::runtime_error("cannot write to log file " + path_);
  std::fflush(file_->getFilePtr());
  ++events_;
  bytes_ += size;
}

void RunLog::sawProcess(const std::string& name, int pid) {
  auto [it, fresh] = processes_.emplace(name, pid);
  if (!fresh && it->second == pid) return;
  it->second = pid;
  writeManifest();
}

void RunLog::close() {
  if (closed_) return;
  closed_ = true;
  std::fflush(file_->getFilePtr());
  file_.reset();
  manifest_["complete"] = true;
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
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, fs::path(dir_) / "manifest.json");
}

}  // namespace afford

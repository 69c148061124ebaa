#include "logger/node.hpp"

#include <filesystem>

#include "afford/channels.hpp"

namespace afford {

LoggerNode::LoggerNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, std::string log_root)
    : NodeBase(lcm, "logger", std::move(log)), log_root_(std::move(log_root)) {
  for (const char* c : channel::kWithSerial) trackChannel(c);
  subscribeRaw(".*", [this](const lcm::ReceiveBuffer* b, const std::string& ch) { onAny(b, ch); }, 100000);
}

void LoggerNode::onConfigured(const RunConfig& config) {
  const run_config_t& m = runConfigMessage();
  nlohmann::json manifest = {
      {"run_id", m.run_id},         {"experiment", m.experiment}, {"system", m.system},
      {"seed", m.seed},             {"steps", config.steps},      {"afford_version", AFFORD_VERSION},
      {"config_yaml", m.config_yaml}, {"segments", nlohmann::json::array()}, {"complete", false}};
  const std::string dir = (std::filesystem::path(log_root_) / m.run_id).string();
  written_.clear();
  left_.clear();
  // A logger restarted during the run: go on where the earlier segments end.
  const RecordedSoFar before = readRecorded(dir);
  log_file_ = std::make_unique<RunLog>(dir, manifest);
  for (const auto& [channel, next] : before.next_serial) expectSerial(channel, next);
  for (const auto& [channel, contents] : before.untracked) written_[channel] = contents;
  if (before.events > 0)
    log_->info("recording run '{}' into {}, after {} events in earlier segments", m.run_id, log_file_->path(),
               before.events);
  else
    log_->info("recording run '{}' into {}", m.run_id, log_file_->path());
}

bool LoggerNode::readyToLeave() {
  if (!log_file_) return true;
  if (missingMessages() > 0) return false;
  for (const auto& [process, left] : left_)
    if (!left) return false;
  return true;
}

void LoggerNode::onLeaveTimeout() {
  std::string who;
  for (const auto& [process, left] : left_)
    if (!left) who += " " + process;
  log_->warn("closing the log of run '{}' with {} messages still missing{}{}", runId(), missingMessages(),
             who.empty() ? "" : "; no final count from:", who);
}

void LoggerNode::onStop() {
  if (!log_file_) return;
  log_file_->close();
  log_->info("closed {} ({} events)", log_file_->path(), log_file_->events());
  const std::string dir = log_file_->dir();
  log_file_.reset();
  setState(process_status_t::DONE, dir);
}

void LoggerNode::onAny(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
  if (!log_file_) return;
  if (ch == channel::kResend) return;
  if (ch == channel::kStatus) {
    process_status_t st;
    std::string reason;
    if (!decodeAtEdge(rbuf, st, reason)) return;
    if (st.run_id == runId()) {
      log_file_->sawProcess(st.process, st.pid);
      if (st.process != process()) left_.emplace(st.process, false);
    } else if (st.counts_run == runId() && left_.count(st.process)) {
      left_[st.process] = true;  // it left the run: its counts are final
    }
    return;
  }
  if (isSerialChannel(ch)) {
    RunHeader h;
    if (peekRunHeader(rbuf->data, rbuf->data_size, h)) {
      if (h.run_id != runId()) return;  // another run's message (or stray)
      if (!inSerialOrder(ch, h.serial)) return;
    }
    return write(rbuf, ch);
  }
  // The runner's channels: each content once (RUN_CONFIG is said again to latecomers).
  auto& seen = written_[ch];
  std::string content(static_cast<const char*>(rbuf->data), rbuf->data_size);
  if (!seen.insert(std::move(content)).second) return;
  write(rbuf, ch);
}

void LoggerNode::write(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
  try {
    log_file_->write(ch, rbuf->data, rbuf->data_size, rbuf->recv_utime);
  } catch (const std::exception& e) {
    log_->error("{}: {}", ch, e.what());
  }
}

}  // namespace afford

#include "logger/node.hpp"

#include <filesystem>

#include "afford/channels.hpp"

namespace afford {

LoggerNode::LoggerNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, std::string log_root)
    : NodeBase(lcm, "logger", std::move(log)), log_root_(std::move(log_root)) {
  subscribeRaw(".*", [this](const lcm::ReceiveBuffer* b, const std::string& ch) { onAny(b, ch); }, 100000);
}

void LoggerNode::onConfigured(const RunConfig& config) {
  const run_config_t& m = runConfigMessage();
  nlohmann::json manifest = {
      {"run_id", m.run_id},         {"experiment", m.experiment}, {"system", m.system},
      {"seed", m.seed},             {"steps", config.steps},      {"afford_version", AFFORD_VERSION},
      {"config_yaml", m.config_yaml}, {"segments", nlohmann::json::array()}, {"complete", false}};
  const std::string dir = (std::filesystem::path(log_root_) / m.run_id).string();
  log_file_ = std::make_unique<RunLog>(dir, manifest);
  log_->info("recording run '{}' into {}", m.run_id, log_file_->path());
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
  if (ch == channel::kStatus) {
    process_status_t st;
    std::string reason;
    if (decodeAtEdge(rbuf, st, reason) && st.run_id == runId()) log_file_->sawProcess(st.process, st.pid);
    return;
  }
  try {
    log_file_->write(ch, rbuf->data, rbuf->data_size, rbuf->recv_utime);
  } catch (const std::exception& e) {
    log_->error("{}: {}", ch, e.what());
  }
}

}  // namespace afford

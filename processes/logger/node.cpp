#include "logger/node.hpp"

#include <unistd.h>

#include <filesystem>

#include "afford/version.hpp"
#include "afford/affordance_table_t.hpp"
#include "afford/protocol.hpp"
#include "afford/processes.hpp"
#include "afford/decision_t.hpp"
#include "afford/effect_t.hpp"
#include "afford/extrinsic_result_t.hpp"
#include "afford/focus_t.hpp"
#include "afford/forward_prediction_t.hpp"
#include "afford/forward_query_t.hpp"
#include "afford/look_t.hpp"
#include "afford/object_probe_t.hpp"
#include "afford/prediction_t.hpp"
#include "afford/run_result_t.hpp"
#include "afford/scene_t.hpp"

namespace afford {

LoggerNode::LoggerNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol,
                       std::string log_root)
    : NodeBase(lcm, "logger", std::move(log), protocol), log_root_(std::move(log_root)) {
  // Every recorded run channel of the protocol (RUN_CONFIG and RUN_CONTROL come through onControl).
  forEachChannel([this](const auto& c) {
    using Msg = typename std::decay_t<decltype(c)>::Message;
    if constexpr (wire::Bounds<Msg>::kSerial)
      if (c.recorded) record(c);
  });
}

template <class Msg>
void LoggerNode::record(const Channel<Msg>& channel) {
  takes(channel, std::string("every ") + channel.name + " of the run, in serial order, once: written as it came")
      .then([this](const Msg& m, const Envelope& e) {
        write(e);
        handled(m.step);  // its STATUS says the last step it recorded: how far its log is
      });
}

void LoggerNode::onConfigured(const RunConfig& config) {
  const run_config_t& m = runConfigMessage();
  nlohmann::json manifest = {
      {"run_id", m.run_id},         {"experiment", m.experiment}, {"system", m.system},
      {"seed", m.seed},             {"steps", config.steps},      {"afford_version", affordVersion()},
      {"config_yaml", m.config_yaml}, {"segments", nlohmann::json::array()}, {"complete", false},
      {"config_digest", m.digest},  // the request recorded (run_config_t.request)
      {"logger_session", session_},  // this logger process, while it lives
      {"bus_keyed", edge().key() != nullptr}};  // recorded without the tags either way
  const std::string dir = (std::filesystem::path(log_root_) / m.run_id).string();
  closed_dir_.clear();
  written_.clear();
  control_written_ = 0;
  control_dropped_ = 0;
  left_.clear();
  ended_ = false;
  write_error_.clear();
  // Closed complete by an earlier logger process of this request (killed before its DONE reached the runner):
  // nothing is left to record, and the STOP gets its DONE.
  if (closedLog(dir, m.digest)) {
    closed_dir_ = dir;
    log_->info("{} already holds the complete log of run '{}', of this very request (a logger process closed it, "
               "perhaps killed before it said so): nothing to record",
               dir, m.run_id);
    return;
  }
  // A logger restarted during the run: go on where the earlier segments end.
  LogLimits limits;
  limits.event_bytes = config.protocol.bus.max_message_bytes;
  RecordedSoFar before = readRecorded(dir, limits);
  for (const LogProblem& p : before.problems)
    log_->warn("an earlier segment of run '{}': offset {}: {}: skipped", m.run_id, p.offset, p.what);
  // Earlier segments of this request (a restarted logger) are gone on from; another request's log is never mixed
  // with this one, nor overwritten. One this very process wrote (a request it took from a recording played back,
  // or from another runner, and was told to leave) is set aside whole, so that the one asked for now is recorded;
  // one written by anyone else is someone else's record: the run is refused, naming it.
  if (before.events > 0 && before.request != m.digest) {
    if (!wroteLog(dir, session_))
      throw ConfigError(dir + " holds the log of " +
                        (before.request ? "another request of run '" + m.run_id + "' (another RUN_CONFIG)"
                                        : "a run whose RUN_CONFIG cannot be read") +
                        ": its log is kept as it is; move the folder aside, or use another run id");
    log_->warn("run '{}': {} held the log of another request of it, which this logger recorded and was told to "
               "leave: set aside in {}", m.run_id, dir, setAsideLog(dir));
    before = RecordedSoFar{};
  }
  log_file_ = std::make_unique<RunLog>(dir, manifest);  // refuses a folder that holds a complete log
  log_file_->sawProcess(process(), static_cast<int>(getpid()));
  control_dropped_ = log_file_->count("control_dropped");  // an earlier segment's
  for (const auto& [channel, next] : before.next_serial) edge().expectSerial(channel, next, before.last_digest.at(channel));
  for (const auto& [channel, contents] : before.untracked) {
    written_[channel] = contents;
    control_written_ += static_cast<std::int64_t>(contents.size());
  }
  ended_ = before.ended;
  if (before.events > 0)
    log_->info("recording run '{}' into {}, after {} events in earlier segments", m.run_id, log_file_->path(),
               before.events);
  else
    log_->info("recording run '{}' into {}", m.run_id, log_file_->path());
}

void LoggerNode::onControl(const Envelope& e) {
  if (!log_file_) return;
  std::string content(reinterpret_cast<const char*>(e.data), e.size);
  std::set<std::string>& written = written_[e.channel];
  if (written.count(content)) return;  // said again: recorded once
  // A run has a handful of these (its config, START, STOP); a flood of distinct
  // ones is forged, and neither its memory nor the log grows with it.
  if (control_written_ >= config().protocol.limits.control_messages) {
    if (control_dropped_++ == 0)
      log_->warn("{}: run '{}' has had {} distinct RUN_CONFIG and RUN_CONTROL messages "
                 "(protocol.limits.control_messages): more are not recorded, only counted",
                 e.channel, runId(), control_written_);
    log_file_->count("control_dropped", control_dropped_);
    return;
  }
  written.insert(std::move(content));
  ++control_written_;
  write(e);
}

bool LoggerNode::publishes(const std::string& process) const {
  for (const std::string& ch : channelNames(/*serial_only=*/true))
    if (publisherOf(ch, config().phase) == process) return true;
  return false;
}

void LoggerNode::onPeerStatus(const process_status_t& st) {
  if (!log_file_ || !isProcessName(st.process)) return;
  const std::int64_t request = runConfigMessage().digest;
  if (st.run_id == runId() && st.config_digest == request) {
    log_file_->sawProcess(st.process, st.pid);
    if (publishes(st.process)) left_.emplace(st.process, false);  // its final counts matter
  } else if (st.counts_run == runId() && st.counts_config == request && left_.count(st.process)) {
    left_[st.process] = true;  // it left the run: its counts are final
    // Only the run's STOP makes a process leave with final counts: this logger did not have it (lost, or the
    // logger was paused through it and its datagram dropped). It closes the log as on STOP.
    if (state() == process_status_t::RUNNING && !stopTaken()) {
      log_->warn("run '{}': {} left the run (its final counts) but no STOP came here: closing the log once nothing "
                 "is missing", runId(), st.process);
      takeStop();
    }
  }
}

void LoggerNode::write(const Envelope& e) {
  if (!log_file_) return;
  try {
    log_file_->write(e.channel, e.data, static_cast<std::uint32_t>(e.size), e.recv_utime);
  } catch (const std::exception& ex) {
    if (write_error_.empty()) write_error_ = ex.what();
    throw;  // the edge fails the run with it
  }
  if (e.channel == ch::result.name || e.channel == ch::extrinsicResult.name) ended_ = true;
}

bool LoggerNode::readyToLeave() {
  if (!log_file_ || !write_error_.empty()) return true;
  if (edge().missing() > 0) return false;
  for (const auto& [process, left] : left_)
    if (!left) return false;
  return true;
}

void LoggerNode::onLeaveTimeout() {
  std::string who;
  for (const auto& [process, left] : left_)
    if (!left) who += " " + process;
  log_->warn("closing the log of run '{}' with {} messages still missing{}{}", runId(), edge().missing(),
             who.empty() ? "" : "; no final count from:", who);
}

void LoggerNode::onStop() {
  if (!log_file_ && !closed_dir_.empty()) setState(process_status_t::DONE, closed_dir_);
  if (!log_file_) return;
  nlohmann::json missing = nlohmann::json::object();
  for (const auto& [channel, range] : edge().missingRanges())
    missing[channel] = {{"first", range.first}, {"last", range.second - 1}};
  std::string why;
  if (!write_error_.empty())
    why = "a write failed: " + write_error_;
  else if (!missing.empty())
    why = "messages are missing (see \"missing\")";
  else if (!ended_)
    why = "the run did not end: it was stopped before its last step";
  const std::string dir = log_file_->dir();
  try {
    log_file_->close(why, missing);
    log_->info("closed {} ({} events){}", log_file_->path(), log_file_->events(), why.empty() ? "" : ": incomplete, " + why);
  } catch (const std::exception& e) {
    log_->error("closing {}: {}", log_file_->path(), e.what());
    if (why.empty()) why = e.what();
  }
  log_file_.reset();
  if (write_error_.empty()) setState(process_status_t::DONE, dir);
}

void LoggerNode::restartPositions(process_status_t& st) const {
  for (const EdgeInbound::Position& p : edge().positions()) {
    st.takes.push_back(p.channel);
    st.takes_from.push_back(p.next);
  }
  st.n_takes = static_cast<int32_t>(st.takes.size());
}

}  // namespace afford

#include "experiment/run/runners.hpp"

#include <algorithm>

#include "afford/names.hpp"
#include "afford/processes.hpp"
#include "afford/protocol.hpp"

namespace afford {

using std::chrono::milliseconds;

RunnerBeat::RunnerBeat(Edge& edge, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol)
    : edge_(edge), log_(std::move(log)), protocol_(&protocol), runners_(Instance::self(kRunnerName)) {}

bool RunnerBeat::heard(const process_status_t& m) {
  const auto now = Clock::now();
  if (m.process != kRunnerName) {
    if (isProcessName(m.process)) processes_.heard(m, now, protocol_->limits.peers, forgotten_);
    return false;
  }
  const Instance who = Instance::of(m);
  switch (runners_.heard(m, now, protocol_->limits.peers, forgotten_)) {
    case Copies::Heard::Nothing:
      break;
    case Copies::Heard::New:
      answer_ = true;  // named in the next beat, at once
      if (who.before(runners_.self()))  // until it answers (it names this one), or is found not to be alive
        quiet_from_ = std::max(quiet_from_, now);
      log_->warn("another runner on this bus: {} (run {}): {}", who.text(),
                 m.run_id.empty() ? "-" : printable(m.run_id, 200),
                 who.before(runners_.self())
                     ? "started before this one, which is refused once that one answers it (a recording's beat does not)"
                     : "started after this one, which goes on (the later one is refused)");
      break;
    case Copies::Heard::Refuse:
      refusal_ = "another runner (" + who.text() + ", run " + (m.run_id.empty() ? "-" : printable(m.run_id, 200)) +
                 ") is driving this bus; wait for it to finish or use another group";
      log_->error("{}", refusal_);
      break;
  }
  return true;
}

bool RunnerBeat::refusingCopy(const process_status_t& m) {
  const Instance who = Instance::of(m);
  if (who.host.empty() || !processes_.refuses(who, Clock::now(), live())) return false;
  if (said_.insert(m.process + " " + who.id()).second) {
    std::string others;
    for (const Instances::Entry* e : processes_.live(m.process, Clock::now(), live()))
      if (!(e->who == who)) others += (others.empty() ? "" : ", ") + e->who.text();
    log_->warn("two copies of {} on this bus: {} and {}, started later, which refuses to serve: the run is not "
               "given to it",
               m.process, others, who.text());
  }
  return true;
}

bool RunnerBeat::anotherServes(const process_status_t& m, const std::string& run_id, std::int64_t request) const {
  const Instance who = Instance::of(m);
  if (who.host.empty() || !m.run_id.empty() || m.state != process_status_t::WAITING) return false;
  for (const Instances::Entry* e : processes_.live(m.process, Clock::now(), milliseconds(protocol_->heartbeat_ms)))
    if (!(e->who == who) && e->run_id == run_id && e->config_digest == request) return true;
  return false;
}

std::string RunnerBeat::mixed(const std::string& run_id, std::int64_t request,
                              const std::vector<std::string>& processes) const {
  const auto now = Clock::now();
  for (const std::string& p : processes) {
    std::vector<const Instances::Entry*> in;
    for (const Instances::Entry* e : processes_.live(p, now, live()))
      if (e->run_id == run_id && e->config_digest == request && !processes_.refuses(e->who, now, live()))
        in.push_back(e);
    // Two of them heard together (each since the other was first heard): not one restarted after the other.
    for (std::size_t i = 0; i < in.size(); ++i)
      for (std::size_t j = i + 1; j < in.size(); ++j)
        if (in[i]->at > in[j]->first && in[j]->at > in[i]->first)
          return "two copies of " + p + " take part in this run: " + in[i]->who.text() + " and " + in[j]->who.text() +
                 ", which do not hear each other (neither names the other); stop one of them";
  }
  return "";
}

bool RunnerBeat::settled() const {
  return beaten_ && refusal_.empty() && Clock::now() - quiet_from_ >= 2 * milliseconds(protocol_->heartbeat_ms);
}

bool RunnerBeat::due(int stage) const { return !beaten_ || answer_ || stage != stage_ || Clock::now() >= next_; }

void RunnerBeat::beat(int stage, const Doing& doing) {
  const auto now = Clock::now();
  const std::size_t text = static_cast<std::size_t>(protocol_->limits.text_bytes);
  // The furthest step of the run heard (processes that have left it say no step of it).
  step_ = doing.run_id == run_ && doing.request == request_ ? std::max(step_, doing.step) : doing.step;
  run_ = doing.run_id;
  request_ = doing.request;
  process_status_t st{};
  st.run_id = doing.run_id;
  st.step = step_;
  st.process = kRunnerName;
  st.pid = runners_.self().pid;
  st.beat = beats_++;
  st.state = process_status_t::RUNNING;
  st.config_digest = doing.request;
  st.detail = doing.detail.substr(0, text);
  st.counts_config = 0;
  st.n_channels = 0;  // it publishes no run channel: it claims no counts
  st.n_takes = 0;
  st.host = runners_.self().host;
  st.started = runners_.self().started;
  st.copies = runners_.named(now, live());
  st.n_copies = static_cast<std::int32_t>(st.copies.size());
  edge_.send(ch::status, st);
  if (!beaten_) quiet_from_ = now;
  beaten_ = true;
  answer_ = false;
  stage_ = stage;
  next_ = now + milliseconds(protocol_->heartbeat_ms);
}

}  // namespace afford

#include "afford/node.hpp"

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <sstream>

#include "afford/channels.hpp"
#include "afford/logging.hpp"
#include "afford/resend_t.hpp"

namespace afford {

NodeBase::NodeBase(lcm::LCM& lcm, std::string process, std::shared_ptr<spdlog::logger> log)
    : lcm_(lcm), log_(std::move(log)), process_(std::move(process)) {
  subscribeRaw("RUN_CONFIG", [this](const lcm::ReceiveBuffer* b, const std::string&) { onRunConfig(b); }, 100);
  subscribeRaw("RUN_CONTROL", [this](const lcm::ReceiveBuffer* b, const std::string&) { onRunControl(b); }, 100);
  subscribeRaw(channel::kStatus, [this](const lcm::ReceiveBuffer* b, const std::string&) { onStatus(b); }, 1000);
  subscribeRaw(channel::kResend, [this](const lcm::ReceiveBuffer* b, const std::string&) { onResend(b); }, 1000);
}

void NodeBase::subscribeRaw(const std::string& channel_regex,
                            std::function<void(const lcm::ReceiveBuffer*, const std::string&)> handler, int queue) {
  auto holder = std::make_unique<Holder>();
  holder->fn = std::move(handler);
  holder->sub = lcm_.subscribe(channel_regex, &Holder::on, holder.get());
  holder->sub->setQueueCapacity(queue);
  holders_.push_back(std::move(holder));
}

NodeBase::~NodeBase() {
  for (const auto& h : holders_) lcm_.unsubscribe(h->sub);
}

void NodeBase::drop(const std::string& channel, const std::string& reason) {
  log_->warn("{}: dropped message: {}", channel, reason);
}

bool NodeBase::acceptRun(const std::string& channel, const std::string& run_id) {
  if (state_ == process_status_t::WAITING) {
    log_->debug("{}: ignored message of run '{}': no run configured", channel, run_id);
    return false;
  }
  if (run_id != run_id_) {
    drop(channel, "unknown run id '" + run_id + "' (this process serves run '" + run_id_ + "')");
    return false;
  }
  return true;
}

void NodeBase::onRunConfig(const lcm::ReceiveBuffer* rbuf) {
  run_config_t msg;
  std::string reason;
  if (!decodeAtEdge(rbuf, msg, reason)) return drop("RUN_CONFIG", reason);
  if (state_ != process_status_t::WAITING) {
    if (msg.run_id == run_id_) {
      publishStatus();  // a repeated config: confirm we have it
      return;
    }
    return drop("RUN_CONFIG", "run '" + msg.run_id + "' ignored: this process serves run '" + run_id_ + "'");
  }
  try {
    RunConfig cfg = parseRunConfigText(msg.config_yaml);
    if (cfg.seed != msg.seed || toString(cfg.system) != msg.system || cfg.experiment != msg.experiment)
      throw ConfigError("message fields (seed, system, experiment) disagree with config_yaml");
    config_ = std::move(cfg);
    run_msg_ = msg;
    run_id_ = msg.run_id;
    last_step_ = -1;
    forgetRun();
    history_run_ = run_id_;
    onConfigured(config_);
  } catch (const std::exception& e) {
    run_id_.clear();
    log_->error("RUN_CONFIG: rejected run '{}': {}", msg.run_id, e.what());
    detail_ = e.what();
    state_ = process_status_t::WAITING;
    process_status_t st;
    st.run_id = msg.run_id;
    st.step = -1;
    st.process = process_;
    st.pid = static_cast<int32_t>(getpid());
    st.state = process_status_t::FAILED;
    st.detail = e.what();
    st.n_channels = 0;  // nothing published in that run
    lcm_.publish("STATUS", &st);
    return;
  }
  log_->info("configured for run '{}' ({} {} seed {}, {} steps)", run_id_, msg.experiment, msg.system, msg.seed,
             config_.steps);
  setState(process_status_t::READY);
}

void NodeBase::onRunControl(const lcm::ReceiveBuffer* rbuf) {
  run_control_t msg;
  std::string reason;
  if (!decodeAtEdge(rbuf, msg, reason)) return drop("RUN_CONTROL", reason);
  if (!acceptRun("RUN_CONTROL", msg.run_id)) return;
  if (msg.command == run_control_t::START) {
    if (state_ != process_status_t::READY) return;  // already started: idempotent
    setState(process_status_t::RUNNING);
    onStart();
    retryDeferred();  // messages that came before START
  } else if (msg.command == run_control_t::STOP) {
    if (readyToLeave()) return leaveRun();
    if (!stop_pending_) stop_deadline_ = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    stop_pending_ = true;
  } else {
    drop("RUN_CONTROL", "unknown command " + std::to_string(msg.command));
  }
}

void NodeBase::leaveRun() {
  if (state_ == process_status_t::WAITING) return;
  onStop();
  log_->info("left run '{}' at step {}", run_id_, last_step_);
  deferred_.clear();
  stop_pending_ = false;
  run_id_.clear();
  last_step_ = -1;
  setState(process_status_t::WAITING, detail_);
}

void NodeBase::setState(int8_t state, const std::string& detail) {
  state_ = state;
  detail_ = detail;
  publishStatus();
}

void NodeBase::publishStatus() {
  process_status_t st;
  st.run_id = run_id_;
  st.step = last_step_;
  st.process = process_;
  st.pid = static_cast<int32_t>(getpid());
  st.state = state_;
  st.detail = detail_;
  st.counts_run = history_run_;
  for (const auto& [channel, h] : history_) {
    st.channels.push_back(channel);
    st.counts.push_back(static_cast<int64_t>(h.size()));
  }
  st.n_channels = static_cast<int32_t>(st.channels.size());
  lcm_.publish("STATUS", &st);
  next_beat_ = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
}

void NodeBase::tick() {
  if (std::chrono::steady_clock::now() >= next_beat_) publishStatus();
  if (!run_id_.empty()) askMissing();
  if (stop_pending_ && (readyToLeave() || std::chrono::steady_clock::now() > stop_deadline_)) {
    if (!readyToLeave()) onLeaveTimeout();
    leaveRun();
  }
}

// ---- reliable delivery -------------------------------------------------------

void NodeBase::forgetRun() {
  serials_.reset();
  history_.clear();
  deferred_.clear();
  history_run_.clear();
}

bool NodeBase::inSerialOrder(const std::string& channel, std::int64_t serial) {
  switch (serials_.offer(channel, serial)) {
    case SerialTracker::Verdict::Repeat:
      log_->debug("{}: serial {} already had (a repeat)", channel, serial);
      return false;
    case SerialTracker::Verdict::Gap:
      log_->debug("{}: serial {} came before serial {}: asking again for the missing ones", channel, serial,
                  serials_.expected(channel));
      askMissing();
      return false;
    case SerialTracker::Verdict::Accept:
      if (serials_.missing() > 0) askMissing();
      return true;
  }
  return false;
}

void publishResend(lcm::LCM& lcm, const std::string& run_id, const SerialTracker::Request& r,
                   const std::string& requester) {
  resend_t m;
  m.run_id = run_id;
  m.step = 0;
  m.channel = r.channel;
  m.first = r.first;
  m.last = r.last;
  m.requester = requester;
  lcm.publish(channel::kResend, &m);
}

void NodeBase::askMissing() {
  for (const SerialTracker::Request& r : serials_.due(std::chrono::steady_clock::now())) {
    log_->debug("{}: asking for serials {}..{}", r.channel, r.first, r.last);
    publishResend(lcm_, run_id_, r, process_);
  }
}

void NodeBase::onStatus(const lcm::ReceiveBuffer* rbuf) {
  if (run_id_.empty()) return;
  process_status_t st;
  std::string reason;
  if (!decodeAtEdge(rbuf, st, reason)) return drop(channel::kStatus, reason);
  if (st.counts_run != run_id_ || st.process == process_) return;
  bool any = false;
  for (int i = 0; i < st.n_channels; ++i)
    if (std::find(tracked_.begin(), tracked_.end(), st.channels[i]) != tracked_.end()) {
      serials_.announce(st.channels[i], st.counts[i]);
      any = true;
    }
  if (any) askMissing();
}

void NodeBase::onResend(const lcm::ReceiveBuffer* rbuf) {
  resend_t r;
  std::string reason;
  if (!decodeAtEdge(rbuf, r, reason)) return drop(channel::kResend, reason);
  if (r.run_id.empty() || r.run_id != history_run_) return;
  auto it = history_.find(r.channel);
  if (it == history_.end()) return;  // another process's channel
  const auto& h = it->second;
  constexpr std::int64_t kMostAtOnce = 128;
  const std::int64_t first = std::max<std::int64_t>(0, r.first);
  const std::int64_t last = std::min({r.last, first + kMostAtOnce - 1, static_cast<std::int64_t>(h.size()) - 1});
  if (first > last) return;
  log_->debug("{}: publishing serials {}..{} again for {}", r.channel, first, last, r.requester);
  for (std::int64_t i = first; i <= last; ++i)
    lcm_.publish(r.channel, h[static_cast<std::size_t>(i)].data(), static_cast<unsigned>(h[static_cast<std::size_t>(i)].size()));
}

void NodeBase::dispatch(const std::string& channel, std::function<void()> call) {
  // A channel's messages keep their order: behind a deferred one, a message waits too.
  const bool queued = std::any_of(deferred_.begin(), deferred_.end(),
                                  [&](const Deferred& d) { return d.channel == channel; });
  bool handled_now = false;
  if (!queued) {
    defer_now_ = false;
    call();
    handled_now = !defer_now_;
    defer_now_ = false;
  }
  if (!handled_now) {
    constexpr std::size_t kMostDeferred = 100000;
    if (deferred_.size() >= kMostDeferred)
      return drop(channel, "more than " + std::to_string(kMostDeferred) + " messages wait for their turn");
    deferred_.push_back({channel, std::move(call)});
    if (!queued) return;
  }
  retryDeferred();
}

void NodeBase::retryDeferred() {
  if (retrying_ || deferred_.empty()) return;
  retrying_ = true;
  for (bool progress = true; progress && !deferred_.empty() && !run_id_.empty();) {
    progress = false;
    std::vector<Deferred> waiting = std::move(deferred_);
    deferred_.clear();
    std::vector<std::string> blocked;  // channels whose earlier message still waits
    for (Deferred& d : waiting) {
      if (run_id_.empty()) break;  // the run ended in a handler
      if (std::find(blocked.begin(), blocked.end(), d.channel) != blocked.end()) {
        deferred_.push_back(std::move(d));
        continue;
      }
      defer_now_ = false;
      d.call();
      if (defer_now_) {
        blocked.push_back(d.channel);
        deferred_.push_back(std::move(d));
      } else {
        progress = true;
      }
    }
    defer_now_ = false;
  }
  retrying_ = false;
}

// ---- process main ------------------------------------------------------------

namespace {
volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }
}  // namespace

bool stopRequested() { return g_stop != 0; }
void installStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void CLIHook::option(const std::string& name, std::string& target, const std::string& help) {
  static_cast<CLI::App*>(app_)->add_option(name, target, help)->capture_default_str();
}

int processMain(int argc, char** argv, const ProcessSpec& spec, const std::function<void(CLIHook&)>& add_options,
                const std::function<std::unique_ptr<NodeBase>(lcm::LCM&, std::shared_ptr<spdlog::logger>)>& make_node) {
  CLI::App app{spec.description, "afford-" + spec.name};
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::string level = "info";
  app.add_option("--lcm-url", url, "LCM provider URL of the run (one UDP port per run)")->capture_default_str();
  app.add_option("--log-level", level, "trace, debug, info, warn, error or off")->capture_default_str();
  CLIHook hook(&app);
  add_options(hook);
  CLI11_PARSE(app, argc, argv);

  std::shared_ptr<spdlog::logger> log;
  try {
    log = makeLogger(spec.name, level);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "afford-%s: --log-level: %s\n", spec.name.c_str(), e.what());
    return 2;
  }
  installStopHandlers();
  cv::setNumThreads(0);  // images are 150 x 150: a thread pool only adds wake-ups
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    log->error("cannot open LCM at '{}' (is there a multicast route? see README: network namespace)", url);
    return 1;
  }
  std::unique_ptr<NodeBase> node;
  try {
    node = make_node(lcm, log);
  } catch (const std::exception& e) {
    log->error("cannot start: {}", e.what());
    return 1;
  }
  log->info("listening on {}", url);
  while (!stopRequested()) {
    lcm.handleTimeout(100);
    node->tick();
  }
  node->leaveRun();
  node.reset();
  log->info("stopped");
  return 0;
}

}  // namespace afford

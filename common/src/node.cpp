#include "afford/node.hpp"

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>
#include <unistd.h>

#include <csignal>
#include <sstream>

#include "afford/logging.hpp"

namespace afford {

NodeBase::NodeBase(lcm::LCM& lcm, std::string process, std::shared_ptr<spdlog::logger> log)
    : lcm_(lcm), log_(std::move(log)), process_(std::move(process)) {
  subscribeRaw("RUN_CONFIG", [this](const lcm::ReceiveBuffer* b, const std::string&) { onRunConfig(b); }, 100);
  subscribeRaw("RUN_CONTROL", [this](const lcm::ReceiveBuffer* b, const std::string&) { onRunControl(b); }, 100);
}

void NodeBase::subscribeRaw(const std::string& channel_regex,
                            std::function<void(const lcm::ReceiveBuffer*, const std::string&)> handler, int queue) {
  auto holder = std::make_unique<Holder>();
  holder->fn = std::move(handler);
  lcm::Subscription* s = lcm_.subscribe(channel_regex, &Holder::on, holder.get());
  s->setQueueCapacity(queue);
  holders_.push_back(std::move(holder));
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
  } else if (msg.command == run_control_t::STOP) {
    leaveRun();
  } else {
    drop("RUN_CONTROL", "unknown command " + std::to_string(msg.command));
  }
}

void NodeBase::leaveRun() {
  if (state_ == process_status_t::WAITING) return;
  onStop();
  log_->info("left run '{}' at step {}", run_id_, last_step_);
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
  lcm_.publish("STATUS", &st);
  next_beat_ = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
}

void NodeBase::tick() {
  if (std::chrono::steady_clock::now() >= next_beat_) publishStatus();
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

#include "experiment/watch/live.hpp"

#include <lcm/lcm-cpp.hpp>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "afford/bus.hpp"
#include "afford/edge.hpp"
#include "afford/logging.hpp"
#include "afford/protocol.hpp"
#include "experiment/watch/sampler.hpp"
#include "viewer/feed.hpp"

namespace afford {

void lowerThreadPriority(int nice) {
  if (nice > 0 && setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice) != 0)
    std::fprintf(stderr, "afford watch: cannot lower its priority (--nice %d): %s\n", nice, std::strerror(errno));
}

namespace {

// One bus's feed into the shared state: its run's pictures only while its run is the one shown (several
// buses say several runs at once); every run's configuration, status and result (the runs heard).
class BusView : public RunView {
 public:
  explicit BusView(WatchState& state) : state_(state) {}
  void onRun(const std::string& run_id, const std::string& title) override {
    run_ = run_id;
    state_.onRun(run_id, title);
  }
  void onScene(std::int64_t step, const cv::Mat& rgb, bool goal) override {
    if (shown()) state_.onScene(step, rgb, goal);
  }
  void onSceneData(std::int64_t step, const std::vector<std::uint8_t>& data, int width, int height,
                   bool goal) override {
    if (shown()) state_.onSceneData(step, data, width, height, goal);
  }
  void onFocus(std::int64_t step, const std::vector<std::uint8_t>& image, int side, double x, double y,
               bool goal) override {
    if (shown()) state_.onFocus(step, image, side, x, y, goal);
  }
  void onPrediction(std::int64_t step, const std::array<double, 4>& affordance) override {
    if (shown()) state_.onPrediction(step, affordance);
  }
  void onDecision(std::int64_t step, bool acted, int action, double motivation, double threshold) override {
    if (shown()) state_.onDecision(step, acted, action, motivation, threshold);
  }
  void onGoal(std::int64_t step, int id, const std::string& module, const std::vector<std::uint8_t>& image, int side,
              double x, double y) override {
    if (shown()) state_.onGoal(step, id, module, image, side, x, y);
  }
  void onGoalResult(std::int64_t step, int id, const std::string& module, bool reached) override {
    if (shown()) state_.onGoalResult(step, id, module, reached);
  }
  void onTable(const affordance_table_t& m) override {
    if (shown()) state_.onTable(m);
  }
  void onConfig(const run_config_t& m, const RunConfig& config) override { state_.onConfig(m, config); }
  void onStatus(const process_status_t& m) override { state_.onStatus(m); }
  void onResult(const run_result_t& m) override { state_.onResult(m); }
  void onExtrinsicResult(const extrinsic_result_t& m) override { state_.onExtrinsicResult(m); }

 private:
  bool shown() const { return state_.shows(run_); }
  WatchState& state_;
  std::string run_;
};

}  // namespace

struct LiveWatch::Listener {
  std::unique_ptr<lcm::LCM> bus;
  std::unique_ptr<Edge> edge;
  std::unique_ptr<BusView> view;
  std::unique_ptr<ViewFeed> feed;
  std::unique_ptr<StepSampler> sampler;
};

LiveWatch::LiveWatch(const ProtocolConfig& protocol, LiveWatchOptions options)
    : protocol_(protocol), options_(std::move(options)), key_(busKeyFrom(options_.bus_key)),
      server_(state_, options_.server), log_(makeLogger("watch", "info")) {}

LiveWatch::~LiveWatch() { stop(); }

void LiveWatch::serve() {
  // Its threads are made by one of lower priority, and take it (a thread's priority is its maker's).
  std::exception_ptr failed;
  std::thread maker([&] {
    lowerThreadPriority(options_.nice);
    try {
      server_.start();
    } catch (...) {
      failed = std::current_exception();
    }
  });
  maker.join();
  if (failed) std::rethrow_exception(failed);
}

void LiveWatch::listen(const std::vector<std::string>& urls) {
  const auto gap = std::chrono::duration_cast<StepSampler::Clock::duration>(
      std::chrono::duration<double>(1.0 / options_.server.most_per_second));
  for (const std::string& given : urls) {
    auto l = std::make_unique<Listener>();
    // The bus's datagrams taken every batch_ms, not one at a time: a watcher woken for each would take the
    // run's CPU (third_party/lcm patch 0011); what a page is sent (5 states a second) does not change.
    const std::string url = options_.batch_ms > 0 ? withBusOption(given, "receive_batch_ms", options_.batch_ms) : given;
    l->bus = openBus(url, protocol_.bus);
    l->edge = std::make_unique<Edge>(*l->bus, log_, "watch", protocol_);
    l->edge->useKey(key_);
    l->view = std::make_unique<BusView>(state_);
    l->feed = std::make_unique<ViewFeed>(*l->view, protocol_, "", options_.say_runs ? log_.get() : nullptr);
    l->feed->subscribe(*l->edge, false);
    Edge& edge = *l->edge;
    l->sampler = std::make_unique<StepSampler>(
        state_,
        [&edge](bool on) {
          edge.take(ch::focus.name, on);
          edge.take(ch::prediction.name, on);
        },
        gap);
    listeners_.push_back(std::move(l));
  }
  for (std::size_t k = threads_.size(); k < listeners_.size(); ++k)
    threads_.emplace_back([this, l = listeners_[k].get()] {
      lowerThreadPriority(options_.nice);
      while (!stopping_) {
        pumpBus(*l->bus, 50);
        l->sampler->tick(StepSampler::Clock::now());
      }
      // What the bus said before the stop (a run's last result), held by the batching receiver meanwhile.
      pumpBus(*l->bus, options_.batch_ms + 50);
      while (pumpBus(*l->bus, 0) > 0) {
      }
    });
}

void LiveWatch::stop() {
  if (stopping_.exchange(true)) return;
  for (auto& t : threads_) t.join();
  server_.flush(std::chrono::seconds(2));  // the pages following are sent the end they heard
  server_.stop();
}

}  // namespace afford

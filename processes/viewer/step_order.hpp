// A run's messages in step order, whatever their order in its log. The logger
// records each channel in serial order, but how the channels interleave is not
// guaranteed (after a loss and RESEND, or in a restarted logger's later
// segment, one channel can run far ahead of another): a tool that drew or
// exported a run in log order paired one step's scene with another step's
// focus. Here every message is placed by its content alone: the step it
// belongs to, then its channel's place in a step; each channel keeps its own
// order. So what `afford render`, `afford watch --log`, `afford export` and
// `afford.read_log` make of a log depends on what it holds, not on how its
// channels were interleaved.
#pragma once
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "afford/bounds.hpp"
#include "afford/logfile.hpp"
#include "afford/logging.hpp"
#include "afford/phase.hpp"

namespace afford {

// Where a message of a run goes in step order.
struct StepKey {
  static constexpr std::int64_t kBefore = std::numeric_limits<std::int64_t>::min();  // RUN_CONFIG, START
  static constexpr std::int64_t kAfter = std::numeric_limits<std::int64_t>::max();   // STOP
  std::int64_t step = kBefore;  // the step the message belongs to
  int rank = 0;                 // its channel's place within a step (stepRank)
  bool operator<(const StepKey& o) const { return step != o.step ? step < o.step : rank < o.rank; }
};

// A channel's place within a step, as a step goes out: RUN_CONFIG, RUN_CONTROL,
// PROBE, SCENE, EFFECT, GOAL_RESULT, GOAL, LOOK, FOCUS, AFFORDANCE_TABLE,
// PREDICTION, FORWARD_QUERY, FORWARD_PREDICTION, DECISION, EXTRINSIC_RESULT,
// RESULT, then STATUS and any other channel.
int stepRank(const std::string& channel);

// The key of a run's message from its content: its step; an EFFECT's is the
// step after its action's (the scene it was seen on), but in the extrinsic
// phase, whose action's scene has the action's step; RUN_CONFIG and START go
// before the first step, STOP after the last. Nothing if the content cannot be
// trusted to say (a digest that does not match, fields that do not read).
std::optional<StepKey> stepKeyOf(const LogEvent& e, Phase phase, const BoundsContext& ctx);

// One channel's steps in order, held as runs of a constant difference: a
// channel said every step costs a few bytes, whatever the run's length.
class StepTrail {
 public:
  void add(std::int64_t step);
  std::int64_t size() const { return size_; }
  std::int64_t last() const { return last_; }
  std::size_t runs() const { return runs_.size(); }  // what it holds: a run is 24 bytes
  // The i-th step, read in order: `at` is moved along (start it at {}).
  struct At {
    std::size_t run = 0;
    std::int64_t in_run = 0;
  };
  std::int64_t step(const At& at) const;
  void advance(At& at) const;

 private:
  struct Run {
    std::int64_t first;
    std::int64_t delta;
    std::int64_t count;
  };
  std::vector<Run> runs_;
  std::int64_t size_ = 0, last_ = 0;
};

// A run of a log, given in step order. The log is read up to the run's
// RUN_CONFIG, once through for the key of every message of the run
// (StepTrail: a few bytes a channel), then as the messages are given, holding
// only those read ahead of their turn (none for a log recorded in step order;
// a channel's lead where one ran ahead).
class StepOrdered {
 public:
  // One reading of the log from its start, in the log's order: `next` gives its
  // next event (false after the last), `take` says whether an event is the
  // run's (the run's RUN_CONFIG first, then the run's own events). Events of
  // the run's id before its RUN_CONFIG are the run's too.
  struct Pass {
    std::function<bool(LogEvent&)> next;
    std::function<bool(const LogEvent&)> take;
    std::function<void()> read_through;  // (optional) called when the first full reading has read the log to its end
  };
  // `open(quiet)` begins a reading; `quiet`: the first one, which must say
  // nothing of what it skips (the second one says it). `protocol` bounds what
  // is decoded for a key (RUN_CONFIG, RUN_CONTROL, STATUS).
  StepOrdered(std::function<Pass(bool quiet)> open, const ProtocolConfig& protocol);

  // The run's next message in step order, and its key; false after the last
  // (the log is then read to its end). Throws std::runtime_error if the log
  // changed between the two readings.
  bool next(LogEvent& e, StepKey& key);
  // From the first message again (the keys are kept: the log is read once more, not twice).
  void rewind();

  Phase phase() const { return phase_; }
  // The first and last step of the run's messages (RUN_CONFIG and RUN_CONTROL aside); -1 if none.
  std::int64_t firstStep() const { return first_step_; }
  std::int64_t lastStep() const { return last_step_; }
  // The events of this reading that are not the run's (other runs', before its RUN_CONFIG), so far.
  std::int64_t leftOut() const { return left_out_; }
  // The most messages held at once, read ahead of their turn, in this reading.
  std::size_t mostHeld() const { return most_held_; }

 private:
  struct Channel {
    std::string name;
    int rank = 0;
    StepTrail trail;
    StepTrail::At at;
    std::int64_t given = 0;
    std::deque<LogEvent> held;
  };
  Channel& channelOf(const std::string& name);
  // Is the event at `at` in the reading the run's?
  bool ofRun(Pass& pass, const LogEvent& e, std::int64_t at) const;
  // Reads on until `c` has a message held; false if the reading ends first.
  bool readFor(Channel& c);

  std::function<Pass(bool)> open_;
  int name_bytes_;
  Pass pass_;
  std::int64_t read_ = 0;       // events of this reading so far
  std::int64_t config_at_ = -1;  // the run's RUN_CONFIG among the log's events
  std::string run_id_;
  Phase phase_ = Phase::Intrinsic;
  std::vector<Channel> channels_;
  std::map<std::string, std::size_t> index_;
  std::int64_t first_step_ = -1, last_step_ = -1, left_out_ = 0;
  std::size_t held_ = 0, most_held_ = 0;
  bool ended_ = false;
};

// A log read by `Stream` (bool next(LogEvent&): the log's events in its order;
// std::vector<std::string> cutShort(const Selector&): what the log lacks of the
// run, once read) for the run `Selector` chooses (bool take(const LogEvent&)),
// given in step order; both are made anew for each reading, the first with a
// logger that says nothing. stream() and selector() are the current reading's:
// what it skipped, the run's configuration.
template <class Stream, class Selector>
class StepOrderedLog {
 public:
  using MakeStream = std::function<std::unique_ptr<Stream>(spdlog::logger&)>;
  using MakeSelector = std::function<std::unique_ptr<Selector>(spdlog::logger&)>;
  StepOrderedLog(MakeStream stream, MakeSelector selector, const ProtocolConfig& protocol, spdlog::logger& log)
      : quiet_(makeLogger("quiet", "off")),
        order_([this, stream, selector, &log](bool quiet) { return open(stream, selector, quiet ? *quiet_ : log); },
               protocol) {
    for (const std::string& c : cut_) log.warn("the log is cut: {}", c);
  }
  StepOrderedLog(const StepOrderedLog&) = delete;
  StepOrderedLog& operator=(const StepOrderedLog&) = delete;

  bool next(LogEvent& e, StepKey& key) { return order_.next(e, key); }
  StepOrdered& order() { return order_; }
  const Stream& stream() const { return *stream_; }
  const Selector& selector() const { return *selector_; }
  // What the log lacks of its run (Stream::cutShort(Selector): a log cut short), found by the first full
  // reading and said as warnings when the log is opened; empty for a whole log.
  const std::vector<std::string>& cut() const { return cut_; }

 private:
  StepOrdered::Pass open(const MakeStream& stream, const MakeSelector& selector, spdlog::logger& log) {
    stream_ = stream(log);
    selector_ = selector(log);
    return {[this](LogEvent& e) { return stream_->next(e); }, [this](const LogEvent& e) { return selector_->take(e); },
            [this] { cut_ = stream_->cutShort(*selector_); }};
  }

  std::shared_ptr<spdlog::logger> quiet_;
  std::unique_ptr<Stream> stream_;
  std::unique_ptr<Selector> selector_;
  std::vector<std::string> cut_;
  StepOrdered order_;  // (last: its first reading is made as it is built)
};

}  // namespace afford

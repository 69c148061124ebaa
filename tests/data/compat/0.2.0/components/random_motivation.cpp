// A motivation of one's own, in a process of one's own (docs/writing-a-component.md):
// "random" acts at every step, with an action drawn uniformly for the step.
// Run it in place of the shipped motivation process:
//   afford experiment base --set motivation.kind=random --process motivation=build/bin/random-motivation
// The draw is keyed by (seed, step, purpose), so replay and live restart
// make it again; the component keeps no state at all.
#include "motivation/component.hpp"
#include "motivation/node.hpp"
#include "afford/rng.hpp"
#include "afford/process_main.hpp"

namespace {

class RandomMotivation : public afford::MotivationComponent {
 public:
  explicit RandomMotivation(const afford::MotivationParams& params) : seed_(params.seed) {}

  afford::Decision decide(const afford::Percept& p) override {
    constexpr std::uint64_t kMine = 0x72616e646f6d;  // "random": this component's sub-key
    const afford::KeyedRng rng(seed_, p.step, afford::Purpose::Component, kMine);
    afford::Decision d;
    d.act = true;
    d.action = static_cast<int>(rng.bits(0) % afford::kNumActions);
    d.motivation = 1.0;  // what DECISION reports as the signal, and its threshold
    d.threshold = 0.0;
    return d;
  }

 private:
  std::int64_t seed_;
};

}  // namespace

int main(int argc, char** argv) {
  afford::registerMotivation("random", [](const afford::MotivationParams& p) { return std::make_unique<RandomMotivation>(p); });
  return afford::processMain(
      argc, argv, {"motivation", "a motivation of one's own: a random action at every step (motivation.kind: random)"},
      [](afford::CLIHook&) {},
      [](lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const afford::ProtocolConfig& protocol) {
        return std::make_unique<afford::MotivationNode>(lcm, std::move(log), protocol);
      });
}

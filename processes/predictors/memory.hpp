// The agent's memory of past experiences (issue 11, docs/model.md#memory):
// the experience replay the paper proposes in section 3.1.2 ("replay of past
// experience ... would intermix experience related to the different objects")
// and the revisits of docs/model.md#revisit draw on it. The paper's agent has
// none; the predictors keep one only when replay or revisits are configured.
//
// Experiences are filed by look and action. A look is what the agent has seen
// through its focus window: a remembered focus image (the first one seen of
// it), and any later focus image within predictors.memory.look_threshold of it
// (mean absolute difference per value, allowing a shift of up to look_shift_px
// pixels) is the same look. Each (look, action) keeps its newest
// per_look_action experiences, so an object seen rarely, or no longer in the
// world, keeps its experiences however many others come after. When
// max_looks are remembered, a new look replaces the one seen least recently.
//
// Everything here is a pure function of what it was given, in order; draws
// are keyed by (seed, step, Purpose::Replay, sub). No LCM here.
#pragma once
#include <array>
#include <cstdint>
#include <deque>
#include <iosfwd>
#include <memory>
#include <unordered_map>
#include <vector>

#include "afford/actions.hpp"
#include "afford/checksum.hpp"
#include "afford/config.hpp"
#include "predictors/experience.hpp"

namespace afford {

class Memory {
 public:
  using Ref = std::shared_ptr<const Experience>;  // immutable: the forward-model worker may hold it
  using TriedAgo = std::array<std::int64_t, kNumActions>;

  // Throws ConfigError for max_looks or per_look_action below 1.
  Memory(const MemoryConfig& config, int focus_side);

  // The look of a focus image seen at `step`: the nearest remembered look
  // within look_threshold, or a new one. Returns its index (stable while it is remembered).
  // Throws std::invalid_argument for an image that is not 3 x side x side bytes.
  int see(const std::vector<std::uint8_t>& image, std::int64_t step);
  // The distance see() compares with look_threshold (0..1).
  double distance(const std::vector<std::uint8_t>& image, int look) const;

  // Steps since each action was last tried on `look`, as of `step`; -1: never.
  TriedAgo triedAgo(int look, std::int64_t step) const;

  // An action executed on `look` at `step`, with what came of it.
  void record(int look, std::int64_t step, Ref experience);

  // `count` remembered experiences for replay, keyed by (seed, step, sub).
  // Balanced: a (look, action) uniformly, then one of its experiences;
  // uniform: any experience. `effects_only`: only experiences whose effect was
  // seen (what the forward models learn from). None from an empty memory.
  std::vector<Ref> sample(ReplaySampling sampling, std::int64_t seed, std::int64_t step, std::uint64_t sub,
                          std::size_t count, bool effects_only) const;

  int looks() const;              // looks remembered
  std::size_t experiences() const;  // experiences remembered

  // The whole memory, in a fixed order (checkpoints, checksums): the settings
  // it was kept with, then its looks and their experiences.
  void save(std::ostream& out) const;
  // Restores a saved memory whole, with the settings it was kept with (not
  // necessarily this one's). Throws std::runtime_error naming `what` if the
  // stream is cut short or holds what no memory holds (images of another
  // size, an experience filed under another action, counts beyond its limits).
  void load(std::istream& in, const std::string& what);
  void hash(Fnv1a& h) const;

 private:
  struct Look {
    bool used = false;
    std::vector<std::uint8_t> image;             // the first focus image seen of it
    std::vector<std::pair<int, int>> nonzero;    // (index, value) of its non-zero bytes
    std::array<long, 3> channel_sum{};           // sum of its bytes per colour channel
    std::array<long, 3> border_sum{};            // ... of those within look_shift_px of the window's edge
    std::int64_t last_seen = -1;
    TriedAgo tried_at{-1, -1, -1, -1};           // step each action was last tried on it
    std::array<std::deque<Ref>, kNumActions> experiences;  // newest last
    std::array<int, kNumActions> with_effect{};           // of those, how many had their effect
  };
  void forget(int look);
  void setImage(Look& l, const std::vector<std::uint8_t>& image) const;

  MemoryConfig config_;
  int side_;
  std::vector<Look> looks_;
  // FNV-1a of each remembered look's first image -> the looks with that hash: an image equal to a look's first
  // image is that look (distance 0; two looks are never within the threshold of each other's first image), found
  // without a search. Squares and rectangles look exactly alike wherever they are.
  std::unordered_multimap<std::uint64_t, int> by_image_;
};

}  // namespace afford

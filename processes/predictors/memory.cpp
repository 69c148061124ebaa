#include "predictors/memory.hpp"

#include <algorithm>
#include <cstdlib>
#include <istream>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>

#include "afford/rng.hpp"

namespace afford {
namespace {

std::uint64_t imageHash(const std::vector<std::uint8_t>& image) {
  std::uint64_t h = 0xCBF29CE484222325ull;
  for (std::uint8_t b : image) h = (h ^ b) * 0x100000001B3ull;
  return h;
}

template <class T>
void put(std::ostream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
void get(std::istream& in, T& v) {
  in.read(reinterpret_cast<char*>(&v), sizeof v);
}

void putBytes(std::ostream& out, const std::vector<std::uint8_t>& b) {
  put(out, static_cast<std::uint32_t>(b.size()));
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}
// A damaged file: cut short (truncated), or holding what no memory holds (corrupt).
struct Damaged : std::runtime_error {
  using std::runtime_error::runtime_error;
};
void need(const std::istream& in, const std::string& what) {
  if (!in) throw Damaged("truncated in " + what);
}

// An image of exactly `want` bytes (or, with `or_none`, of none).
std::vector<std::uint8_t> getBytes(std::istream& in, std::size_t want, bool or_none, const std::string& what) {
  std::uint32_t n = 0;
  get(in, n);
  need(in, what);
  if (n != want && !(or_none && n == 0))
    throw Damaged(what + " of " + std::to_string(n) + " bytes, not " + std::to_string(want));
  std::vector<std::uint8_t> b(n);
  in.read(reinterpret_cast<char*>(b.data()), n);
  need(in, what);
  return b;
}

void putExperience(std::ostream& out, const Experience& e) {
  put(out, static_cast<std::int32_t>(e.action));
  put(out, static_cast<std::uint8_t>(e.affordance));
  for (double v : {e.before_x, e.before_y, e.target_x, e.target_y, e.after_x, e.after_y}) put(out, v);
  putBytes(out, e.before_image);
  putBytes(out, e.after_image);
}
// An experience of `action` (the slot it is filed under), with images of `image_bytes`: an after-image only when
// its effect was seen.
Experience getExperience(std::istream& in, int action, std::size_t image_bytes, const std::string& what) {
  Experience e;
  std::int32_t a = 0;
  std::uint8_t affordance = 0;
  get(in, a);
  get(in, affordance);
  for (double* v : {&e.before_x, &e.before_y, &e.target_x, &e.target_y, &e.after_x, &e.after_y}) get(in, *v);
  need(in, what);
  if (a != action) throw Damaged(what + " of action " + std::to_string(a) + ", filed under action " + std::to_string(action));
  if (affordance > 1) throw Damaged(what + " whose effect is " + std::to_string(affordance) + ", not 0 or 1");
  e.action = a;
  e.affordance = affordance != 0;
  e.before_image = getBytes(in, image_bytes, false, what + "'s image");
  e.after_image = getBytes(in, e.affordance ? image_bytes : 0, false, what + "'s image after");
  return e;
}

}  // namespace

Memory::Memory(const MemoryConfig& config, int focus_side) : config_(config), side_(focus_side) {
  if (config.max_looks < 1 || config.per_look_action < 1)
    throw ConfigError("config key 'predictors.memory': max_looks and per_look_action must be at least 1");
  looks_.reserve(static_cast<std::size_t>(std::min(config.max_looks, 4096)));
}

void Memory::setImage(Look& l, const std::vector<std::uint8_t>& image) const {
  l.image = image;
  l.nonzero.clear();
  l.channel_sum = {0, 0, 0};
  l.border_sum = {0, 0, 0};
  const int shift = config_.look_shift_px;
  for (std::size_t i = 0; i < image.size(); ++i)
    if (image[i]) {
      l.nonzero.emplace_back(static_cast<int>(i), image[i]);
      l.channel_sum[i % 3] += image[i];
      const int pixel = static_cast<int>(i / 3), y = pixel / side_, x = pixel % side_;
      if (y < shift || y >= side_ - shift || x < shift || x >= side_ - shift) l.border_sum[i % 3] += image[i];
    }
}

double Memory::distance(const std::vector<std::uint8_t>& image, int look) const {
  const Look& l = looks_.at(static_cast<std::size_t>(look));
  const int side = side_, shift = config_.look_shift_px;
  long total = 0;
  for (std::uint8_t v : image) total += v;
  // sum |a - b'| over all values = sum(a) + sum over b' non-zero of (|a - b'| - a), for b' = b shifted by (dy, dx):
  // b's pixel (y, x) shows at (y - dy, x - dx), and one shifted out of the window is gone.
  long best = std::numeric_limits<long>::max();
  for (int dy = -shift; dy <= shift; ++dy)
    for (int dx = -shift; dx <= shift; ++dx) {
      long s = total;
      for (const auto& [index, value] : l.nonzero) {
        const int pixel = index / 3, y = pixel / side - dy, x = pixel % side - dx;
        if (y < 0 || y >= side || x < 0 || x >= side) continue;
        const int a = image[static_cast<std::size_t>((y * side + x) * 3 + index % 3)];
        s += std::abs(a - value) - a;
      }
      best = std::min(best, s);
    }
  return static_cast<double>(best) / (255.0 * static_cast<double>(image.size()));
}

int Memory::see(const std::vector<std::uint8_t>& image, std::int64_t step) {
  const std::size_t bytes = static_cast<std::size_t>(3 * side_ * side_);
  if (image.size() != bytes)
    throw std::invalid_argument("a focus image of " + std::to_string(image.size()) + " bytes, not " + std::to_string(bytes));
  const std::uint64_t hash = imageHash(image);
  for (auto [it, end] = by_image_.equal_range(hash); it != end; ++it)
    if (looks_[static_cast<std::size_t>(it->second)].image == image) {
      looks_[static_cast<std::size_t>(it->second)].last_seen = step;
      return it->second;
    }
  std::array<long, 3> sum{0, 0, 0};
  for (std::size_t i = 0; i < image.size(); ++i) sum[i % 3] += image[i];
  // Per channel, a shifted look's sum lies between its sum less what lies within `shift` of the border, and its
  // sum: the L1 distance is at least the gap, so a look whose gap alone is too far is not compared.
  int nearest = -1;
  double nearest_distance = config_.look_threshold;
  for (std::size_t k = 0; k < looks_.size(); ++k) {
    const Look& l = looks_[k];
    if (!l.used) continue;
    long gap = 0;
    for (int c = 0; c < 3; ++c)
      gap += std::max({0L, sum[c] - l.channel_sum[c], l.channel_sum[c] - l.border_sum[c] - sum[c]});
    if (static_cast<double>(gap) / (255.0 * static_cast<double>(bytes)) >= nearest_distance) continue;
    const double d = distance(image, static_cast<int>(k));
    if (d < nearest_distance) {
      nearest = static_cast<int>(k);
      nearest_distance = d;
    }
  }
  if (nearest < 0) {  // a new look: a free slot, or the one seen least recently
    for (std::size_t k = 0; k < looks_.size() && nearest < 0; ++k)
      if (!looks_[k].used) nearest = static_cast<int>(k);
    if (nearest < 0 && static_cast<int>(looks_.size()) < config_.max_looks) {
      looks_.emplace_back();
      nearest = static_cast<int>(looks_.size()) - 1;
    }
    if (nearest < 0) {
      nearest = 0;
      for (std::size_t k = 1; k < looks_.size(); ++k)
        if (looks_[k].last_seen < looks_[static_cast<std::size_t>(nearest)].last_seen) nearest = static_cast<int>(k);
      forget(nearest);
    }
    Look& l = looks_[static_cast<std::size_t>(nearest)];
    l.used = true;
    setImage(l, image);
    by_image_.emplace(hash, nearest);
  }
  looks_[static_cast<std::size_t>(nearest)].last_seen = step;
  return nearest;
}

void Memory::forget(int look) {
  Look& l = looks_.at(static_cast<std::size_t>(look));
  for (auto [it, end] = by_image_.equal_range(imageHash(l.image)); it != end; ++it)
    if (it->second == look) {
      by_image_.erase(it);
      break;
    }
  l = Look{};
}

Memory::TriedAgo Memory::triedAgo(int look, std::int64_t step) const {
  const Look& l = looks_.at(static_cast<std::size_t>(look));
  TriedAgo out;
  for (int a = 0; a < kNumActions; ++a) out[a] = l.tried_at[a] < 0 ? -1 : step - l.tried_at[a];
  return out;
}

void Memory::record(int look, std::int64_t step, Ref experience) {
  Look& l = looks_.at(static_cast<std::size_t>(look));
  if (!l.used) throw std::logic_error("an experience of look " + std::to_string(look) + ", which is not remembered");
  const int a = experience->action;
  l.tried_at[a] = step;
  auto& kept = l.experiences[a];
  l.with_effect[a] += experience->affordance;
  kept.push_back(std::move(experience));
  if (static_cast<int>(kept.size()) > config_.per_look_action) {
    l.with_effect[a] -= kept.front()->affordance;
    kept.pop_front();
  }
}

std::vector<Memory::Ref> Memory::sample(ReplaySampling sampling, std::int64_t seed, std::int64_t step,
                                        std::uint64_t sub, std::size_t count, bool effects_only) const {
  // The groups that can be drawn, in look and action order, and how many experiences each offers.
  struct Group {
    const std::deque<Ref>* kept;
    std::size_t offered;
  };
  std::vector<Ref> out;
  if (count == 0) return out;
  std::vector<Group> groups;
  std::size_t total = 0;
  for (const Look& l : looks_) {
    if (!l.used) continue;
    for (int a = 0; a < kNumActions; ++a) {
      const std::size_t n = effects_only ? static_cast<std::size_t>(l.with_effect[a]) : l.experiences[a].size();
      if (n == 0) continue;
      groups.push_back({&l.experiences[a], n});
      total += n;
    }
  }
  if (groups.empty()) return out;
  // The k-th experience a group offers (with effects_only, the k-th of those with an effect).
  const auto pick = [effects_only](const std::deque<Ref>& kept, std::size_t k) {
    for (const Ref& e : kept)
      if (!effects_only || e->affordance) {
        if (k == 0) return e;
        --k;
      }
    return kept.back();  // not reached: k < offered
  };
  const KeyedRng rng(seed, step, Purpose::Replay, sub);
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    if (sampling == ReplaySampling::Balanced) {
      const Group& g = groups[static_cast<std::size_t>(rng.uniform(2 * i) * static_cast<double>(groups.size()))];
      out.push_back(pick(*g.kept, static_cast<std::size_t>(rng.uniform(2 * i + 1) * static_cast<double>(g.offered))));
    } else {
      std::size_t k = static_cast<std::size_t>(rng.uniform(2 * i) * static_cast<double>(total));
      for (const Group& g : groups) {
        if (k < g.offered) {
          out.push_back(pick(*g.kept, k));
          break;
        }
        k -= g.offered;
      }
    }
  }
  return out;
}

int Memory::looks() const {
  return static_cast<int>(std::count_if(looks_.begin(), looks_.end(), [](const Look& l) { return l.used; }));
}

std::size_t Memory::experiences() const {
  std::size_t n = 0;
  for (const Look& l : looks_)
    for (const auto& kept : l.experiences) n += kept.size();
  return n;
}

void Memory::save(std::ostream& out) const {
  // The settings it was kept with, then the looks and their experiences.
  put(out, config_.look_threshold);
  put(out, static_cast<std::int32_t>(config_.look_shift_px));
  put(out, static_cast<std::int32_t>(config_.max_looks));
  put(out, static_cast<std::int32_t>(config_.per_look_action));
  put(out, static_cast<std::uint32_t>(looks_.size()));
  for (const Look& l : looks_) {
    put(out, static_cast<std::uint8_t>(l.used));
    if (!l.used) continue;
    putBytes(out, l.image);
    put(out, l.last_seen);
    for (std::int64_t t : l.tried_at) put(out, t);
    for (const auto& kept : l.experiences) {
      put(out, static_cast<std::uint32_t>(kept.size()));
      for (const Ref& e : kept) putExperience(out, *e);
    }
  }
}

void Memory::load(std::istream& in, const std::string& what) {
  const std::size_t bytes = static_cast<std::size_t>(3 * side_ * side_);
  try {
    MemoryConfig c;
    std::int32_t shift = 0, max_looks = 0, per = 0;
    get(in, c.look_threshold);
    get(in, shift);
    get(in, max_looks);
    get(in, per);
    need(in, "its settings");
    if (!(c.look_threshold >= 0 && c.look_threshold <= 1) || shift < 0 || shift > 10 || max_looks < 1 ||
        max_looks > 100'000 || per < 1 || per > 100'000)
      throw Damaged("settings out of range");
    c.look_shift_px = shift;
    c.max_looks = max_looks;
    c.per_look_action = per;
    std::uint32_t n = 0;
    get(in, n);
    need(in, "its looks");
    if (n > static_cast<std::uint32_t>(c.max_looks))
      throw Damaged(std::to_string(n) + " looks, more than its max_looks " + std::to_string(c.max_looks));
    Memory restored(c, side_);
    restored.looks_.resize(n);
    for (std::uint32_t k = 0; k < n; ++k) {
      Look& l = restored.looks_[k];
      const std::string look = "look " + std::to_string(k);
      std::uint8_t used = 0;
      get(in, used);
      need(in, look);
      if (used > 1) throw Damaged(look + " marked " + std::to_string(used));
      if (!used) continue;
      l.used = true;
      restored.setImage(l, getBytes(in, bytes, false, look + "'s image"));
      get(in, l.last_seen);
      for (std::int64_t& t : l.tried_at) get(in, t);
      need(in, look);
      for (int a = 0; a < kNumActions; ++a) {
        std::uint32_t m = 0;
        get(in, m);
        need(in, look);
        if (m > static_cast<std::uint32_t>(c.per_look_action))
          throw Damaged(look + " with " + std::to_string(m) + " experiences of action " + std::to_string(a) +
                        ", more than its per_look_action " + std::to_string(c.per_look_action));
        for (std::uint32_t i = 0; i < m; ++i) {
          auto e = std::make_shared<Experience>(
              getExperience(in, a, bytes, look + "'s experience " + std::to_string(i) + " of action " + std::to_string(a)));
          e->before_input = focusInput(e->before_image);
          l.with_effect[static_cast<std::size_t>(a)] += e->affordance;
          l.experiences[static_cast<std::size_t>(a)].push_back(std::move(e));
        }
      }
    }
    for (std::size_t k = 0; k < restored.looks_.size(); ++k)
      if (restored.looks_[k].used) restored.by_image_.emplace(imageHash(restored.looks_[k].image), static_cast<int>(k));
    *this = std::move(restored);
  } catch (const Damaged& e) {
    throw std::runtime_error(what + ": its memory is damaged (" + e.what() + ")");
  }
}

void Memory::hash(Fnv1a& h) const {
  // The same bytes save() writes, without a stream: looks, then their experiences.
  struct HashBuf : std::streambuf {
    Fnv1a* h;
    int_type overflow(int_type c) override {
      if (c != traits_type::eof()) {
        const char ch = static_cast<char>(c);
        h->add(&ch, 1);
      }
      return c;
    }
    std::streamsize xsputn(const char* s, std::streamsize n) override {
      h->add(s, static_cast<std::size_t>(n));
      return n;
    }
  } buf;
  buf.h = &h;
  std::ostream out(&buf);
  save(out);
}

}  // namespace afford

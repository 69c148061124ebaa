#include "experiment/design/tables.hpp"

#include <stdexcept>
#include <string>

#include "afford/rng.hpp"

namespace afford {

bool mixed(const AffordanceTable& table) {
  std::array<int, kNumActions> column_ones{};
  for (const auto& row : table) {
    int ones = 0;
    for (std::size_t a = 0; a < row.size(); ++a) {
      ones += row[a] == 1.0;
      column_ones[a] += row[a] == 1.0;
    }
    if (ones == 0 || ones == kNumActions) return false;
  }
  for (int ones : column_ones)
    if (ones == 0 || ones == static_cast<int>(table.size())) return false;
  return true;
}

int ownColourAction(Colour c) {
  for (int a = 0; a < kNumActions; ++a)
    if (kActionChannel[a] == colourChannel(c)) return a;
  return -1;
}

std::vector<std::size_t> oneWayLooks(const AffordanceTable& table, const std::vector<ObjectSpec>& objects) {
  // The looks an object can be turned into: the same shape, another colour, where the table says so.
  const auto next = [&](std::size_t o) {
    std::vector<std::size_t> out;
    for (int a = 0; a < kNumActions; ++a) {
      if (kActionChannel[a] < 0 || table[o][a] != 1.0) continue;
      for (std::size_t p = 0; p < objects.size(); ++p)
        if (objects[p].shape == objects[o].shape && colourChannel(objects[p].colour) == kActionChannel[a]) out.push_back(p);
    }
    return out;
  };
  std::vector<std::size_t> one_way;
  for (std::size_t o = 0; o < objects.size(); ++o) {
    const std::vector<std::size_t> exits = next(o);
    if (exits.empty()) continue;
    std::vector<bool> seen(objects.size(), false);
    std::vector<std::size_t> todo = exits;
    bool back = false;
    while (!todo.empty() && !back) {
      const std::size_t p = todo.back();
      todo.pop_back();
      if (seen[p]) continue;
      seen[p] = true;
      back = p == o;
      for (std::size_t q : next(p)) todo.push_back(q);
    }
    if (!back) one_way.push_back(o);
  }
  return one_way;
}

AffordanceTable randomTable(std::int64_t seed, std::int64_t index, const std::vector<ObjectSpec>& objects) {
  if (objects.size() < 2)
    throw std::invalid_argument("a random affordance table needs at least 2 objects (every column mixed), not " +
                                std::to_string(objects.size()));
  // Rejection: about 1 in 3 draws for the paper's nine objects is mixed.
  constexpr std::uint64_t kAttempts = 10000;
  for (std::uint64_t attempt = 0; attempt < kAttempts; ++attempt) {
    const KeyedRng rng(seed, index, Purpose::RandomTable, attempt);
    AffordanceTable t(objects.size());
    for (std::size_t o = 0; o < objects.size(); ++o)
      for (std::size_t a = 0; a < kNumActions; ++a)
        t[o][a] = static_cast<int>(a) == ownColourAction(objects[o].colour)
                      ? 0.0
                      : static_cast<double>(rng.bits(o * kNumActions + a) >> 63);
    if (mixed(t)) return t;
  }
  throw std::runtime_error("no mixed affordance table for these objects in " + std::to_string(kAttempts) + " draws");
}

}  // namespace afford

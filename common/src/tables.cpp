#include "afford/tables.hpp"

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

AffordanceTable randomTable(std::int64_t seed, std::int64_t index, std::size_t objects) {
  if (objects < 2)
    throw std::invalid_argument("a random affordance table needs at least 2 objects (every column mixed), not " +
                                std::to_string(objects));
  // Rejection: about 1 in 3 draws of 9 x 4 entries is mixed.
  constexpr std::uint64_t kAttempts = 10000;
  for (std::uint64_t attempt = 0; attempt < kAttempts; ++attempt) {
    const KeyedRng rng(seed, index, Purpose::RandomTable, attempt);
    AffordanceTable t(objects);
    for (std::size_t o = 0; o < objects; ++o)
      for (std::size_t a = 0; a < kNumActions; ++a) t[o][a] = static_cast<double>(rng.bits(o * kNumActions + a) >> 63);
    if (mixed(t)) return t;
  }
  throw std::runtime_error("no mixed affordance table in " + std::to_string(kAttempts) + " draws");
}

}  // namespace afford

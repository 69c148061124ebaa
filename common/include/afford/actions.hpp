// The four actions of paper 2.3.2, in the order used by every table:
// move, turn green, turn red, turn blue (ids match decision_t constants).
#pragma once
#include <array>
#include <string_view>

namespace afford {

constexpr int kNumActions = 4;
enum Action : int { kMove = 0, kTurnGreen = 1, kTurnRed = 2, kTurnBlue = 3 };
constexpr std::array<std::string_view, kNumActions> kActionNames = {"move", "turn green", "turn red",
                                                                    "turn blue"};
// RGB channel that a colour action paints (index into R,G,B); -1 for move.
constexpr std::array<int, kNumActions> kActionChannel = {-1, 1, 0, 2};

inline bool validAction(int a) { return a >= 0 && a < kNumActions; }

// The physical table's actions (world.kind: table; docs/model.md#a-physical-table), in the same four places.
constexpr std::array<std::string_view, kNumActions> kTableActionNames = {"push", "carry", "topple", "roll"};

}  // namespace afford

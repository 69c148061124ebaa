// Prints the LCM fingerprint of every afford message type, one "NAME HEX" line each, in name order: what a
// release's logs hold at the head of each message (tests/compat/record.sh keeps it as types.txt; read.sh
// compares each earlier release's with this build's).
#include <cinttypes>
#include <cstdio>

#include "all_types.hpp"

int main() {
#define AFFORD_PRINT_TYPE(T) std::printf("%s %016" PRIx64 "\n", #T, static_cast<std::uint64_t>(afford::T::getHash()));
  AFFORD_FOR_EACH_TYPE(AFFORD_PRINT_TYPE)
  return 0;
}

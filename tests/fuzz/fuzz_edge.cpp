// libFuzzer target of the message edge's bus-free steps (afford/decode.hpp):
// fingerprint, wire bounds, LCM's decode, the field checks, the digest. Any
// datagram, as any message type, with or without the run's config, is either
// refused with a reason or accepted; nothing crashes, leaks or trips UBSan.
// An accepted datagram re-encodes to exactly its own bytes.
// A custom mutator sets the size fields (array counts, string lengths) to the
// values that break decoders, and often re-seals the digest so that mutated
// datagrams get past it. Built and run by scripts/fuzz.sh.
// Input: one selector byte (tests/fuzz/fuzz_edge.hpp), then the datagram.
// AFFORD_FUZZ_TRACE=1 prints every size-field mutation.
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "afford/decode.hpp"
#include "tests/fuzz/fuzz_edge.hpp"

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

namespace afford::fuzz {
namespace {

// Printed at exit (libFuzzer runs one input at a time: no atomics needed).
struct Stats {
  std::uint64_t mutations = 0;            // calls of the custom mutator
  std::uint64_t size_mutations = 0;       // of them, one size field set
  std::uint64_t resealed = 0;             // of them, the digest recomputed
  std::uint64_t accepted[kTypes][2] = {}; // inputs decodeChecked took, by type and with_run
};
Stats stats;
bool trace = false;

[[noreturn]] void fail(const char* type, bool with_run, const std::string& what) {
  std::fprintf(stderr, "fuzz_edge: %s (%s): %s\n", type, with_run ? "with the run's config" : "observer",
               what.c_str());
  std::abort();
}

template <class Msg>
void decodeOne(std::size_t type, bool with_run, const std::uint8_t* data, std::size_t size) {
  const char* name = wire::Bounds<Msg>::kName;
  Msg msg;
  std::string why;
  if (!decodeChecked(data, size, context(with_run), msg, why)) {
    if (why.empty()) fail(name, with_run, "refused without a reason");
    return;
  }
  const int n = msg.getEncodedSize();
  if (n < 0 || static_cast<std::size_t>(n) != size)
    fail(name, with_run, "accepted " + std::to_string(size) + " bytes that re-encode to " + std::to_string(n));
  std::vector<std::uint8_t> again(size);
  if (msg.encode(again.data(), 0, n) != n) fail(name, with_run, "accepted, but does not re-encode");
  if (std::memcmp(again.data(), data, size) != 0) {
    std::size_t at = 0;
    while (again[at] == data[at]) ++at;
    fail(name, with_run, "accepted, but re-encodes to other bytes from byte " + std::to_string(at));
  }
  ++stats.accepted[type][with_run ? 1 : 0];
}

// ---- the size-field mutation -------------------------------------------------------

std::int64_t get(const std::uint8_t* at, int width) {
  std::uint64_t u = 0;
  for (int i = 0; i < width; ++i) u = (u << 8) | at[i];
  if (width < 8 && (u >> (8 * width - 1)) != 0) u |= ~std::uint64_t{0} << (8 * width);
  return static_cast<std::int64_t>(u);
}
void put(std::uint8_t* at, int width, std::int64_t v) {
  auto u = static_cast<std::uint64_t>(v);
  for (int i = width - 1; i >= 0; --i, u >>= 8) at[i] = static_cast<std::uint8_t>(u & 0xff);
}
bool fits(int width, std::int64_t v) {
  return width == 8 || (v >= -(std::int64_t{1} << (8 * width - 1)) && v < (std::int64_t{1} << (8 * width - 1)));
}
std::int64_t plus(std::int64_t a, std::int64_t b) {
  std::int64_t r;
  if (__builtin_add_overflow(a, b, &r)) return b > 0 ? std::numeric_limits<std::int64_t>::max()
                                                     : std::numeric_limits<std::int64_t>::min();
  return r;
}

// What a size field is set to: the edges of its own range and of the bytes
// left, of int32 (LCM 1.3.1 multiplies counts by sizeof(T) in an int:
// 0x10000001 doubles wrap), a count that allocates much from few bytes, and
// huge 64-bit values for 8-byte fields. Only values the field can hold.
std::vector<std::int64_t> interesting(const wire::SizeField& f, std::int64_t now, std::int64_t left) {
  constexpr std::int64_t i32max = std::numeric_limits<std::int32_t>::max();
  constexpr std::int64_t i32min = std::numeric_limits<std::int32_t>::min();
  std::vector<std::int64_t> all = {0,         1,          -1,         f.max,      plus(f.max, 1), plus(now, -1),
                                   plus(now, 1), left,    left + 1,   i32max,     i32min,         0x10000001,
                                   0x01000000, 0x7f,      0x80,       0xff,       0x7fff,         0x8000,
                                   0xffff};
  if (f.width == 8)
    all.insert(all.end(), {std::numeric_limits<std::int64_t>::max(), std::numeric_limits<std::int64_t>::min(),
                           std::int64_t{1} << 32, (std::int64_t{1} << 32) + 1, std::int64_t{1} << 62,
                           0x1000000000000001, -(std::int64_t{1} << 32)});
  std::vector<std::int64_t> fit;
  for (std::int64_t v : all)
    if (fits(f.width, v)) fit.push_back(v);
  return fit;
}

// Sets one size field of the input, found by the wire check's own walk, to an
// interesting value; returns the size, or 0 when the walk found none.
std::size_t mutateSizeField(std::uint8_t* data, std::size_t size, std::minstd_rand& rng) {
  if (size < 2) return 0;
  const bool with_run = withRun(data[0]);
  std::vector<wire::SizeField> sizes;
  const char* name = "";
  forType(typeOf(data[0]), [&](auto t) {
    using Msg = typename decltype(t)::type;
    std::string why;
    wire::checkWire<Msg>(data + 1, size - 1, boundsFor<Msg>(context(with_run)), why, &sizes);
    name = wire::Bounds<Msg>::kName;
  });
  if (sizes.empty()) return 0;
  const wire::SizeField& f = sizes[rng() % sizes.size()];
  std::uint8_t* at = data + 1 + f.offset;
  const std::int64_t now = get(at, f.width);
  const auto left = static_cast<std::int64_t>(size - 1 - f.offset - static_cast<std::size_t>(f.width));
  const std::vector<std::int64_t> values = interesting(f, now, left);
  const std::int64_t v = values[rng() % values.size()];
  put(at, f.width, v);
  ++stats.size_mutations;
  if (trace)
    std::fprintf(stderr, "fuzz_edge: size mutation: %s %s: %" PRId64 " -> %" PRId64 "\n", name, f.field.c_str(), now,
                 v);
  return size;
}

void printStats() {
  std::uint64_t accepted = 0;
  std::string by_type;
  for (std::size_t t = 0; t < kTypes; ++t) {
    forType(t, [&](auto type) {
      using Msg = typename decltype(type)::type;
      const std::uint64_t run = stats.accepted[t][1], observer = stats.accepted[t][0];
      accepted += run + observer;
      by_type += std::string(" ") + wire::Bounds<Msg>::kName + "=" + std::to_string(run) + "/" +
                 std::to_string(observer);
    });
  }
  std::fprintf(stderr,
               "fuzz_edge: custom mutator: %" PRIu64 " calls, %" PRIu64 " size-field mutations, %" PRIu64
               " digests re-sealed\n"
               "fuzz_edge: accepted inputs: %" PRIu64 " (by type, with the run's config/observer):%s\n",
               stats.mutations, stats.size_mutations, stats.resealed, accepted, by_type.c_str());
}

}  // namespace
}  // namespace afford::fuzz

using namespace afford::fuzz;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  context(true);  // load both configs once, before the first input
  context(false);
  const char* t = std::getenv("AFFORD_FUZZ_TRACE");
  trace = t && *t && std::strcmp(t, "0") != 0;
  std::atexit(printStats);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::size_t type = typeOf(data[0]);
  const bool run = withRun(data[0]);
  forType(type, [&](auto t) { decodeOne<typename decltype(t)::type>(type, run, data + 1, size - 1); });
  return 0;
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                               unsigned int seed) {
  std::minstd_rand rng(seed);
  ++stats.mutations;
  std::size_t n = 0;
  if (rng() % 2 == 0) n = mutateSizeField(data, size, rng);
  if (n == 0) n = LLVMFuzzerMutate(data, size, max_size);
  if (n >= 1 + 16 && rng() % 2 == 0) {  // a fingerprint and a digest at least
    afford::sealBuffer(data + 1, n - 1);
    ++stats.resealed;
  }
  return n;
}

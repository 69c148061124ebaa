// libFuzzer target of the project's log reader (afford/logfile.hpp): any
// bytes, read as a log file, give well-formed events and problems with their
// offsets; nothing crashes, leaks, trips UBSan, or allocates beyond the caps
// (scripts/fuzz.sh runs it with -malloc_limit_mb). Every event it returns is
// within the caps and within the file, and the bytes it accounts for (events,
// skipped, torn) never exceed the file's. Seeded with real run logs
// (scripts/fuzz.sh writes them). Built and run by scripts/fuzz.sh.
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "afford/logfile.hpp"

namespace {
[[noreturn]] void fail(const char* what, long long a, long long b) {
  std::fprintf(stderr, "fuzz_logreader: %s (%lld, %lld)\n", what, a, b);
  std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // A copy: fmemopen wants a writable buffer, and the reader must not read past it (ASan sees to that).
  void* copy = std::malloc(size ? size : 1);
  if (size) __builtin_memcpy(copy, data, size);
  std::FILE* f = size ? fmemopen(copy, size, "rb") : nullptr;
  if (!f) {
    std::free(copy);
    return 0;
  }
  afford::LogLimits limits;
  limits.event_bytes = 1 << 16;  // small, so that inputs reach the cap
  {
    afford::LogReader reader(f, "fuzz-input", limits);
    long long accounted = 0, last_offset = -1;
    for (afford::LogEvent e; reader.next(e);) {
      if (e.channel.empty() || static_cast<int>(e.channel.size()) > limits.channel_bytes)
        fail("a channel beyond the cap", static_cast<long long>(e.channel.size()), limits.channel_bytes);
      if (static_cast<long long>(e.data.size()) > limits.event_bytes)
        fail("data beyond the cap", static_cast<long long>(e.data.size()), limits.event_bytes);
      if (e.offset <= last_offset) fail("events out of order", e.offset, last_offset);
      last_offset = e.offset;
      const long long bytes = 28 + static_cast<long long>(e.channel.size() + e.data.size());
      if (e.offset + bytes > static_cast<long long>(size)) fail("an event beyond the file", e.offset, bytes);
      accounted += bytes;
    }
    accounted += reader.skippedBytes() + reader.tornBytes();
    if (accounted > static_cast<long long>(size)) fail("more bytes accounted for than the file has", accounted, static_cast<long long>(size));
    for (const afford::LogProblem& p : reader.problems())
      if (p.offset < 0 || p.offset >= static_cast<long long>(size)) fail("a problem's offset outside the file", p.offset, static_cast<long long>(size));
  }
  std::free(copy);
  return 0;
}

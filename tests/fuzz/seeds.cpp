// Seeds of the edge's fuzz target: the sample of every type
// (tests/samples.hpp), sealed with its digest, in both contexts: files
// <type>-run and <type>-observer in DIR. Each must pass decodeChecked whole,
// so that the fuzzer starts from messages that reach every step.
//   fuzz_edge_seeds DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "afford/decode.hpp"
#include "tests/fuzz/fuzz_edge.hpp"

int main(int argc, char** argv) {
  using namespace afford;
  using namespace afford::fuzz;
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DIR\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  int written = 0, refused = 0;
  for (std::size_t type = 0; type < kTypes; ++type) {
    forType(type, [&](auto t) {
      using Msg = typename decltype(t)::type;
      Msg m = test::sample<Msg>();
      const std::vector<std::uint8_t> datagram = sealed(m);
      for (bool with_run : {true, false}) {
        Msg decoded;
        std::string why;
        const std::string name = std::string(wire::Bounds<Msg>::kName) + (with_run ? "-run" : "-observer");
        if (!decodeChecked(datagram.data(), datagram.size(), context(with_run), decoded, why)) {
          std::fprintf(stderr, "fuzz_edge_seeds: the sample %s is refused: %s\n", name.c_str(), why.c_str());
          ++refused;
          continue;
        }
        std::ofstream out(dir / name, std::ios::binary);
        const char s = static_cast<char>(selector(type, with_run));
        out.write(&s, 1);
        out.write(reinterpret_cast<const char*>(datagram.data()), static_cast<std::streamsize>(datagram.size()));
        if (!out) {
          std::fprintf(stderr, "fuzz_edge_seeds: cannot write %s\n", (dir / name).c_str());
          ++refused;
          continue;
        }
        ++written;
      }
    });
  }
  std::fprintf(stderr, "fuzz_edge_seeds: %d seeds in %s\n", written, dir.c_str());
  return refused == 0 ? 0 : 1;
}

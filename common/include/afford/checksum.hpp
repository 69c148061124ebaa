// FNV-1a 64 over raw bytes: the weights checksum reported by runs and replays.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "afford/seal.hpp"

namespace afford {

class Fnv1a {
 public:
  void add(const void* data, std::size_t n) { h_ = fnv1a64(h_, data, n); }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h_));
    return buf;
  }

 private:
  std::uint64_t h_ = 0xCBF29CE484222325ull;
};

}  // namespace afford

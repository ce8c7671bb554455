// Reproducible random bytes for codec and filter tests.
#pragma once
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

namespace tessera {

inline std::vector<std::byte> randomBytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<std::byte> v(n);
  for (auto& b : v) b = std::byte(rng() & 0xFF);
  return v;
}

}  // namespace tessera

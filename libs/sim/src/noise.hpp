#pragma once
// Deterministic per-frame randomness for sensor noise without a random
// number generator per pixel: a fixed table of normal deviates read from a
// hashed offset per row (frame, camera and row decide the offset).
#include <cstdint>
#include <vector>

#include "rng.hpp"

namespace ivoa::sim::detail {

class NoiseTable {
 public:
  static constexpr uint32_t kSize = 1u << 20;
  static constexpr uint32_t kMask = kSize - 1;
  static const NoiseTable& instance();

  const float* normals() const { return normals_.data(); }    // N(0, 1)
  const float* uniforms() const { return uniforms_.data(); }  // U[0, 1)
  // Offset of a row's first value for (frame, stream, row).
  static uint32_t offset(uint64_t frame, uint32_t stream, uint32_t row) {
    return static_cast<uint32_t>(hash_combine(hash_combine(frame, stream), row)) & kMask;
  }

 private:
  NoiseTable();
  std::vector<float> normals_, uniforms_;
};

}  // namespace ivoa::sim::detail

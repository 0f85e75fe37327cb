#include "noise.hpp"

namespace ivoa::sim::detail {

NoiseTable::NoiseTable() : normals_(kSize), uniforms_(kSize) {
  Rng rng(0x5eed1e55ULL);
  for (float& n : normals_) n = static_cast<float>(rng.normal());
  for (float& u : uniforms_) u = static_cast<float>(rng.uniform());
}

const NoiseTable& NoiseTable::instance() {
  static const NoiseTable table;
  return table;
}

}  // namespace ivoa::sim::detail

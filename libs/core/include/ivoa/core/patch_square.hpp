#pragma once
// A square cut around a query cell, in image pixels: kept apart from
// footprint_patch.hpp so the introspection model's public header can name
// it without the grid messages.

namespace ivoa {

// side x side pixels centred on (u, v).
struct PatchSquare {
  double u = 0, v = 0;
  int side = 0;
};

}  // namespace ivoa

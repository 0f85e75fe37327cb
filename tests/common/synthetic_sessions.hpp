#pragma once
// Small dataset sessions whose four classes look different (stripes one
// way or the other, a blob, noise), for training and evaluation tests.
#include <string>

namespace ivoa::test {

struct SyntheticSession {
  int per_class = 10;     // samples of each class
  unsigned seed = 1;      // patterns and noise
  int evidence_size = 0;  // > 0: evidence that follows the class (NaN in the third value)
  std::string detector = "jppc";
  double patch_scale = 0;  // recorded only: every patch is the fixed 100 px square
  int views = 1;           // 2: each patch stacked over a copy of itself (as a two-view session's)
};

// Writes session `name` under `dataset_root`: one frame, the classes in turn.
void write_synthetic_session(const std::string& dataset_root, const std::string& name, const SyntheticSession& s);

}  // namespace ivoa::test

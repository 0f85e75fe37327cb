#pragma once
// Small dataset sessions whose four classes look different (stripes one
// way or the other, a blob, noise), for training and evaluation tests.
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace ivoa::test {

struct SyntheticSession {
  int per_class = 10;     // samples of each class
  unsigned seed = 1;      // patterns and noise
  int evidence_size = 0;  // > 0: evidence that follows the class (NaN in the third value)
  std::string detector = "jppc";
  double patch_scale = 0;  // recorded only: every patch is the fixed 100 px square
  int views = 1;           // 2: each patch stacked over a copy of itself (as a two-view session's)
  int patch_size = 100;    // px, the side of each (view's) square
  std::string scene;       // recorded in session.json, as a simulated session's scene and seed
  int64_t scene_seed = -1;
  cv::Size image_size;  // of the frames the patches were cut from; 0 x 0: not recorded
};

// Writes session `name` under `dataset_root`: one frame (utime 0), the
// classes in turn, every cell at pixel (kSyntheticCellU, kSyntheticCellV).
inline constexpr double kSyntheticCellU = 150, kSyntheticCellV = 100;
void write_synthetic_session(const std::string& dataset_root, const std::string& name, const SyntheticSession& s);

}  // namespace ivoa::test

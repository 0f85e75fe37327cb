#pragma once
// Parameters of the stereo obstacle detectors, as plain structs. JPP-C keeps
// JPP's own key names (its libconfig .cfg, amrl.cfg defaults) so a JPP user
// recognises them; units are the project's: metres and pixels (JPP's config
// file is in millimetres). Every field is settable by a flag and from a
// --config file (see options.hpp): JPP's own keys by their name (--daisy_R),
// the project's additions with a prefix (--jpp_footprint, --sgbm_p2,
// --dense_max_range).
#include <string>

namespace ivoa::stereo {

// JPP-C: sparse, on-demand stereo checks of ground points (ivoa_jpp_spec.md §1).
struct JppConfig {
  // Rectified image size relative to the raw image (JPP: rect_img_width /
  // calib_img_width). 0.5 turns the 960x600 camera into JPP's 480x300.
  double rect_scale = 0.5;
  // DAISY descriptor (JPP daisy_params): R radius of the outer ring, pixels;
  // Q rings; T sample angles per ring; H orientation bins. (Q*T+1)*H floats
  // per pixel: 3 with JPP's 5.0, 2, 1, 1. The thresholds below are on the
  // per-pixel L1 scale of that 3-float descriptor.
  double daisy_R = 5.0;
  int daisy_Q = 2;
  int daisy_T = 1;
  int daisy_H = 1;
  // Half-width of the matching window, pixels: (2w+1)^2 = 121 pixels for 5.
  int SAD_window_size = 5;
  // CP(p): mean per-pixel L1 descriptor distance below this -> a surface at p.
  double conf_pos_thresh = 0.75;
  // CN(p): above this -> confidently nothing at p. Full JPP only; JPP-C does
  // not use it (kept for JppMatcher users).
  double conf_neg_thresh = 1.2;
  // Step between the ground samples of one footprint check, metres (JPP
  // grid_size, in mm there; not the query grid's --grid-spacing).
  double grid_size = 0.05;
  // Which ground samples a footprint check tests, at step grid_size:
  //  "half_box" (default): JPP's is_bot_clear, the box ahead of (x, y)
  //          (dx in [0, r], dy in [-r, r]: 15 samples for r = 0.10, step 0.05).
  //  "disc": the lattice points within r (13 samples), the shape the depth
  //          monitor checks. Measured on the simulator, it is the worse
  //          choice: an obstacle in the disc's rear half stands between the
  //          camera and the half box's samples, so JPP's half box flags it
  //          anyway (the ground it must see is hidden), while the disc's
  //          rear samples near the robot fall on steeply slanted ground,
  //          where JPP's fronto-parallel window fails and clean floor reads
  //          as an obstacle.
  std::string footprint = "half_box";

  // Departures from JPP (see jppc_detector.hpp).
  // Border bias fix: the window cost divides by the pixels actually compared;
  // a window with fewer than this fraction of its pixels inside both images
  // gives no verdict (UNKNOWN). JPP always divides by 121.
  double min_window_fraction = 0.5;
  // Optional texture gate, OFF by default (0): a sample whose left window has
  // a mean positive horizontal gradient below this (8-bit gray levels per
  // pixel) gives no verdict. Off keeps JPP's texture-less behaviour (zero
  // descriptors match anything, so texture-less obstacles read as free):
  // that failure mode is what IVOA's introspection learns to predict.
  double texture_gate = 0.0;
};

// OpenCV StereoSGBM on the rectified pair (data_notes.md §5 settings).
struct SgbmConfig {
  double rect_scale = 0.5;    // rectified size relative to the raw image
  std::string mode = "3way";  // "3way" (fastest), "sgbm", "hh"
  int min_disparity = 0;      // pixels
  int num_disparities = 96;   // pixels, multiple of 16; 96 at 480x300 sees the ground down to 0.38 m (0.12 m baseline)
  int block_size = 5;         // pixels, odd
  int p1 = 0;                 // penalty of a 1-disparity change between neighbours; 0 = 8*block^2
  int p2 = 0;                 // penalty of a larger change; 0 = 32*block^2
  int uniqueness_ratio = 10;  // percent
  int speckle_window_size = 100;  // pixels
  int speckle_range = 2;          // disparity units
  int disp12_max_diff = 1;        // left-right check, pixels (< 0 disables)
  int pre_filter_cap = 63;        // x-derivative prefilter clipped to [-cap, cap], gray levels
};

// Dense detector: SGBM points in the robot frame, classified by height.
struct DenseConfig {
  SgbmConfig sgbm;
  double min_obstacle_height = 0.05;   // m: points with z in [min, max] are obstacles
  double max_obstacle_height = 0.60;   // m: taller points are above the robot, ignored
  double hole_depth = 0.05;            // m: points below z = -hole_depth (reflections, holes) are obstacles
  int min_obstacle_points = 10;        // obstacle (or below-ground) points within r for OBSTACLE,
  double min_obstacle_fraction = 0.1;  // and at least this share of the valid points within r
                                       // (near the robot a disc holds ~1000 points; stray mismatches
                                       // at occlusion edges add a few dozen)
  int min_ground_points = 10;          // ground points within r (and no obstacle) for FREE
  double max_range = 8.0;              // m: points farther than this from the robot (in x or y) are ignored
};

struct DetectorConfig {
  JppConfig jpp;
  DenseConfig dense;
};

// Throw std::invalid_argument naming the first bad field (with its flag name).
void validate(const JppConfig& config);
void validate(const SgbmConfig& config);
void validate(const DenseConfig& config);

}  // namespace ivoa::stereo

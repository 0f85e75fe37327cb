#pragma once
// The rig the simulator renders by default: a Point Grey-like stereo pair
// (960x600, ~0.12 m baseline, ~0.3 m above the ground, pitched down ~15 deg,
// modest lens distortion) and a Kinect-like depth sensor just above it.
#include "ivoa/core/calibration.hpp"

namespace ivoa::sim {

struct SimRigParams {
  double baseline = 0.12;         // metres between the camera centres
  double camera_height = 0.30;    // metres, left camera above the ground
  double pitch_deg = 15.0;        // camera pitched down
  double focal = 620.0;           // pixels (960x600: ~75 x 52 deg field of view)
  bool distortion = true;         // k1 = -0.09, k2 = 0.035 (left; the right lens differs slightly)
  double depth_above = 0.06;      // metres, depth sensor above the left camera
  double depth_pitch_deg = 15.0;  // depth sensor pitch
};

RigCalibration make_sim_rig(const SimRigParams& params = {});

}  // namespace ivoa::sim

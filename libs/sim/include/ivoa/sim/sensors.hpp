#pragma once
// Models of the sensors' imperfections: how a camera turns scene radiance
// into 8-bit pixels (exposure, gain, optics blur, shot and read noise,
// clipping, gamma, Bayer colour filter) and how a Kinect-like depth sensor
// turns range into millimetres (range limits, noise growing with range,
// quantisation, dropouts).
namespace ivoa::sim {

struct CameraSensorConfig {
  double full_well = 9000;   // electrons at saturation
  double read_noise = 5.0;   // electrons rms
  double sensitivity = 900;  // electrons per (radiance unit x ms)
  double min_exposure_ms = 0.02;
  double max_exposure_ms = 25.0;    // a 30 Hz camera cannot integrate longer
  double max_gain = 12.0;           // analog gain reached once exposure is at its maximum
  double target_level = 0.20;       // auto exposure: mean signal / full well
  double gamma = 1.0 / 2.2;         // camera output curve
  double right_sensitivity = 1.03;  // right sensor's response relative to the left
  bool bayer = true;                // RGGB colour filter + bilinear demosaic, as a Bayer camera and its driver
  bool motion_blur = true;          // smear along rows by yaw rate x exposure time
};

struct DepthSensorConfig {
  double noise_coefficient = 1.4e-3;  // sigma = c * z^2 (metres, z in metres)
  double projector_baseline = 0.075;  // metres, IR projector to the right of the IR camera (shadows)
  double edge_ratio = 0.05;           // invalid where a neighbour differs by more than this fraction of depth
  double dark_return = 0.05;          // returns weaker than this (ir albedo x cos / (z/2)^2) tend to drop out
  double specular_dropout = 4.0;      // dropout chance per unit of mirror reflectance (smooth surfaces)
  double sunlight_dropout = 0.6;      // dropout chance on sunlit surfaces at 4 m (less when near)
  double random_dropout = 0.003;      // isolated missing pixels
};

}  // namespace ivoa::sim

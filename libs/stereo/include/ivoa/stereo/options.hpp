#pragma once
// Command-line flags (and so --config file keys) for the detector
// parameters. A JPP key's flag has its field's name (--daisy_R); the
// project's JPP fields take --jpp_ (--jpp_footprint for `footprint`), SGBM's
// --sgbm_ and the dense detector's --dense_.
namespace CLI {
class App;
}

namespace ivoa::stereo {
struct JppConfig;
struct SgbmConfig;
struct DenseConfig;
struct DetectorConfig;

// Matching only (descriptor, window, thresholds): for tools on rectified pairs.
void add_jpp_matcher_options(CLI::App& app, JppConfig& config);    // --conf_pos_thresh, --daisy_R, ...
void add_sgbm_matcher_options(CLI::App& app, SgbmConfig& config);  // --sgbm_num_disparities, ...
// Everything, including the rectification scales and JPP's --grid_size.
void add_jpp_options(CLI::App& app, JppConfig& config);
void add_dense_options(CLI::App& app, DenseConfig& config);  // SGBM flags and --dense_*
void add_detector_options(CLI::App& app, DetectorConfig& config);

}  // namespace ivoa::stereo

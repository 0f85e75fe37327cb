// ivoa-stereo-eval: scores the point checks of the stereo perception models
// (JPP-C's CP predicate, SGBM disparity) against ground-truth disparity on
// a rectified pair, e.g. Middlebury "Aloe" from Debian's opencv-doc.
#include <cmath>
#include <cstdio>
#include <fstream>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "disparity_io.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/stereo/options.hpp"
#include "point_check_scoring.hpp"

namespace {

constexpr const char* kAloeDir = "/usr/share/doc/opencv-doc/examples/data/";

cv::Mat load_gray(const std::string& path, double scale) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw ivoa::stereo_eval::DisparityFileError(path + ": cannot read image");
  if (scale == 1.0) return image;
  cv::Mat out;  // the size rule of scale_disparity, so image and truth agree
  const cv::Size size(static_cast<int>(std::lround(image.cols * scale)), static_cast<int>(std::lround(image.rows * scale)));
  cv::resize(image, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

int round_up_16(double d) { return static_cast<int>(std::ceil(d / 16.0)) * 16; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Score stereo point checks (JPP-C CP, SGBM) against ground-truth disparity on a rectified pair"};
  ivoa::CommonOptions common;
  ivoa::add_common_options(app, common);
  std::string left_path = std::string(kAloeDir) + "aloeL.jpg", right_path = std::string(kAloeDir) + "aloeR.jpg";
  std::string gt_path = std::string(kAloeDir) + "aloeGT.png", json_path, overlay_path;
  double gt_divisor = 1.0, scale = 0.5, sgbm_tolerance = 1.0;
  std::vector<std::string> models{"jppc", "sgbm"};
  ivoa::stereo_eval::ScoringOptions scoring;
  ivoa::stereo::JppConfig jpp;
  ivoa::stereo::SgbmConfig sgbm;
  app.add_option("--left", left_path, "rectified left image")->capture_default_str();
  app.add_option("--right", right_path, "rectified right image")->capture_default_str();
  app.add_option("--gt", gt_path, "ground-truth disparity of the left image: PFM, 16- or 8-bit PNG; 0/inf/NaN unknown")
      ->capture_default_str();
  app.add_option("--gt-divisor", gt_divisor, "disparity = stored value / divisor (KITTI 16-bit PNG: 256)")
      ->capture_default_str();
  app.add_option("--scale", scale, "resize images and disparities by this factor (aloeGT is full resolution)")
      ->capture_default_str();
  app.add_option("--stride", scoring.stride, "score every N-th pixel in x and y")->capture_default_str();
  app.add_option("--wrong-offsets", scoring.wrong_offsets, "wrong hypotheses at truth +- these offsets, pixels")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--texture-threshold", scoring.texture_threshold,
                 "textured: RMS x-gradient over the 11x11 window >= this, gray levels/px")
      ->capture_default_str();
  app.add_option("--models", models, "jppc, sgbm")->delimiter(',')->check(CLI::IsMember({"jppc", "sgbm"}));
  app.add_option("--sgbm-tolerance", sgbm_tolerance, "SGBM confirms a hypothesis within this many pixels")
      ->capture_default_str();
  app.add_option("--json", json_path, "write the scores as JSON");
  app.add_option("--overlay", overlay_path, "write a PNG of JPP-C's truth outcomes (green confirmed, red rejected)");
  ivoa::stereo::add_jpp_matcher_options(app, jpp);
  ivoa::stereo::add_sgbm_matcher_options(app, sgbm);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("stereo-eval", common.log_level);

  cv::Mat left, right, truth;
  try {
    left = load_gray(left_path, scale);
    right = load_gray(right_path, scale);
    truth = ivoa::stereo_eval::scale_disparity(ivoa::stereo_eval::load_disparity(gt_path, gt_divisor), scale);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  }
  if (left.size() != right.size() || left.size() != truth.size()) {
    spdlog::error("sizes differ: left {}x{}, right {}x{}, ground truth {}x{}", left.cols, left.rows, right.cols,
                  right.rows, truth.cols, truth.rows);
    return ivoa::kExitBadInput;
  }
  double max_disparity = 0;
  cv::Mat finite = truth.clone();
  cv::patchNaNs(finite, 0);
  cv::minMaxLoc(finite, nullptr, &max_disparity);
  if (app.count("--sgbm_num_disparities") == 0) sgbm.num_disparities = round_up_16(max_disparity + 8);
  spdlog::info("{}x{} pair at scale {}, ground truth {:.1f}% known, max disparity {:.1f} px", left.cols, left.rows,
               scale, 100.0 * cv::countNonZero(finite > 0) / static_cast<double>(finite.total()), max_disparity);

  std::vector<ivoa::stereo_eval::ModelScore> scores;
  cv::Mat overlay;
  try {
    for (const std::string& name : models) {
      std::unique_ptr<ivoa::stereo_eval::PointCheckModel> model;
      if (name == "jppc")
        model = std::make_unique<ivoa::stereo_eval::JppPointModel>(jpp);
      else
        model = std::make_unique<ivoa::stereo_eval::SgbmPointModel>(sgbm, sgbm_tolerance);
      scores.push_back(ivoa::stereo_eval::score(*model, left, right, truth, scoring,
                                                name == "jppc" && !overlay_path.empty() ? &overlay : nullptr));
    }
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  }
  std::printf("%s", ivoa::stereo_eval::to_table(scores).c_str());
  if (!json_path.empty() && !(std::ofstream(json_path) << ivoa::stereo_eval::to_json(scores, scoring))) {
    spdlog::error("cannot write {}", json_path);
    return ivoa::kExitIoError;
  }
  if (!overlay.empty() && !cv::imwrite(overlay_path, overlay)) {
    spdlog::error("cannot write {}", overlay_path);
    return ivoa::kExitIoError;
  }
  return ivoa::kExitOk;
}

// ivoa-stereo-eval: scores the point checks of the stereo perception models
// (JPP-C's CP predicate, SGBM disparity) against ground-truth disparity on
// a rectified pair, e.g. Middlebury "Aloe" from Debian's opencv-doc.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "disparity_io.hpp"
#include "ivoa/core/flag_checks.hpp"
#include "ivoa/core/image_files.hpp"
#include "ivoa/core/process.hpp"
#include "ivoa/stereo/options.hpp"
#include "point_check_scoring.hpp"

namespace {

constexpr const char* kAloeDir = "/usr/share/doc/opencv-doc/examples/data/";

cv::Mat load_gray(const std::string& path, double scale) {
  const cv::Mat image = ivoa::stereo_eval::read_image(path, cv::IMREAD_GRAYSCALE);
  if (scale == 1.0) return image;
  cv::Mat out;  // the size rule of scale_disparity, so image and truth agree
  const cv::Size size(static_cast<int>(std::lround(image.cols * scale)),
                      static_cast<int>(std::lround(image.rows * scale)));
  if (size.width < 1 || size.height < 1)
    throw ivoa::stereo_eval::DisparityFileError("--scale " + fmt::format("{:g}", scale) + " shrinks " + path + " (" +
                                                std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                                ") to nothing");
  cv::resize(image, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

int round_up_16(double d) { return static_cast<int>(std::ceil(d / 16.0)) * 16; }

struct CommandLine {
  std::string left_path = std::string(kAloeDir) + "aloeL.jpg";
  std::string right_path = std::string(kAloeDir) + "aloeR.jpg";
  std::string gt_path = std::string(kAloeDir) + "aloeGT.png";
  std::string json_path, overlay_path;
  double gt_divisor = 1.0, scale = 0.5, sgbm_tolerance = 1.0;
  std::vector<std::string> models{"jppc", "sgbm"};
  ivoa::stereo_eval::ScoringOptions scoring;
  ivoa::stereo::JppConfig jpp;
  ivoa::stereo::SgbmConfig sgbm;
};

void add_options(CLI::App& app, CommandLine& cl) {
  app.add_option("--left", cl.left_path, "rectified left image")->capture_default_str();
  app.add_option("--right", cl.right_path, "rectified right image")->capture_default_str();
  app.add_option("--gt", cl.gt_path,
                 "ground-truth disparity of the left image: PFM, 16- or 8-bit PNG; 0/inf/NaN unknown")
      ->capture_default_str();
  app.add_option("--gt-divisor", cl.gt_divisor, "disparity = stored value / divisor (KITTI 16-bit PNG: 256)")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--scale", cl.scale, "resize images and disparities by this factor (aloeGT is full resolution)")
      ->capture_default_str()
      ->check(ivoa::number_in(1e-6, 4));  // 4: a 1282 px image is 5128 px, and SGBM's buffers grow with it
  app.add_option("--stride", cl.scoring.stride, "score every N-th pixel in x and y")
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--wrong-offsets", cl.scoring.wrong_offsets, "wrong hypotheses at truth +- these offsets, pixels")
      ->delimiter(',')
      ->capture_default_str()
      ->check(ivoa::positive_number());
  app.add_option("--texture-threshold", cl.scoring.texture_threshold,
                 "textured: RMS x-gradient over the 11x11 window >= this, gray levels/px")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--models", cl.models, "jppc, sgbm")->delimiter(',')->check(CLI::IsMember({"jppc", "sgbm"}));
  app.add_option("--sgbm-tolerance", cl.sgbm_tolerance, "SGBM confirms a hypothesis within this many pixels")
      ->capture_default_str()
      ->check(ivoa::non_negative_number());
  app.add_option("--json", cl.json_path, "write the scores as JSON");
  app.add_option("--overlay", cl.overlay_path, "write a PNG of JPP-C's truth outcomes (green confirmed, red rejected)");
  ivoa::stereo::add_jpp_matcher_options(app, cl.jpp);
  ivoa::stereo::add_sgbm_matcher_options(app, cl.sgbm);
}

struct Pair {
  cv::Mat left, right, truth;
};

// Throws with the file or the sizes named.
Pair load_pair(const CommandLine& cl) {
  Pair p;
  p.left = load_gray(cl.left_path, cl.scale);
  p.right = load_gray(cl.right_path, cl.scale);
  p.truth = ivoa::stereo_eval::scale_disparity(ivoa::stereo_eval::load_disparity(cl.gt_path, cl.gt_divisor), cl.scale);
  if (p.left.size() != p.right.size() || p.left.size() != p.truth.size())
    throw std::runtime_error(fmt::format("sizes differ: left {}x{}, right {}x{}, ground truth {}x{}", p.left.cols,
                                         p.left.rows, p.right.cols, p.right.rows, p.truth.cols, p.truth.rows));
  return p;
}

// Sizes SGBM's search to the truth unless --sgbm_num_disparities was given.
// Throws if the truth cannot be the pair's.
void fit_sgbm_range(const CLI::App& app, const Pair& p, CommandLine& cl) {
  double max_disparity = 0;
  cv::Mat finite = p.truth.clone();
  cv::patchNaNs(finite, 0);
  cv::minMaxLoc(finite, nullptr, &max_disparity);
  if (max_disparity >= p.left.cols)  // SGBM would search (and allocate for) a range wider than the image
    throw std::runtime_error(fmt::format(
        "{}: the largest ground-truth disparity is {:.0f} px after --gt-divisor {}, wider than the {} px image: is "
        "the divisor right (KITTI's 16-bit PNG: 256)?",
        cl.gt_path, max_disparity, cl.gt_divisor, p.left.cols));
  if (app.count("--sgbm_num_disparities") == 0) cl.sgbm.num_disparities = round_up_16(max_disparity + 8);
  spdlog::info("{}x{} pair at scale {}, ground truth {:.1f}% known, max disparity {:.1f} px", p.left.cols, p.left.rows,
               cl.scale, 100.0 * cv::countNonZero(finite > 0) / static_cast<double>(finite.total()), max_disparity);
  if (max_disparity > 0 && max_disparity < 4)  // no real stereo pair is that flat: a divisor for another format
    spdlog::warn(
        "{}: the largest ground-truth disparity is {:.2f} px after --gt-divisor {}: is the divisor right "
        "(KITTI's 16-bit PNG: 256; an 8-bit Middlebury PNG: 1)?",
        cl.gt_path, max_disparity, cl.gt_divisor);
}

std::vector<ivoa::stereo_eval::ModelScore> score_models(const CommandLine& cl, const Pair& p, cv::Mat& overlay) {
  std::vector<ivoa::stereo_eval::ModelScore> scores;
  std::set<std::string> scored;
  for (const std::string& name : cl.models) {
    if (!scored.insert(name).second) continue;  // named twice: one row is enough
    std::unique_ptr<ivoa::stereo_eval::PointCheckModel> model;
    if (name == "jppc") model = std::make_unique<ivoa::stereo_eval::JppPointModel>(cl.jpp);
    else model = std::make_unique<ivoa::stereo_eval::SgbmPointModel>(cl.sgbm, cl.sgbm_tolerance);
    scores.push_back(ivoa::stereo_eval::score(*model, p.left, p.right, p.truth, cl.scoring,
                                              name == "jppc" && !cl.overlay_path.empty() ? &overlay : nullptr));
  }
  return scores;
}

// The matcher settings, and outputs that would write over an input.
int check_flags(const CommandLine& cl) {
  try {
    ivoa::stereo::validate(cl.sgbm);
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  }
  for (const std::string* out : {&cl.json_path, &cl.overlay_path})
    if (const std::string input = ivoa::same_file_among(*out, {cl.left_path, cl.right_path, cl.gt_path});
        !input.empty()) {
      spdlog::error("{} is the input {}: it would be written over", *out, input);
      return ivoa::kExitUsage;
    }
  return ivoa::kExitOk;
}

int write_outputs(const CommandLine& cl, const std::vector<ivoa::stereo_eval::ModelScore>& scores,
                  const cv::Mat& overlay) {
  std::printf("%s", ivoa::stereo_eval::to_table(scores).c_str());
  if (!ivoa::write_text_file(cl.json_path, ivoa::stereo_eval::to_json(scores, cl.scoring))) return ivoa::kExitIoError;
  if (std::string error; !overlay.empty() && !ivoa::write_image_file(cl.overlay_path, overlay, error)) {
    spdlog::error("{}", error);
    return ivoa::kExitIoError;
  }
  return ivoa::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Score stereo point checks (JPP-C CP, SGBM) against ground-truth disparity on a rectified pair"};
  ivoa::CommonOptions common;
  ivoa::add_offline_options(app, common);
  CommandLine cl;
  add_options(app, cl);
  if (const int code = ivoa::parse_command_line(app, argc, argv); code >= 0) return code;
  ivoa::init_logging("stereo-eval", common.log_level);
  if (const int code = check_flags(cl); code != ivoa::kExitOk) return code;
  Pair pair;
  try {
    pair = load_pair(cl);
    fit_sgbm_range(app, pair, cl);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return ivoa::kExitBadInput;
  }
  std::vector<ivoa::stereo_eval::ModelScore> scores;
  cv::Mat overlay;
  try {
    scores = score_models(cl, pair, overlay);
  } catch (const std::invalid_argument& e) {  // matcher settings the pair cannot take
    spdlog::error("{}", e.what());
    return ivoa::kExitUsage;
  } catch (const cv::Exception& e) {  // OpenCV refusing the settings or out of memory: said, not aborted
    spdlog::error("scoring failed: {}", e.what());
    return ivoa::kExitFailure;
  }
  const bool none_scored = std::all_of(scores.begin(), scores.end(),
                                       [](const auto& s) { return s.textured.pixels + s.untextured.pixels == 0; });
  if (none_scored) {
    spdlog::error("no pixel scored: --stride {} over the {}x{} pair leaves none with known ground truth",
                  cl.scoring.stride, pair.left.cols, pair.left.rows);
    return ivoa::kExitBadInput;
  }
  return write_outputs(cl, scores, overlay);
}

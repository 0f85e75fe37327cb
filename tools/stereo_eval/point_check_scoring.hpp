#pragma once
// Scores a perception model's point checks against ground-truth disparity,
// in disparity space on a rectified pair: for each scored left pixel, a
// hypothesis "a surface at the true disparity" should be confirmed, and
// hypotheses "a surface at the true disparity +- k pixels" should not.
// Pixels are split into textured and untextured by the RMS horizontal
// gradient over the matching window, since a hypothesis on a texture-less
// surface cannot be told apart from its neighbours by any matcher.
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/stereo/config.hpp"
#include "ivoa/stereo/jpp_matcher.hpp"
#include "ivoa/stereo/sgbm.hpp"

namespace ivoa::stereo_eval {

// A perception model that answers "is there a surface at disparity d
// behind left pixel p?".
class PointCheckModel {
 public:
  virtual ~PointCheckModel() = default;
  virtual std::string name() const = 0;
  virtual void set_pair(const cv::Mat& left_gray, const cv::Mat& right_gray) = 0;
  struct Check {
    bool confirmed = false;
    double cost = 0;  // lower = more likely; NaN where the model has no cost for it
  };
  // Empty when the model cannot test the hypothesis (e.g. outside the image).
  virtual std::optional<Check> check(cv::Point left, double disparity) = 0;
};

// JPP's CP at the integer pixel nearest to the hypothesis.
class JppPointModel : public PointCheckModel {
 public:
  explicit JppPointModel(const stereo::JppConfig& config) : matcher_(config) {}
  std::string name() const override { return "jppc"; }
  void set_pair(const cv::Mat& left_gray, const cv::Mat& right_gray) override;
  // Cost: JPP's window cost.
  std::optional<Check> check(cv::Point left, double disparity) override;

 private:
  stereo::JppMatcher matcher_;
};

// SGBM confirms a hypothesis when its disparity is within `tolerance` of it.
class SgbmPointModel : public PointCheckModel {
 public:
  SgbmPointModel(const stereo::SgbmConfig& config, double tolerance) : sgbm_(config), tolerance_(tolerance) {}
  std::string name() const override { return "sgbm"; }
  void set_pair(const cv::Mat& left_gray, const cv::Mat& right_gray) override;
  // Cost: distance from SGBM's disparity (NaN where SGBM has none).
  std::optional<Check> check(cv::Point left, double disparity) override;
  const cv::Mat& disparity() const { return disparity_; }

 private:
  stereo::SgbmMatcher sgbm_;
  double tolerance_;
  cv::Mat disparity_;
};

struct Rate {
  int64_t tested = 0, confirmed = 0;
  double value() const { return tested > 0 ? static_cast<double>(confirmed) / static_cast<double>(tested) : 0.0; }
  void add(bool yes) {
    ++tested;
    confirmed += yes ? 1 : 0;
  }
};

struct TextureClassScore {
  int64_t pixels = 0;
  Rate at_truth;                  // hypotheses at the true disparity
  Rate wrong;                     // every wrong offset together
  std::map<int, Rate> by_offset;  // signed offset -> rate
  // Threshold-free: share of (pixel, wrong offset) pairs whose cost is
  // higher at the wrong disparity than at the true one.
  Rate truth_cheaper;
  double cost_sum_truth = 0, cost_sum_wrong = 0;
  int64_t cost_count_truth = 0, cost_count_wrong = 0;
  double mean_cost_truth() const { return cost_count_truth ? cost_sum_truth / cost_count_truth : 0.0; }
  double mean_cost_wrong() const { return cost_count_wrong ? cost_sum_wrong / cost_count_wrong : 0.0; }
};

struct ModelScore {
  std::string model;
  TextureClassScore textured, untextured;
};

struct ScoringOptions {
  int stride = 2;                           // score every stride-th pixel in x and y
  std::vector<int> wrong_offsets{2, 4, 8};  // +-k pixels
  double texture_threshold = 6.0;           // RMS x-gradient, gray levels / px
  int texture_window = 5;                   // half-width of the texture window, pixels
};

// RMS horizontal central-difference gradient over a (2w+1)^2 window, per pixel.
cv::Mat texture_energy(const cv::Mat& gray, int half_window);

// Scores `model` on one pair. `truth` is CV_32F disparity, NaN = unknown.
ModelScore score(PointCheckModel& model, const cv::Mat& left_gray, const cv::Mat& right_gray, const cv::Mat& truth,
                 const ScoringOptions& options, cv::Mat* outcome_overlay = nullptr);

std::string to_json(const std::vector<ModelScore>& scores, const ScoringOptions& options);
std::string to_table(const std::vector<ModelScore>& scores);

}  // namespace ivoa::stereo_eval
